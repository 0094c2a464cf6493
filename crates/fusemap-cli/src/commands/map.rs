//! `fusemap map`: a robot log or a world file mapped, its outputs written.

use crate::commands::world::run_simulated;
use crate::progress;
use anyhow::{bail, Result};
use fusemap_core::config::Plan;
use fusemap_pipeline::outputs::{self, finish, Crop, ExportOptions, RunRecord, Summary};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `fusemap map`: a world file (simulated) or a robot log; `crop` exports that region
/// densely.
pub fn map(
    config: Option<&Path>,
    world: Option<&Path>,
    log: Option<&Path>,
    out: &Path,
    crop: Option<Crop>,
) -> Result<()> {
    let plan = super::plan_of(config)?;
    let export = ExportOptions { crop, export_cells: plan.limits.export_cells };
    if let Some(c) = &crop {
        outputs::crop_area(&plan.geometry, c, export.export_cells)?;
    }
    let mut inputs: Vec<PathBuf> = config.map(Path::to_path_buf).into_iter().collect();
    let summary = match (world, log) {
        (Some(w), None) => {
            inputs.push(w.to_path_buf());
            let wf = fusemap_io::world_file::load_world_with(w, &plan.limits)?;
            run_simulated(&plan, &export, &wf.world, &wf.scanner, wf.poses, out, &w.display().to_string(), &inputs)?
        }
        (None, Some(l)) => {
            inputs.push(l.to_path_buf());
            run_log(&plan, &export, l, out, &inputs)?
        }
        (Some(_), Some(_)) => bail!("give either --world FILE or a LOG, not both"),
        (None, None) => {
            bail!("nothing to map: give a LOG (CARMEN, ROS 1 bag, MCAP, rosbag2 directory) or --world FILE")
        }
    };
    print!("{summary}");
    println!("outputs       {}", out.display());
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

/// Maps a robot log through the pipeline and writes the outputs.
fn run_log(plan: &Plan, export: &ExportOptions, path: &Path, out: &Path, inputs: &[PathBuf]) -> Result<Summary> {
    let started = Instant::now();
    let files = outputs::prepare(out, inputs)?;
    // fusemap-io errors already name the file (and the line or message): no context.
    // The engine's refusals (a map past limits.map_cells) and the pipeline's (a log with
    // no scans, a lidar topic the log lacks) do not know the file: named here.
    let run = fusemap_pipeline::map_log(plan, path, &mut progress::reporter()).map_err(|e| match e {
        fusemap_pipeline::PipelineError::Engine(e) => anyhow::anyhow!("{}: {e}", path.display()),
        fusemap_pipeline::PipelineError::Refused(e) => anyhow::anyhow!("{}: {e}", path.display()),
        other => other.into(),
    })?;
    let value = serde_json::to_value(&run.report)?;
    let record = RunRecord {
        source_kind: &run.format.to_string(),
        source: &path.display().to_string(),
        started,
        notes: run.notes,
        log: Some(value),
        trajectory: Some(&run.trajectory),
    };
    Ok(finish(&run.engine, files, export, record)?)
}
