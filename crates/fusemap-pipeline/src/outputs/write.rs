//! Writing a run's outputs: `map.npz`, `map.pgm` + `map.yaml`, `map.png`, the camera
//! layers, `slam.png`, `trajectory.tum` and `summary.json`, as one set ([`Outputs`]):
//! `summary.json` goes last with each file's size and SHA-256. A failing run leaves the
//! previous set as it was; no output is ever written over an input.

use super::map_formats::{write_map_formats, FormatRequest};
use super::report_page::{self, Picture};
use super::set::{OutputFiles, Outputs};
use super::summary::{CellsUpdated, MapInfo, Seconds, Summary};
use super::view::{view_of, ExportOptions, ExportRoom, MapView};
use super::OutputError;
use fusemap_core::config::{OutputConfig, PointsMode};
use fusemap_core::fusion::rasters::{dynamic_cells, semantic_cells, shown_classes};
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::grid::{CellBox, CellIndex, CellRaster, DynamicParams, FusionGrid, Raster};
use fusemap_core::measurement::{SensorId, SensorKind};
use fusemap_core::metrics::{map_entropy, sparse_entropy, EntropyReport};
use fusemap_core::sensor::ReturnCounts;
use fusemap_core::time::Stamp;
use fusemap_io::npz::NpzLayers;
use fusemap_io::semantic::{ClassInfo, SemanticRaster};
use std::time::Instant;

/// What a run mapped and what it has to say, for the summary beside the map.
pub struct RunRecord<'a> {
    /// What was mapped: `world` (simulated) or the log's format.
    pub source_kind: &'a str,
    /// The input, as the summary names it.
    pub source: &'a str,
    /// When the run began (the summary's wall time counts from here).
    pub started: Instant,
    /// Facts about the input a user should know.
    pub notes: Vec<String>,
    /// The log run's report (absent for a simulated world).
    pub log: Option<serde_json::Value>,
    /// The base's trajectory, written as `trajectory.tum` when there is one.
    pub trajectory: Option<&'a [(Stamp, Pose2)]>,
    /// `fusemap validate`'s findings (§5), for `summary.json`'s `validation`.
    pub validation: Option<serde_json::Value>,
    /// `fusemap calibrate`'s estimates, for `summary.json`'s `calibration`.
    pub calibration: Option<serde_json::Value>,
    /// The lidar returns as placed, for point clouds of `[output] points = "endpoints"`.
    pub endpoints: Option<&'a [[f32; 2]]>,
    /// `map → odom` and the odometry frame's name, where known (`MapRun::map_from_odom`).
    pub map_from_odom: Option<(&'a str, Pose2)>,
    /// The phases the job timed before the outputs (`finish` adds the outputs' share).
    pub seconds: Seconds,
}

/// The semantic and dynamic layers of a run with a camera, over the occupancy raster's
/// cells.
pub struct Layers {
    /// The semantic layer.
    pub semantic: SemanticRaster,
    /// Its most likely class per cell as the picture shows it (-1: hidden).
    pub shown: Vec<i16>,
    /// The dynamic layer's probability at the run's last stamp.
    pub dynamic: CellRaster<f32>,
}

/// The engine's first camera model, if it has one.
fn camera_of(engine: &Engine) -> Option<&fusemap_core::sensor::camera::CameraModel> {
    (0..u16::MAX)
        .map(SensorId)
        .take_while(|&id| engine.sensor_kind(id).is_some())
        .find_map(|id| engine.camera_model(id))
}

