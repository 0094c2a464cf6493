//! A simulated world mapped and written (`fusemap map --world`, `fusemap demo --corridor`):
//! the mapping is the pipeline's ([`fusemap_pipeline::world::map_world`]); this writes its
//! outputs.

use crate::progress;
use anyhow::Result;
use fusemap_core::config::Plan;
use fusemap_core::geometry::Pose2;
use fusemap_core::sim::{ScannerSpec, World};
use fusemap_pipeline::outputs::{self, finish, ExportOptions, RunRecord, Summary};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Maps a simulated run of `world` with `scanner` along `poses` into `out`; `source`
/// names the world in the summary and in errors.
#[allow(clippy::too_many_arguments)]
pub fn run_simulated(
    plan: &Plan,
    export: &ExportOptions,
    world: &World,
    scanner: &ScannerSpec,
    poses: Vec<Pose2>,
    out: &Path,
    source: &str,
    inputs: &[PathBuf],
) -> Result<Summary> {
    let started = Instant::now();
    let files = outputs::prepare(out, inputs)?;
    let run = fusemap_pipeline::world::map_world(plan, world, scanner, &poses, &mut progress::reporter())
        .map_err(|e| anyhow::anyhow!("{source}: {e}"))?;
    let record = RunRecord { source_kind: "world", source, started, notes: run.notes, log: None, trajectory: None };
    Ok(finish(&run.engine, files, export, record)?)
}
