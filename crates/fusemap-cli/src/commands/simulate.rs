//! `fusemap simulate [SCENARIO.toml] --out DIR`: the design document's production line (or
//! a scenario file's world) recorded as a rosbag2 bag, with its ground truth beside it.

use anyhow::{Context, Result};
use fusemap_sim::bag::SimulationError;
use fusemap_sim::Scenario;
use std::path::Path;

/// Runs the simulator and writes `DIR/bag`, `DIR/truth.yaml` + `.pgm`,
/// `DIR/truth_semantic.yaml` + `.png`, `DIR/truth.tum`.
pub fn run(scenario: Option<&Path>, out: &Path, resolution: f64, overwrite: bool) -> Result<()> {
    let s = match scenario {
        Some(p) => fusemap_sim::bag::load_scenario(p)?,
        None => Scenario::default(),
    };
    if let Some(p) = scenario {
        fusemap_io::atomic::ensure_not_input(&out.join("bag"), &[p.to_path_buf()])?;
    }
    // The memory budget of a run with default limits: `simulate` reads no config.
    let memory = fusemap_core::config::LimitsConfig::default().memory_bytes();
    let (rec, files) = match fusemap_sim::bag::simulate_to(&s, out, resolution, overwrite, memory) {
        Ok(written) => written,
        Err(SimulationError::Scenario(e)) => return Err(anyhow::anyhow!("scenario: {e}")),
        Err(SimulationError::Write(e)) => {
            return Err(e).with_context(|| format!("writing the simulation to {}", out.display()))
        }
    };
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