/// The layers of `grid` over `raster`'s cells when the engine has a camera (its class
/// table names the classes), `None` otherwise.
pub fn layers_of(engine: &Engine, grid: &FusionGrid, raster: &Raster) -> Option<Layers> {
    let camera = camera_of(engine)?;
    let classes = camera.classes();
    let area = CellBox {
        min: raster.first_cell,
        max: CellIndex::new(
            raster.first_cell.x + raster.width as i64 - 1,
            raster.first_cell.y + raster.height as i64 - 1,
        ),
    };
    let cells = semantic_cells(grid, area, classes);
    let shown = shown_classes(grid, &cells, classes);
    let semantic = SemanticRaster {
        width: cells.best.width,
        height: cells.best.height,
        resolution: cells.best.resolution,
        origin: [cells.best.origin.x, cells.best.origin.y],
        classes: classes.iter().map(|c| ClassInfo { id: c.id, name: c.name.clone(), color: c.color }).collect(),
        best: cells.best.cells,
        prob: cells.prob,
        probs: cells.probs,
    };
    let half_life = engine.dynamic_params().map_or(DynamicParams::default().half_life_s, |p| p.half_life_s);
    let dynamic = dynamic_cells(grid, area, engine.last_stamp().unwrap_or_default(), half_life);
    Some(Layers { semantic, shown, dynamic })
}

impl Layers {
    /// The semantic layer as `semantic.png` shows it: each cell's class only where
    /// [`shown_classes`] shows it (`map.npz` keeps the whole layer).
    pub fn picture(&self) -> SemanticRaster {
        let s = &self.semantic;
        SemanticRaster {
            width: s.width,
            height: s.height,
            resolution: s.resolution,
            origin: s.origin,
            classes: s.classes.clone(),
            best: self.shown.clone(),
            prob: s.prob.clone(),
            probs: Vec::new(),
        }
    }
}

/// The run's clock: when it began, when its outputs began, and the phases before them.
struct RunClock {
    started: Instant,
    outputs_from: Instant,
    phases: Seconds,
}

impl RunClock {
    /// Sets the summary's wall time and its phases to now (the report page shows them as
    /// of its writing; `summary.json` as of its own, the last file of the set).
    fn stop(&self, summary: &mut Summary) {
        let now = Instant::now();
        summary.wall_time_s = (now - self.started).as_secs_f64();
        let outputs = (now - self.outputs_from).as_secs_f64();
        summary.seconds = self.phases.clone().closed(outputs, summary.wall_time_s);
    }
}

/// Writes the map files of `view` and the trajectory (when there is one) into the set,
/// then commits it with the summary, which lists them.
fn write(
    outputs: Outputs,
    view: &MapView,
    layers: Option<&Layers>,
    summary: &mut Summary,
    trajectory: Option<&[(Stamp, Pose2)]>,
    request: FormatRequest<'_>,
    clock: &RunClock,
) -> Result<(), OutputError> {
    let Outputs { files, set, owned } = outputs;
    if let Some(t) = trajectory {
        fusemap_io::trajectory::write_tum(&files.trajectory, t)?;
    }
    let graph = summary.log.as_ref().and_then(pose_graph_of);
    if let MapView::Sparse { tiles, overview, .. } = view {
        fusemap_io::npz::write_sparse_map_npz(&files.npz, tiles)?;
        fusemap_io::picture::write_map_png(&files.png, overview)?;
    }
    if let MapView::Dense(r) = view {
        // semantic.png's classes, built once for it and map.mcap's /map/semantic.
        let picture = layers.map(Layers::picture);
        match (layers, &picture) {
            (Some(l), Some(picture)) => {
                let with = NpzLayers { semantic: Some(&l.semantic), dynamic: Some(&l.dynamic) };
                fusemap_io::npz::write_map_npz_with(&files.npz, r, &with)?;
                fusemap_io::semantic::write_semantic(&files.semantic, picture)?;
                fusemap_io::semantic::write_dynamic_png(&files.dynamic, &l.dynamic)?;
            }
            _ => fusemap_io::npz::write_map_npz(&files.npz, r)?,
        }
        fusemap_io::map_server::write_map_server(&files.yaml, r)?;
        fusemap_io::picture::write_map_png(&files.png, r)?;
        if let Some((trajectory, closures, fixes)) = &graph {
            fusemap_io::slam_picture::write_pose_graph_png(&files.slam, r, trajectory, closures, fixes)?;
        }
        let closures = graph.as_ref().map_or(&[][..], |g| &g.1[..]);
        let layers = layers.zip(picture.as_ref()).map(|(l, p)| (p, &l.dynamic));
        write_map_formats(&files, request, r, layers, trajectory.unwrap_or_default(), closures)?;
    }
    clock.stop(summary);
    let value =
        serde_json::to_value(&*summary).map_err(|e| fusemap_io::Error::io(&files.summary, std::io::Error::other(e)))?;
    let width_m = summary.map.width as f64 * summary.map.resolution;
    let crop = match view {
        MapView::Dense(r) => observed_crop(r),
        _ => [0.0, 1.0, 0.0, 1.0],
    };
    report_page::write_report(&set.staged(REPORT_HTML), &value, &pictures(&files, layers, width_m, crop))?;
    // Files of an earlier run that this run does not write are removed at the commit: a
    // run never leaves files beside its summary that look like its own.
    let summary_path = set.dir().join("summary.json");
    let known: Vec<&str> = OutputFiles::NAMES.iter().copied().chain(owned.iter().map(String::as_str)).collect();
    set.commit(&known, "summary.json", |list| {
        summary.files = list.to_vec();
        clock.stop(summary);
        serde_json::to_vec_pretty(&*summary).map_err(|e| fusemap_io::Error::io(&summary_path, std::io::Error::other(e)))
    })?;
    Ok(())
}

