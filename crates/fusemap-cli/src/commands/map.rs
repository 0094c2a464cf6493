//! `fusemap map`: a robot log or a world file mapped, its outputs written. The job is
//! planned and run by the library ([`fusemap_pipeline::job`]); this prints its summary.

use crate::progress;
use anyhow::{bail, Result};
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
    // A run that observed no cell wrote only its summary: that is a failure a script must
    // see, with the reason.
    if summary.entropy.is_none() {
        bail!(
            "no map was written: no cell was observed in {} scans ({} valid returns); {} says what was skipped and why",
            summary.scans,
            summary.returns.valid,
            out.join("summary.json").display()
        );
    }
    Ok(())
}
