//! `fusemap map`: a robot log or a world file mapped, its outputs written. The job is
//! planned and run by the library ([`fusemap_pipeline::job`]); this prints its summary.

use crate::progress;
use anyhow::Result;
use fusemap_pipeline::job::MapJob;
use fusemap_pipeline::outputs::Crop;
use std::path::Path;

/// `fusemap map`: a world file (simulated) or a robot log; `crop` exports that region
/// densely.
pub fn map(
    config: Option<&Path>,
    world: Option<&Path>,
    log: Option<&Path>,
    out: &Path,
    crop: Option<Crop>,
) -> Result<()> {
    let job = MapJob::plan(config, world, log, out, crop)?;
    let summary = job.run(&mut progress::reporter())?;
    print!("{summary}");
    println!("outputs       {}", super::shown(out));
    super::fail_without_map(&summary, out)
}
