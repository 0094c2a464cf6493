//! `fusemap demo --out DIR`: the design document's scenario end to end. The production
//! line is simulated (built in, no data needed), written as a rosbag2 bag, and mapped in
//! one pass lidar-only, camera-only and fused; each map is scored against the
//! simulator's ground truth and the three are drawn side by side. `--corridor` maps the
//! document's §3.3 corridor instead.

use crate::progress;
use anyhow::Result;
use fusemap_core::sim::{ScannerSpec, SimulatedRun};
use fusemap_pipeline::demo::{scores_table, DemoJob};
use fusemap_pipeline::job::MapJob;
use std::path::Path;

/// `fusemap demo --corridor`: the design document's corridor with the default config.
pub fn corridor(out: &Path, config: Option<&Path>) -> Result<()> {
    let run = SimulatedRun::document_corridor();
    let name = "built-in corridor (design document §3.3)";
    let job = MapJob::world(config, fusemap_core::sim::corridor(), ScannerSpec::document(), run.poses, name, out)?;
    let summary = job.run(&mut progress::reporter())?;
    print!("{summary}");
    println!("outputs       {}", super::shown(out));
    super::fail_without_map(&summary, out)
}

/// `fusemap demo`: the production line, lidar-only, camera-only and fused.
pub fn production(out: &Path, config: Option<&Path>) -> Result<()> {
    let job = DemoJob::plan(config, out)?;
    let plan = job.plan.clone();
    let run = job.run(&mut progress::reporter())?;
    print!("{}", run.summary);
    print!("{}", scores_table(&run.scores, &plan));
    println!("comparison    {}", super::shown(&out.join("comparison.png")));
    let others: Vec<String> =
        run.other_maps.iter().map(String::as_str).chain(["sim"]).map(|name| super::shown(&out.join(name))).collect();
    println!("outputs       {} (fused), {}", super::shown(out), others.join(", "));
    Ok(())
}
