//! `fusemap._fusemap`: fusemap from Python. `map_log_fields` maps a log as `fusemap map`
//! does and hands the arrays over as numpy arrays (moved, not copied); `Grid` maps scans
//! online, one call a scan, for a ROS 2 node or a notebook. The GIL is released while
//! mapping. Errors are Python exceptions with the CLI's messages: `OSError` for a file
//! that cannot be read or written, `ValueError` for anything else (a bad config, a log
//! that is not valid, a refused run).

use fusemap_core::config::{Config, Plan};
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::grid::{FusionGrid, Raster};
use fusemap_core::measurement::{RangeData, Ray, SensorId};
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;
use fusemap_pipeline::in_memory::{map_log_in_memory, MappedLog};
use fusemap_pipeline::job::JobError;
use fusemap_pipeline::outputs::{view_of, ExportOptions, ExportRoom, MapView};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// An error and its causes on one line, as the CLI prints it after `error: `.
fn message(e: &dyn std::error::Error) -> String {
    fusemap_io::text::error_line(e)
}

/// `OSError` for a file that could not be read or written, `ValueError` otherwise.
fn io_error(e: fusemap_io::Error) -> PyErr {
    let text = message(&e);
    let err = match e {
        fusemap_io::Error::Io { .. } => PyOSError::new_err(text),
        _ => PyValueError::new_err(text),
    };
    with_stage(err, None)
}

/// `err` with the stage of the run that refused it as its `stage` attribute (`None`
/// when it is no refusal): every error `map_log` raises has one.
fn with_stage(err: PyErr, stage: Option<fusemap_pipeline::Stage>) -> PyErr {
    Python::attach(|py| {
        // Setting an attribute on a fresh exception cannot fail; if it did, the error
        // would still carry its message.
        let _ = err.value(py).setattr("stage", stage.map(fusemap_pipeline::Stage::name));
    });
    err
}

/// `OSError` for a file, `ValueError` otherwise; a refused run's carries the stage that
/// refused it as `stage` (`"sensors"`, `"poses"`, `"budget"`, …; `None` for other errors),
/// so a caller can tell a budget to raise from a sensor to add without reading the text.
fn job_error(e: JobError) -> PyErr {
    let stage = match &e {
        JobError::Run { error, .. } | JobError::Pipeline(error) => error.refusal_stage(),
        _ => None,
    };
    match e {
        JobError::File(e) => io_error(e),
        e => with_stage(PyValueError::new_err(message(&e)), stage),
    }
}

/// The configuration `config` names: a TOML file's path (an existing file, or any text
/// without a newline: a missing file is then an `OSError`), or the TOML text itself.
fn config_of(config: &str) -> PyResult<(Config, PathBuf, String)> {
    let path = Path::new(config);
    if path.is_file() || !config.contains('\n') {
        let text = fusemap_io::config_file::read_text(path).map_err(io_error)?;
        let parsed = fusemap_io::config_file::parse_config_str(&text, path).map_err(io_error)?;
        return Ok((parsed, path.to_path_buf(), text));
    }
    let name = PathBuf::from("<config string>");
    let parsed = fusemap_io::config_file::parse_config_str(config, &name).map_err(io_error)?;
    Ok((parsed, name, config.to_string()))
}

/// The plan of `config` (see [`config_of`]; the defaults without), with the map's
/// resolution replaced by `resolution` when given. Field errors name the file and line.
fn plan_of(config: Option<&str>, resolution: Option<f64>) -> PyResult<Plan> {
    let (mut parsed, path, text) = match config {
        Some(c) => config_of(c)?,
        None => (Config::default(), PathBuf::from("<defaults>"), String::new()),
    };
    if let Some(r) = resolution {
        parsed.map.resolution = r;
    }
    parsed.validate().map_err(|e| io_error(fusemap_io::config_file::field_error(&path, &text, &e.field, e.message)))
}

/// The raster's arrays as numpy arrays, row 0 = lowest y: occupancy (float32), log-odds
/// (float32), known (bool).
fn raster_arrays<'py>(py: Python<'py>, r: Raster, into: &Bound<'py, PyDict>) -> PyResult<()> {
    let shape = (r.height, r.width);
    let shaped = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let occupancy = Array2::from_shape_vec(shape, r.occupancy()).map_err(shaped)?;
    into.set_item("occupancy", occupancy.into_pyarray(py))?;
    into.set_item("log_odds", Array2::from_shape_vec(shape, r.log_odds).map_err(shaped)?.into_pyarray(py))?;
    into.set_item("known", Array2::from_shape_vec(shape, r.known).map_err(shaped)?.into_pyarray(py))?;
    into.set_item("resolution", r.resolution)?;
    into.set_item("origin", (r.origin.x, r.origin.y))?;
    Ok(())
}