/// The share of observed cells left outside the report's pictures on each side: the
/// stray rays of a few beams through a door or a window, which would otherwise set the
/// picture's extent.
const CROP_TAIL: f64 = 0.002;
/// The margin around the observed area, as a share of its size.
const CROP_MARGIN: f64 = 0.03;

/// The part of `r`'s pictures the report shows, `[left, right, top, bottom]` as shares of
/// the picture (top = the highest row): the columns and rows holding all but
/// [`CROP_TAIL`] of the observed cells on each side, with a margin.
fn observed_crop(r: &Raster) -> [f64; 4] {
    let (mut cols, mut rows) = (vec![0u64; r.width], vec![0u64; r.height]);
    for (i, _) in r.known.iter().enumerate().filter(|(_, k)| **k) {
        cols[i % r.width] += 1;
        rows[i / r.width] += 1;
    }
    let span = |counts: &[u64]| {
        let total: u64 = counts.iter().sum();
        let tail = (CROP_TAIL * total as f64) as u64;
        let mut acc = 0u64;
        let first = counts.iter().position(|&c| {
            acc += c;
            acc > tail
        });
        acc = 0;
        let last = counts.iter().rposition(|&c| {
            acc += c;
            acc > tail
        });
        let (a, b) = (first.unwrap_or(0) as f64, last.map_or(counts.len(), |l| l + 1) as f64);
        let pad = CROP_MARGIN * (b - a);
        let n = counts.len().max(1) as f64;
        (((a - pad) / n).max(0.0), ((b + pad) / n).min(1.0))
    };
    let (left, right) = span(&cols);
    let (low, high) = span(&rows);
    // Row 0 is the lowest y, drawn at the bottom.
    [left, right, 1.0 - high, 1.0 - low]
}

/// The page beside every run's outputs.
pub const REPORT_HTML: &str = "report.html";

