//! `fusemap demo`, planned and run: the design document's production line simulated
//! (built in, no data needed), written as a rosbag2 bag into the output set, read back
//! and mapped in one pass lidar-only, camera-only and fused ([`three_maps`]); each map
//! scored against the simulator's ground truth ([`score`]) and the three drawn side by
//! side (`comparison.png`). Everything it writes — the bag, the three maps, the picture —
//! is staged in one output set and moves into the output directory together.

use crate::job::{plan_of_or, JobError};
use crate::outputs::{
    finish, layers_of, prepare, view_of, ExportOptions, ExportRoom, MapView, OutputFiles, RunRecord, Seconds, Summary,
};
use crate::scenario::{production_line_plan, score, three_maps, MapScore, Truth};
use crate::Progress;
use fusemap_core::config::Plan;
use fusemap_core::fusion::{Engine, MapEntry};
use fusemap_core::grid::{CellBox, CellIndex, Raster};
use fusemap_io::comparison::{write_comparison_png, Panel};
use fusemap_sim::{Scenario, TruthRaster};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The production-line demo, planned.
pub struct DemoJob {
    /// The mapping configuration: `configs/production_line.toml` unless the user gave one.
    pub plan: Plan,
    /// The output directory.
    pub out: PathBuf,
    /// The files the run reads (the configuration, if given).
    pub inputs: Vec<PathBuf>,
}

/// What the demo wrote and measured.
pub struct DemoRun {
    /// The fused map's summary (`summary.json`).
    pub summary: Summary,
    /// Every map's scores against the ground truth, fused first.
    pub scores: Vec<MapScore>,
    /// The other maps' names (each a directory of the output set beside `sim/`).
    pub other_maps: Vec<String>,
}

impl DemoJob {
    /// The demo into `out`, with `config` instead of the built-in production-line
    /// configuration when given.
    pub fn plan(config: Option<&Path>, out: &Path) -> Result<Self, JobError> {
        let plan = plan_of_or(config, || Ok(production_line_plan()?))?;
        let inputs = config.map(Path::to_path_buf).into_iter().collect();
        Ok(Self { plan, out: out.to_path_buf(), inputs })
    }

    /// Simulates, maps, scores and writes the set.
    pub fn run(self, progress: &mut dyn FnMut(Progress)) -> Result<DemoRun, JobError> {
        let started = Instant::now();
        let (plan, out) = (&self.plan, &self.out);
        let mut files = prepare(out, &self.inputs)?;
        files.own_dir("sim");
        let sim_dir = files.staged("sim");
        let memory = plan.limits.memory_bytes();
        // The simulator's messages go into the bag as they are made (most of them images):
        // the run reads them back from there, and the truth needs only the world and the
        // tracks. Simulating and writing overlap, so their seconds are one phase.
        let t_sim = Instant::now();
        let (rec, sim) =
            fusemap_sim::bag::simulate_to(&Scenario::default(), &sim_dir, plan.geometry.resolution(), true, memory)
                .map_err(|e| match e {
                    fusemap_sim::bag::SimulationError::Scenario(e) => JobError::Scenario(e),
                    fusemap_sim::bag::SimulationError::Write(source) => {
                        JobError::Simulation { dir: sim_dir.clone(), source }
                    }
                })?;
        let simulate_s = t_sim.elapsed().as_secs_f64();
        let inv = crate::recording::Inventory::read_with(&sim.bag.dir, &plan.limits)?;
        let (bound, chosen, track_s) = crate::run::prepare(plan, &inv)?;
        let run = crate::map_with_track(plan, &inv, &bound, chosen, track_s, three_maps(plan).into(), progress)?;
        let truth_occupancy = rec.truth_occupancy(plan.geometry)?;
        let truth_semantic = rec.truth_semantic(plan.geometry)?;
        let truth = Truth {
            occupancy: &truth_occupancy,
            semantic: &truth_semantic,
            person: &rec.person_track,
            person_radius_m: rec.person_radius_m,
        };
        let scores: Vec<MapScore> =
            run.engine.maps().iter().map(|m| score(m.name(), m.grid(), &plan.classes, &truth)).collect();

        // The fused map (the primary) with every output; the other two beside it.
        let mut log = serde_json::to_value(&run.report)?;
        log["scenario_scores"] = serde_json::to_value(&scores)?;
        let bag_in_out = out.join(sim.bag.dir.strip_prefix(files.staged("")).unwrap_or(&sim.bag.dir));
        let source = format!("built-in production line, simulated to {}", bag_in_out.display());
        let export = ExportOptions::of(plan, None);
        let mut other_maps = Vec::new();
        let mut notes = run.notes.clone();
        for m in run.engine.maps().iter().skip(1) {
            files.own_dir(m.name());
            write_map_files(&files.staged(m.name()), &run.engine, m, &export, &mut notes)?;
            other_maps.push(m.name().to_string());
        }
        write_comparison(&files.staged("comparison.png"), &run.engine, &scores, &truth_occupancy, plan)?;
        let record = RunRecord {
            source_kind: "rosbag2 (simulated production line)",
            source: &source,
            started,
            notes,
            log: Some(log),
            trajectory: Some(&run.trajectory),
            validation: None,
            calibration: None,
            endpoints: None,
            map_from_odom: run.map_from_odom.as_ref().map(|(f, m)| (f.as_str(), *m)),
            seconds: Seconds { simulate: Some(simulate_s), ..Seconds::of_log(&run.report) },
        };
        let summary = finish(&run.engine, files, &export, record)?;
        Ok(DemoRun { summary, scores, other_maps })
    }
}