/// Builds the fields of `fusemap.Map` from a mapped log.
fn mapped_fields<'py>(py: Python<'py>, m: MappedLog) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let MappedLog { raster, layers, trajectory, report } = m;
    let (h, w) = (raster.height, raster.width);
    raster_arrays(py, raster, &d)?;
    let shaped = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    if let Some(l) = layers {
        let s = l.semantic;
        d.set_item("semantic_class", Array2::from_shape_vec((h, w), s.best).map_err(shaped)?.into_pyarray(py))?;
        d.set_item("semantic_prob", Array2::from_shape_vec((h, w), s.prob).map_err(shaped)?.into_pyarray(py))?;
        let k = s.classes.len();
        if s.probs.len() == h * w * k {
            d.set_item("semantic_probs", Array3::from_shape_vec((h, w, k), s.probs).map_err(shaped)?.into_pyarray(py))?;
        }
        let names: Vec<String> = s.classes.iter().map(|c| c.name.clone()).collect();
        let ids: Vec<u16> = s.classes.iter().map(|c| c.id).collect();
        d.set_item("semantic_class_names", names)?;
        d.set_item("semantic_class_ids", Array1::from(ids).into_pyarray(py))?;
        // As map.npz: NaN where the layer never observed the cell.
        let cells = l.dynamic.cells.iter().zip(&l.dynamic.known).map(|(&p, &k)| if k { p } else { f32::NAN });
        let dynamic = Array2::from_shape_vec((h, w), cells.collect()).map_err(shaped)?;
        d.set_item("dynamic", dynamic.into_pyarray(py))?;
    }
    // TUM rows: t x y z qx qy qz qw.
    let rows: Vec<f64> = trajectory
        .iter()
        .flat_map(|(t, p)| {
            let (s, c) = (0.5 * p.theta).sin_cos();
            [t.as_secs_f64(), p.x, p.y, 0.0, 0.0, 0.0, s, c]
        })
        .collect();
    d.set_item("trajectory", Array2::from_shape_vec((trajectory.len(), 8), rows).map_err(shaped)?.into_pyarray(py))?;
    let json = py.import("json")?;
    d.set_item("summary", json.call_method1("loads", (report.to_string(),))?)?;
    Ok(d)
}

/// Maps the log at `path` (CARMEN, ROS 1 bag, MCAP, rosbag2 directory) as `fusemap map`
/// does, with `config` (a path or TOML text; the defaults without), and returns the map's
/// fields as a dict (the Python `fusemap.map_log` wraps it in a `Map`).
#[pyfunction]
#[pyo3(signature = (path, config=None))]
fn map_log_fields<'py>(py: Python<'py>, path: PathBuf, config: Option<String>) -> PyResult<Bound<'py, PyDict>> {
    let plan = plan_of(config.as_deref(), None)?;
    // Boxed: a job error is large, and it crosses the detach boundary by value.
    let mapped = py.detach(|| map_log_in_memory(&plan, &path).map_err(Box::new)).map_err(|e| job_error(*e))?;
    mapped_fields(py, mapped)
}

/// An occupancy grid mapped online with one lidar: the config's `[map]` and the first
/// lidar's model (or the defaults), scans and points inserted one call at a time. The
/// engine sits behind a mutex: calls from several threads (an rclpy multi-threaded
/// executor) wait for each other, with the GIL released while they map.
#[pyclass(module = "fusemap._fusemap", frozen)]
struct Grid {
    inner: Mutex<Engine>,
    lidar: SensorId,
    plan: Plan,
}

#[pymethods]
impl Grid {
    /// A grid of `resolution` metres (the config's, 0.05 by default) with `config`.
    #[new]
    #[pyo3(signature = (resolution=None, config=None))]
    fn new(resolution: Option<f64>, config: Option<String>) -> PyResult<Self> {
        let plan = plan_of(config.as_deref(), resolution)?;
        let mut engine = Engine::new(FusionGrid::new(plan.geometry, plan.occupancy));
        engine.set_limits(&plan.limits);
        let lidar = plan.lidars.first().ok_or_else(|| PyValueError::new_err("the configuration enables no lidar"))?;
        let lidar = engine.add_lidar(lidar.name.clone(), lidar.model);
        Ok(Self { inner: Mutex::new(engine), lidar, plan })
    }

