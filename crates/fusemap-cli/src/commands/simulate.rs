//! `fusemap simulate [SCENARIO.toml] --out DIR`: the design document's production line (or
//! a scenario file's world) recorded as a rosbag2 bag, with its ground truth beside it.

use anyhow::Result;
use fusemap_pipeline::simulate::SimulateJob;
use std::path::Path;

/// Runs the simulator and writes `DIR/bag`, `DIR/truth.yaml` + `.pgm`,
/// `DIR/truth_semantic.yaml` + `.png`, `DIR/truth.tum`.
pub fn run(scenario: Option<&Path>, out: &Path, resolution: f64, overwrite: bool) -> Result<()> {
    let (rec, files) = SimulateJob::plan(scenario, out, resolution, overwrite)?.run()?;
    println!("bag           {} ({} messages)", super::shown(&files.bag.dir), files.bag.message_count);
    for t in &files.bag.topics {
        println!("  {:<12}  {:<28} {}", t.name, t.type_name, t.message_count);
    }
    println!("true map      {}", super::shown(&files.truth_map));
    println!("true classes  {}", super::shown(&files.truth_semantic));
    println!("true track    {}", super::shown(&files.truth_trajectory));
    println!(
        "injected      gyro bias {:.4} rad/s, odometry scale {:.3}, {} GNSS outliers, {} GNSS dropouts",
        rec.gyro_bias_radps,
        rec.odometry_scale,
        rec.injected_outliers.len(),
        rec.dropouts.len()
    );
    let c = &rec.camera_truth;
    if !c.stamps.is_empty() {
        println!(
            "camera        {} frames, {} facing the windows ({} backlit floor pixels), {} person pixels, {} lidar returns off the person",
            c.stamps.len(),
            c.backlit_frames,
            c.backlit_pixels,
            c.person_pixels,
            rec.lidar_stats.person_hits
        );
    }
    Ok(())
}
