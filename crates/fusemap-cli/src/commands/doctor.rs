//! `fusemap doctor LOG`: the log doctor's report (see `fusemap_pipeline::doctor`).

use anyhow::Result;
use fusemap_core::config::Config;
use std::path::Path;

/// `fusemap doctor`.
pub fn run(config: Option<&Path>, path: &Path) -> Result<()> {
    let cfg = match config {
        Some(p) => fusemap_io::config_file::load_config(p)?,
        None => Config::default(),
    };
    let plan = cfg.validate().map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    print!("{}", fusemap_pipeline::doctor::report(&plan, path)?);
    Ok(())
}
