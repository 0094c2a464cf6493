//! `fusemap demo` and `fusemap map`: build a map and write its outputs.

use crate::output;
use crate::summary::{CellsUpdated, MapInfo, Summary};
use anyhow::{bail, Result};
use fusemap_core::config::{Config, Plan};
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::OccupancyGrid;
use fusemap_core::metrics::map_entropy;
use fusemap_core::sensor::ReturnCounts;
use fusemap_core::sim::{ScannerSpec, SimulatedRun, World};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A progress bar on stderr; indicatif draws nothing when stderr is not a terminal.
pub fn progress(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {per_sec} eta {eta}") {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(what.to_string());
    pb
}

/// An engine with the plan's grid and lidars.
pub fn engine_for(plan: &Plan) -> Engine {
    let mut engine = Engine::new(OccupancyGrid::new(plan.geometry, plan.occupancy));
    for l in &plan.lidars {
        engine.add_lidar(l.name.clone(), l.model);
    }
    engine
}

/// Builds the summary of a finished engine and writes every output.
pub fn finish(
    engine: &Engine,
    files: &output::OutputFiles,
    source_kind: &str,
    source: &str,
    started: Instant,
    notes: Vec<String>,
    log: Option<serde_json::Value>,
) -> Result<Summary> {
    let grid = engine.grid();
    let raster = grid.known_raster();
    let st = engine.stats();
    let mut returns = ReturnCounts::default();
    let mut scans = 0;
    for s in engine.sensor_stats() {
        returns.add(&s.returns);
        scans += s.scans;
    }
    let mut summary = Summary {
        fusemap_version: env!("CARGO_PKG_VERSION"),
        source_kind: source_kind.to_string(),
        source: source.to_string(),
        scans,
        beams: returns.total(),
        returns,
        rays_walked: st.insert.rays,
        rays_rejected: st.insert.rays_rejected,
        cell_visits: st.insert.cell_visits,
        cells_updated: CellsUpdated::from(&st.insert),
        map: MapInfo::new(raster.as_ref(), grid.geometry().resolution(), grid.tile_count()),
        entropy: raster.as_ref().map(map_entropy),
        wall_time_s: 0.0,
        notes,
        log,
    };
    if raster.is_none() {
        summary.notes.push("no cell was observed: only summary.json was written".into());
    }
    summary.wall_time_s = started.elapsed().as_secs_f64();
    output::write(files, raster.as_ref(), &summary)?;
    summary.wall_time_s = started.elapsed().as_secs_f64();
    Ok(summary)
}

/// Maps a simulated run of `world` with `scanner` along `poses`.
pub fn run_simulated(
    plan: &Plan,
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
    let pb = progress(poses.len() as u64, "mapping");
    for (i, pose) in poses.iter().enumerate() {
        for (k, id) in ids.iter().enumerate() {
            let mount = plan.lidars[k].model.mount();
            let stamp = fusemap_core::time::Stamp::from_secs_f64(i as f64 / scanner.rate_hz).unwrap_or_default();
            let scan = fusemap_core::sim::simulate_scan(world, scanner, mount, *pose, stamp);
            engine.insert_scan(*id, &scan, *pose)?;
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    finish(&engine, &files, "world", source, started, Vec::new(), None)
}

/// `fusemap demo --out DIR`: the design document's corridor with the default config.
pub fn demo(out: &Path, config: Option<&Path>) -> Result<()> {
    let cfg = match config {
        Some(p) => fusemap_io::config_file::load_config(p)?,
        None => Config::default(),
    };
    let plan = cfg.validate().map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let run = SimulatedRun::document_corridor();
    let inputs: Vec<PathBuf> = config.map(Path::to_path_buf).into_iter().collect();
    let summary = run_simulated(
        &plan,
        &fusemap_core::sim::corridor(),
        &ScannerSpec::document(),
        run.poses,
        out,
        "built-in corridor (design document §3.3)",
        &inputs,
    )?;
    summary.print();
    println!("outputs       {}", out.display());
    Ok(())
}

/// `fusemap map`: a world file (simulated) or a robot log.
pub fn map(config: Option<&Path>, world: Option<&Path>, log: Option<&Path>, out: &Path) -> Result<()> {
    let cfg = match config {
        Some(p) => fusemap_io::config_file::load_config(p)?,
        None => Config::default(),
    };
    let plan = cfg.validate().map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let mut inputs: Vec<PathBuf> = config.map(Path::to_path_buf).into_iter().collect();
    let summary = match (world, log) {
        (Some(w), None) => {
            inputs.push(w.to_path_buf());
            let wf = fusemap_io::world_file::load_world(w)?;
            run_simulated(&plan, &wf.world, &wf.scanner, wf.poses, out, &w.display().to_string(), &inputs)?
        }
        (None, Some(l)) => {
            inputs.push(l.to_path_buf());
            crate::commands::log_map::run(&plan, config.is_some(), l, out, &inputs)?
        }
        (Some(_), Some(_)) => bail!("give either --world FILE or a LOG, not both"),
        (None, None) => {
            bail!("nothing to map: give a LOG (CARMEN, ROS 1 bag, MCAP, rosbag2 directory) or --world FILE")
        }
    };
    summary.print();
    println!("outputs       {}", out.display());
    Ok(())
}