/// The run's pictures that were written, each with its legend, for the report.
fn pictures(files: &OutputFiles, layers: Option<&Layers>, width_m: f64, crop: [f64; 4]) -> Vec<Picture> {
    let grey = |v: u8| format!("rgb({v},{v},{v})");
    let shades = || {
        vec![
            (grey(255), "free".to_string()),
            (grey(0), "occupied".to_string()),
            (grey(fusemap_io::picture::UNKNOWN_SHADE), "never observed".to_string()),
        ]
    };
    let rgb = |c: [u8; 3]| format!("rgb({},{},{})", c[0], c[1], c[2]);
    let mut slam = shades();
    slam.extend([
        (rgb(fusemap_io::slam_picture::TRAJECTORY), "trajectory".to_string()),
        (rgb(fusemap_io::slam_picture::LOOP_CLOSURE), "loop closure (blended 35 %)".to_string()),
        (rgb(fusemap_io::slam_picture::FIX), "GNSS fix prior".to_string()),
    ]);
    let classes =
        layers.map_or(Vec::new(), |l| l.semantic.classes.iter().map(|c| (rgb(c.color), c.name.clone())).collect());
    let dynamic = vec![
        (grey(0), "a moving object".to_string()),
        (grey(255), "none".to_string()),
        (grey(fusemap_io::map_server::PIXEL_UNKNOWN), "never observed".to_string()),
    ];
    [
        ("Occupancy (map.png)", &files.png, shades()),
        ("SLAM: trajectory, loop closures, fixes (slam.png)", &files.slam, slam),
        ("Semantic classes where the map is occupied (semantic.png)", &files.semantic_png, classes),
        ("Dynamic layer (dynamic.png)", &files.dynamic, dynamic),
    ]
    .into_iter()
    .filter(|(_, path, _)| path.is_file())
    .map(|(title, path, legend)| Picture { title: title.to_string(), path: path.clone(), legend, width_m, crop })
    .collect()
}

/// The trajectory of scan nodes, the loop closures (submap origin, node) and the GNSS fixes
/// taken as priors.
type GraphPicture = (Vec<Point2>, Vec<(Point2, Point2)>, Vec<Point2>);

/// The scan nodes, the loop closures (submap origin, node) and the fix priors of the pose
/// graph in a run report's `slam` section.
fn pose_graph_of(log: &serde_json::Value) -> Option<GraphPicture> {
    let slam = log.get("slam")?;
    let nodes: Vec<(bool, Point2)> = slam
        .get("nodes")?
        .as_array()?
        .iter()
        .map(|n| {
            let p = n.get("pose").and_then(|p| p.as_array());
            let c = |i: usize| p.and_then(|p| p.get(i)).and_then(|v| v.as_f64()).unwrap_or(f64::NAN);
            (n.get("kind").and_then(|k| k.as_str()) == Some("scan"), Point2::new(c(0), c(1)))
        })
        .collect();
    let trajectory = nodes.iter().filter(|n| n.0).map(|n| n.1).collect();
    let closures = slam
        .get("edges")?
        .as_array()?
        .iter()
        .filter(|e| e.get("kind").and_then(|k| k.as_str()) == Some("loop_closure"))
        .filter_map(|e| {
            let i = |k: &str| e.get(k).and_then(|v| v.as_u64()).and_then(|v| nodes.get(v as usize)).map(|n| n.1);
            Some((i("from")?, i("to")?))
        })
        .collect();
    let fixes = slam
        .get("priors")
        .and_then(|p| p.as_array())
        .into_iter()
        .flatten()
        .filter_map(|p| {
            let xy = p.get("position")?.as_array()?;
            Some(Point2::new(xy.first()?.as_f64()?, xy.get(1)?.as_f64()?))
        })
        .collect();
    Some((trajectory, closures, fixes))
}

/// The notes a view of the map adds: what was not written, and why.
fn view_notes(view: &MapView, camera: bool, formats: OutputConfig, endpoints: bool, notes: &mut Vec<String>) {
    let any_format = formats.mcap || formats.pcd || formats.ply;
    match view {
        MapView::Empty => notes.push("no cell was observed: only summary.json was written".into()),
        MapView::Sparse { .. } => {
            if camera {
                notes.push("the semantic and dynamic layers are written only with a dense map (--crop)".into());
            }
            if any_format {
                notes.push(
                    "map.mcap, map.pcd and map.ply are written only with a dense map (--crop a region within \
                     limits.export_cells)"
                        .into(),
                );
            }
        }
        MapView::Dense(_) => {
            if any_format && formats.points == PointsMode::Endpoints && !endpoints {
                notes.push(
                    "[output] points = \"endpoints\" applies to `fusemap map` on a log; the point clouds hold the \
                     occupied cells"
                        .into(),
                );
            }
        }
    }
}