/// Writes a map of the set (not the primary) as map.npz, map.pgm + map.yaml, map.png, and
/// its semantic and dynamic layers when it has them; sparsely (map.npz of its tiles and an
/// overview map.png) where the primary's limits would write it so, with a note.
fn write_map_files(
    dir: &Path,
    engine: &Engine,
    m: &MapEntry,
    export: &ExportOptions,
    notes: &mut Vec<String>,
) -> Result<(), JobError> {
    std::fs::create_dir_all(dir).map_err(|e| fusemap_io::Error::io(dir, e))?;
    let files = OutputFiles::in_dir(dir);
    let mut why = Vec::new();
    let raster = match view_of(m.grid(), export, ExportRoom::of(engine.export_room(m)), &mut why)? {
        MapView::Empty => return Ok(()),
        MapView::Sparse { tiles, overview, .. } => {
            notes.extend(why.into_iter().map(|n| format!("map `{}`: {n}", m.name())));
            fusemap_io::npz::write_sparse_map_npz(&files.npz, &tiles)?;
            fusemap_io::picture::write_map_png(&files.png, &overview)?;
            return Ok(());
        }
        MapView::Dense(r) => r,
    };
    let layers = layers_of(engine, m.grid(), &raster).filter(|l| l.semantic.best.iter().any(|&b| b >= 0));
    match &layers {
        Some(l) => {
            let with = fusemap_io::npz::NpzLayers { semantic: Some(&l.semantic), dynamic: Some(&l.dynamic) };
            fusemap_io::npz::write_map_npz_with(&files.npz, &raster, &with)?;
            fusemap_io::semantic::write_semantic(&files.semantic, &l.picture())?;
            fusemap_io::semantic::write_dynamic_png(&files.dynamic, &l.dynamic)?;
        }
        None => fusemap_io::npz::write_map_npz(&files.npz, &raster)?,
    }
    fusemap_io::map_server::write_map_server(&files.yaml, &raster)?;
    fusemap_io::picture::write_map_png(&files.png, &raster)?;
    Ok(())
}

/// Ground truth, the three maps and the fused map's classes, side by side over the hall.
fn write_comparison(
    path: &Path,
    engine: &Engine,
    scores: &[MapScore],
    truth: &TruthRaster,
    plan: &Plan,
) -> Result<(), JobError> {
    let area = CellBox {
        min: truth.first_cell,
        max: CellIndex::new(truth.first_cell.x + truth.width as i64 - 1, truth.first_cell.y + truth.height as i64 - 1),
    };
    let occupied = plan.occupancy.clamp_max;
    let truth_raster = Raster {
        width: truth.width,
        height: truth.height,
        resolution: plan.geometry.resolution(),
        origin: plan.geometry.cell_corner(truth.first_cell),
        first_cell: truth.first_cell,
        log_odds: truth
            .occupied
            .iter()
            .map(|&o| fusemap_core::grid::logodds::logit(if o { occupied } else { plan.occupancy.clamp_min }) as f32)
            .collect(),
        known: vec![true; truth.occupied.len()],
        params: plan.occupancy,
    };
    let mut panels = vec![Panel::occupancy(vec!["ground truth".into()], &truth_raster)];
    let mut fused_semantic = None;
    for (m, s) in engine.maps().iter().zip(scores) {
        let raster = m.grid().raster(area);
        let mut caption = vec![format!("{} map", s.name), format!("F1 {:.3}", s.occupied.f1)];
        if let Some(a) = s.semantic.total.accuracy() {
            caption.push(format!("classes {:.3}", a));
        }
        panels.push(Panel::occupancy(caption, &raster));
        if m.name() == "fused" {
            fused_semantic = layers_of(engine, m.grid(), &raster);
        }
    }
    if let Some(l) = fused_semantic {
        let rgb = l
            .shown
            .iter()
            .map(|&b| if b >= 0 { l.semantic.classes[b as usize].color } else { fusemap_io::semantic::UNKNOWN_COLOR })
            .collect();
        panels.push(Panel {
            caption: vec!["fused classes".into()],
            width: l.semantic.width,
            height: l.semantic.height,
            rgb,
        });
    }
    write_comparison_png(path, &panels)?;
    Ok(())
}

/// The scores as a table for a person, one map a line.
pub fn scores_table(scores: &[MapScore], plan: &Plan) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    t.push_str("scores against the simulator's ground truth (1-cell tolerance):\n");
    t.push_str(
        "  map      F1 occ  glass  backlit  pillar free  machine free  person  classes  wall  glass  pillar  \
         shown glass (precision)\n",
    );
    for s in scores {
        let acc = |n: &str| s.semantic_of(&plan.classes, n).map_or("   -".to_string(), |a| format!("{a:.2}"));
        let glass = s.class_precision.get("glass").and_then(|p| Some(format!("{} ({:.2})", p.shown, p.precision?)));
        let _ = writeln!(
            t,
            "  {:<7}  {:>6.3}  {:>5.2}  {:>7}  {:>11.3}  {:>12.3}  {:>6}  {:>7}  {:>4}  {:>5}  {:>6}  {}",
            s.name,
            s.occupied.f1,
            s.glass_occupied_share,
            s.backlit_occupied_cells,
            s.pillar_body_free_share,
            s.machine_body_free_share,
            s.person_static_cells,
            s.semantic.total.accuracy().map_or("-".to_string(), |a| format!("{a:.3}")),
            acc("wall"),
            acc("glass"),
            acc("pillar"),
            glass.unwrap_or_else(|| "-".into()),
        );
    }
    t
}
