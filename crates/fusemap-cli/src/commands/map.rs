//! `fusemap demo` and `fusemap map`: build a map and write its outputs.

use crate::export::{Crop, ExportOptions};
use crate::output::{self, finish};
use crate::progress;
use crate::summary::Summary;
use anyhow::{bail, Result};
use fusemap_core::config::Plan;
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::FusionGrid;
use fusemap_core::sim::{ScannerSpec, World};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// An engine with the plan's grid and lidars.
pub fn engine_for(plan: &Plan) -> Engine {
    let mut engine = Engine::new(FusionGrid::new(plan.geometry, plan.occupancy));
    engine.set_map_cells_limit(&plan.limits);
    for l in &plan.lidars {
        engine.add_lidar(l.name.clone(), l.model);
    }
    engine
}

/// Maps a simulated run of `world` with `scanner` along `poses`.
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
    let files = output::prepare(out, inputs)?;
    let mut engine = engine_for(plan);
    let ids: Vec<_> = (0..plan.lidars.len() as u16).map(fusemap_core::measurement::SensorId).collect();
    // Scan i is taken at i / rate: a pose implying an impossible motion from its neighbours
    // is a glitch (as on a log's pose streams), left out and counted.
    let stamp = |i: usize| fusemap_core::time::Stamp::from_secs_f64(i as f64 / scanner.rate_hz).unwrap_or_default();
    let timed: Vec<_> = poses.iter().enumerate().map(|(i, p)| (stamp(i), *p)).collect();
    let keep = fusemap_core::time::plausible_samples(&timed, &plan.log.motion_limits());
    let glitches = keep.iter().filter(|k| !**k).count() as u64;
    let pb = progress::bar(poses.len() as u64, "mapping");
    for (i, pose) in poses.iter().enumerate() {
        if !keep[i] {
            pb.inc(1);
            continue;
        }
        for (k, id) in ids.iter().enumerate() {
            let mount = plan.lidars[k].model.mount();
            let scan = fusemap_core::sim::simulate_scan(world, scanner, mount, *pose, stamp(i));
            // The engine's refusals (a map past limits.map_cells) name the world file.
            engine.insert_scan(*id, &scan, *pose).map_err(|e| anyhow::anyhow!("{source}: scan {i}: {e}"))?;
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    let notes = if glitches > 0 {
        vec![fusemap_pipeline::track::glitch_note("the world file's trajectory", glitches, &plan.log)]
    } else {
        Vec::new()
    };
    finish(&engine, files, export, "world", source, started, notes, None, None)
}

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
        crate::export::crop_area(&plan.geometry, c, export.export_cells)?;
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
    summary.print();
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
    let files = output::prepare(out, inputs)?;
    // fusemap-io errors already name the file (and the line or message): no context.
    // The engine's refusals (a map past limits.map_cells) and the pipeline's (a log with
    // no scans, a lidar topic the log lacks) do not know the file: named here.
    let run = fusemap_pipeline::map_log(plan, path, &mut progress::reporter()).map_err(|e| match e {
        fusemap_pipeline::PipelineError::Engine(e) => anyhow::anyhow!("{}: {e}", path.display()),
        fusemap_pipeline::PipelineError::Refused(e) => anyhow::anyhow!("{}: {e}", path.display()),
        other => other.into(),
    })?;
    let value = serde_json::to_value(&run.report)?;
    finish(
        &run.engine,
        files,
        export,
        &run.format.to_string(),
        &path.display().to_string(),
        started,
        run.notes,
        Some(value),
        Some(&run.trajectory),
    )
}