    /// Inserts one scan: `ranges` (metres, float32; NaN, inf, 0 are handled as the
    /// lidar model says), beam `i` at `angle_min + i * angle_increment` radians, taken
    /// with the base at `pose` = (x, y, yaw) in the map frame, at `stamp` seconds.
    fn insert_scan(
        &self,
        py: Python<'_>,
        ranges: PyReadonlyArray1<'_, f32>,
        angle_min: f64,
        angle_increment: f64,
        pose: (f64, f64, f64),
        stamp: f64,
    ) -> PyResult<()> {
        let stamp = Stamp::from_secs_f64(stamp).ok_or_else(|| PyValueError::new_err("stamp is not a time"))?;
        let ranges = ranges.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?.to_vec();
        let scan = LaserScan { stamp, angle_min, angle_increment, ranges };
        let pose = Pose2::new(pose.0, pose.1, pose.2);
        py.detach(|| self.engine().insert_scan(self.lidar, &scan, pose))
            .map(|_| ())
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Inserts obstacle points seen from `pose`: `points` is N × 2 (x, y in the base frame,
    /// metres), each the end of a ray from the lidar's mount; a point past the lidar's
    /// maximum range clears its ray up to that range and marks nothing.
    fn insert_points(
        &self,
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        pose: (f64, f64, f64),
        stamp: f64,
    ) -> PyResult<()> {
        let stamp = Stamp::from_secs_f64(stamp).ok_or_else(|| PyValueError::new_err("stamp is not a time"))?;
        let points = points.as_array();
        if points.ncols() != 2 {
            return Err(PyValueError::new_err(format!("points must be N x 2, got N x {}", points.ncols())));
        }
        let model = *self.engine().lidar_model(self.lidar).ok_or_else(|| PyValueError::new_err("no lidar"))?;
        let world_from_base = Pose2::new(pose.0, pose.1, pose.2);
        let origin = world_from_base.transform_point(model.mount().origin_in_base());
        let max_range = model.params().max_range;
        let mut data = RangeData::empty(self.lidar, model.evidence());
        data.stamp = stamp;
        for p in points.rows() {
            let end = world_from_base.transform_point(Point2::new(p[0], p[1]));
            if !(end.x.is_finite() && end.y.is_finite()) {
                return Err(PyValueError::new_err("points must be finite"));
            }
            let (dx, dy) = (end.x - origin.x, end.y - origin.y);
            let d = dx.hypot(dy);
            let ray = if d <= max_range {
                Ray { origin, end, hit: true }
            } else {
                let s = max_range / d;
                Ray { origin, end: Point2::new(origin.x + dx * s, origin.y + dy * s), hit: false }
            };
            data.rays.push(ray);
        }
        py.detach(|| self.engine().insert_range_data(&data))
            .map(|_| ())
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The map over the observed cells' bounding box, as `map.npz` holds it: a dict of
    /// `occupancy`, `log_odds`, `known`, `resolution`, `origin`.
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        raster_arrays(py, self.raster()?, &d)?;
        Ok(d)
    }

    /// Writes the map as `map.npz` (the CLI's layout) to `path`, atomically.
    fn to_npz(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let r = self.raster()?;
        py.detach(|| fusemap_io::npz::write_map_npz(&path, &r)).map_err(io_error)
    }
}

impl Grid {
    /// The engine, locked (a panic in another call leaves it usable: each insert is whole).
    fn engine(&self) -> std::sync::MutexGuard<'_, Engine> {
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn raster(&self) -> PyResult<Raster> {
        let engine = self.engine();
        let grid = engine.grid();
        let room = ExportRoom::of(engine.export_room(engine.maps().primary()));
        let mut notes = Vec::new();
        match view_of(grid, &ExportOptions::of(&self.plan, None), room, &mut notes) {
            Ok(MapView::Dense(r)) => Ok(r),
            Ok(MapView::Empty) => Err(PyValueError::new_err("no cell was observed yet")),
            Ok(MapView::Sparse { .. }) => Err(PyValueError::new_err(format!(
                "the map's box holds more than limits.export_cells ({}) cells",
                self.plan.limits.export_cells
            ))),
            Err(e) => Err(PyValueError::new_err(message(&e))),
        }
    }
}

/// The design document's corridor run (§3.3), as `fusemap demo --corridor` maps it: a list
/// of (ranges, angle_min, angle_increment, (x, y, yaw), stamp) per scan.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn corridor_scans<'py>(
    py: Python<'py>,
) -> PyResult<Vec<(Bound<'py, numpy::PyArray1<f32>>, f64, f64, (f64, f64, f64), f64)>> {
    let run = fusemap_core::sim::SimulatedRun::document_corridor();
    Ok(run
        .scans
        .into_iter()
        .zip(run.poses)
        .map(|(s, p)| {
            let stamp = s.stamp.as_secs_f64();
            (Array1::from(s.ranges).into_pyarray(py), s.angle_min, s.angle_increment, (p.x, p.y, p.theta), stamp)
        })
        .collect())
}

#[pymodule]
fn _fusemap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(map_log_fields, m)?)?;
    m.add_function(wrap_pyfunction!(corridor_scans, m)?)?;
    m.add_class::<Grid>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
