//! `fusemap doctor LOG`: the log doctor's report (see `fusemap_pipeline::doctor`).

use anyhow::Result;
use std::path::Path;

/// `fusemap doctor`: the report on stdout; a log `fusemap map` would refuse exits
/// non-zero with the reason.
pub fn run(config: Option<&Path>, path: &Path) -> Result<()> {
    let report = fusemap_pipeline::doctor::DoctorJob::plan(config, path)?.run()?;
    print!("{}", report.text);
    match report.refusal {
        // The report is printed whole; the exit status says what a script needs to know.
        Some(why) => anyhow::bail!("{} cannot be mapped: {why}", path.display()),
        None => Ok(()),
    }
}