/// The summary's `map` and `entropy` of `view`.
fn map_info(view: &MapView, grid: &FusionGrid) -> (MapInfo, Option<EntropyReport>) {
    match view {
        MapView::Empty => (MapInfo::new(None, grid.geometry().resolution(), grid.tile_count()), None),
        MapView::Dense(r) => {
            (MapInfo::new(Some(r), grid.geometry().resolution(), grid.tile_count()), Some(map_entropy(r)))
        }
        MapView::Sparse { tiles, area, .. } => {
            // Saturating: two sites 1e9 m apart make a box of more than 2^64 cells.
            let cells = (area.width() as u64).saturating_mul(area.height() as u64);
            let info = MapInfo {
                resolution: grid.geometry().resolution(),
                origin: [grid.geometry().cell_corner(area.min).x, grid.geometry().cell_corner(area.min).y],
                width: area.width(),
                height: area.height(),
                tiles: grid.tile_count(),
            };
            (info, Some(sparse_entropy(tiles, cells, grid.table().prior)))
        }
    }
}

/// Builds the summary of a finished engine and writes every output: the view of the map
/// `export` asks for (see [`view_of`]).
pub fn finish(
    engine: &Engine,
    outputs: Outputs,
    export: &ExportOptions,
    record: RunRecord<'_>,
) -> Result<Summary, OutputError> {
    let RunRecord {
        source_kind,
        source,
        started,
        mut notes,
        log,
        trajectory,
        validation,
        calibration,
        endpoints,
        map_from_odom,
        seconds,
    } = record;
    let clock = RunClock { started, outputs_from: Instant::now(), phases: seconds };
    let grid = engine.grid();
    // The returns of an endpoint cloud are held beside the maps while they are written.
    let kept = endpoints.map_or(0, |e| super::map_formats::endpoint_bytes(e.len(), e.len()));
    let room = ExportRoom::of(engine.export_room(engine.maps().primary())).map(|r| r.without(kept));
    let view = view_of(grid, export, room, &mut notes)?;
    let raster = match &view {
        MapView::Dense(r) => Some(r),
        _ => None,
    };
    let layers = raster.and_then(|r| layers_of(engine, grid, r));
    let st = engine.maps().primary().stats();
    let mut returns = ReturnCounts::default();
    let (mut scans, mut camera_frames) = (0, 0);
    for s in engine.sensor_stats() {
        returns.add(&s.returns);
        match s.kind {
            SensorKind::Lidar => scans += s.scans,
            SensorKind::Camera => camera_frames += s.scans,
        }
    }
    let (map, entropy) = map_info(&view, grid);
    let mut summary = Summary {
        fusemap_version: env!("CARGO_PKG_VERSION"),
        source_kind: source_kind.to_string(),
        source: source.to_string(),
        scans,
        camera_frames,
        beams: returns.total(),
        returns,
        rays_walked: st.rays,
        rays_rejected: st.rays_rejected,
        cell_visits: st.cell_visits,
        cell_visits_attenuated: st.cell_visits_attenuated,
        cells_updated: CellsUpdated::from(st),
        map,
        entropy,
        wall_time_s: 0.0,
        seconds: Seconds::default(),
        notes,
        log,
        validation,
        calibration,
        files: Vec::new(),
    };
    view_notes(&view, camera_of(engine).is_some(), export.formats, endpoints.is_some(), &mut summary.notes);
    clock.stop(&mut summary);
    let request = FormatRequest { formats: export.formats, endpoints, map_from_odom };
    write(outputs, &view, layers.as_ref(), &mut summary, trajectory, request, &clock)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outputs::prepare;
    use fusemap_core::config::Config;
    use fusemap_core::sim::{corridor, ScannerSpec};

    /// The document's corridor mapped from a world, from its first `n` poses.
    fn corridor_run(n: u32) -> crate::world::WorldRun {
        let plan = Config::default().validate().unwrap();
        let poses: Vec<Pose2> = (0..n).map(|i| Pose2::new(0.1 * f64::from(i), 0.0, 0.0)).collect();
        crate::world::map_world(&plan, &corridor(), &ScannerSpec::document(), &poses, &mut |_| {}).unwrap()
    }

    fn world_record(notes: Vec<String>) -> RunRecord<'static> {
        RunRecord {
            source_kind: "world",
            source: "corridor",
            started: Instant::now(),
            notes,
            log: None,
            trajectory: None,
            validation: None,
            calibration: None,
            endpoints: None,
            map_from_odom: None,
            seconds: Seconds::default(),
        }
    }

    /// The library alone, without the CLI: the document's corridor mapped and written, and
    /// the summary lists exactly the files on disk, each with its size.
    #[test]
    fn a_finished_world_run_is_written_as_one_listed_set() {
        let run = corridor_run(40);
        let dir = fusemap_io::testdata::temp_dir("outputs-world");
        let out = dir.join("out");
        let outputs = prepare(&out, &[]).unwrap();
        let record = world_record(run.notes);
        let summary = finish(&run.engine, outputs, &ExportOptions::default(), record).unwrap();
        assert_eq!((summary.scans, summary.source_kind.as_str()), (40, "world"));
        assert!(summary.entropy.is_some());
        let mut listed: Vec<&str> = summary.files.iter().map(|f| f.name.as_str()).collect();
        listed.sort_unstable();
        let want = ["map.mcap", "map.npz", "map.pcd", "map.pgm", "map.ply", "map.png", "map.yaml", "report.html"];
        assert_eq!(listed, want);
        for f in &summary.files {
            assert_eq!(std::fs::metadata(out.join(&f.name)).unwrap().len(), f.bytes, "{}", f.name);
        }
        let written: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(written["scans"], 40);
        assert!(summary.to_string().starts_with("source        corridor (world)\nscans         40\n"));
    }

    /// A run that fails while it writes `map.mcap` (written after every map file but the
    /// report) leaves the previous set as it was: nothing of the failed run is in the
    /// directory. (Here the staged `map.mcap` cannot be written because a directory holds
    /// its name; the CLI's `output_set` test stops a run with a file-size limit instead,
    /// as a full disk would.)
    #[test]
    fn a_run_failing_at_map_mcap_leaves_the_previous_set() {
        let dir = fusemap_io::testdata::temp_dir("outputs-mcap-fails");
        let out = dir.join("out");
        let first = corridor_run(40);
        finish(&first.engine, prepare(&out, &[]).unwrap(), &ExportOptions::default(), world_record(Vec::new()))
            .unwrap();
        let before: Vec<(std::ffi::OsString, Vec<u8>)> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap())
            .filter(|e| e.file_type().unwrap().is_file())
            .map(|e| (e.file_name(), std::fs::read(e.path()).unwrap()))
            .collect();
        assert!(before.iter().any(|(n, _)| n == "map.mcap"));
        // Another map (half the poses): any file of it moved into the directory would differ.
        let second = corridor_run(20);
        let outputs = prepare(&out, &[]).unwrap();
        std::fs::create_dir_all(outputs.files.mcap.join("in-the-way")).unwrap();
        let err = finish(&second.engine, outputs, &ExportOptions::default(), world_record(Vec::new())).unwrap_err();
        assert!(err.to_string().contains("map.mcap"), "{err}");
        let entries: Vec<std::fs::DirEntry> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap()).collect();
        let after: Vec<_> =
            entries.iter().filter(|e| e.file_type().unwrap().is_file()).map(|e| e.file_name()).collect();
        assert_eq!(after.len(), before.len(), "{after:?}");
        // No directory but the failed run's hidden staging (the next run removes it).
        let dirs: Vec<_> = entries.iter().filter(|e| e.file_type().unwrap().is_dir()).map(|e| e.file_name()).collect();
        assert!(dirs.iter().all(|d| d.to_string_lossy().starts_with('.')), "{dirs:?}");
        for (name, bytes) in &before {
            assert!(std::fs::read(out.join(name)).unwrap() == *bytes, "{name:?} changed by the failed run");
        }
    }
}
