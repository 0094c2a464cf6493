//! The plan step between a command's flags and its run (as ripgrep turns its low-level
//! arguments into high-level ones before searching): everything a map run needs is read,
//! validated and resolved here, once — the configuration into a [`Plan`], a world file
//! into walls and poses, `--crop` checked against the grid and `[limits]`, the files the
//! run reads listed so no output overwrites one — and a [`MapJob`] comes out. Running it
//! ([`MapJob::run`]) maps and writes the output set ([`crate::outputs`]) and returns the
//! summary. A front end (the CLI, a Python binding, a calibration search) builds jobs and
//! runs them; it keeps only its flags, its progress display and its exit codes.

use crate::outputs::{crop_area, finish, prepare, Crop, ExportOptions, OutputError, RunRecord, Seconds, Summary};
use crate::{PipelineError, Progress};
use fusemap_core::config::{Config, FieldError, Plan};
use fusemap_core::geometry::Pose2;
use fusemap_core::sim::{ScannerSpec, World};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a job could not be planned or run. Each message names the file or the input it is
/// about.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// A file could not be read or written, or is not valid (the error names it, and the
    /// line).
    #[error(transparent)]
    File(#[from] fusemap_io::Error),
    /// The built-in configuration is not valid (a `[limits]` or `[map]` default changed
    /// without its checks).
    #[error("configuration: {0}")]
    Config(FieldError),
    /// The outputs cannot be written, or `--crop` names no exportable region.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The arguments ask for no run or for two at once.
    #[error("{0}")]
    Arguments(String),
    /// The run's report could not be put into `summary.json`.
    #[error("cannot write the run report as JSON: {0}")]
    Report(#[from] serde_json::Error),
    /// The simulator refused its scenario.
    #[error("scenario: {0}")]
    Scenario(#[from] fusemap_sim::SimError),
    /// The simulated recording could not be written.
    #[error("writing the simulation to {}: {source}", dir.display())]
    Simulation {
        /// Where it was to go.
        dir: PathBuf,
        /// Why it could not.
        source: fusemap_io::Error,
    },
    /// The simulator's ground truth does not fit the grid.
    #[error(transparent)]
    Truth(#[from] fusemap_sim::TruthRasterError),
    /// The mapping refused or failed (a run of the simulator's own recording).
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// The mapping refused or failed; `input` names the log or the world.
    #[error("{input}: {error}")]
    Run {
        /// The log or the world.
        input: String,
        /// Why.
        error: PipelineError,
    },
}

/// The validated plan of a configuration file, or of the built-in defaults without one:
/// the file is read and validated once (its errors name the file and the line).
pub fn plan_of(config: Option<&Path>) -> Result<Plan, JobError> {
    plan_of_or(config, || Config::default().validate().map_err(JobError::Config))
}

/// The validated plan of a configuration file, or `default()` without one.
pub fn plan_of_or(config: Option<&Path>, default: impl FnOnce() -> Result<Plan, JobError>) -> Result<Plan, JobError> {
    match config {
        Some(p) => Ok(fusemap_io::config_file::load_plan(p)?),
        None => default(),
    }
}

/// A command over one log (`validate`, `calibrate`), planned: the configuration read and
/// checked, the log and the output directory, and the files no output may replace.
pub struct LogJob {
    /// The validated configuration.
    pub plan: Plan,
    /// The log.
    pub log: PathBuf,
    /// The output directory.
    pub out: PathBuf,
    /// The files the run reads (the configuration, the log).
    pub inputs: Vec<PathBuf>,
}

impl LogJob {
    /// `fusemap CMD [--config C] --out DIR LOG`.
    pub fn plan(config: Option<&Path>, log: &Path, out: &Path) -> Result<Self, JobError> {
        let plan = plan_of(config)?;
        let inputs = config.map(Path::to_path_buf).into_iter().chain([log.to_path_buf()]).collect();
        Ok(Self { plan, log: log.to_path_buf(), out: out.to_path_buf(), inputs })
    }

    /// A pipeline error as the job reports it: a reader's names its file already, the
    /// others get the log's name.
    pub(crate) fn named(&self, error: PipelineError) -> JobError {
        match error {
            PipelineError::Read(e) => JobError::File(e),
            error => JobError::Run { input: self.log.display().to_string(), error },
        }
    }

    /// The first pass over the log.
    pub(crate) fn read(&self, progress: &mut dyn FnMut(Progress)) -> Result<crate::recording::Inventory, JobError> {
        progress(Progress::Phase { name: "reading", total: 0 });
        let inv = crate::recording::Inventory::read_with(&self.log, &self.plan.limits).map_err(JobError::File)?;
        progress(Progress::Done);
        Ok(inv)
    }
}

/// What a map run maps.
pub enum MapSource {
    /// A robot log (CARMEN, ROS 1 bag, MCAP, rosbag2 directory), recognised by its content.
    Log(PathBuf),
    /// A simulated run: `scanner` in `world` from each of `poses`; `name` says what it is
    /// in the summary and in errors.
    World {
        /// The walls.
        world: World,
        /// The simulated scanner.
        scanner: ScannerSpec,
        /// `world_from_base` of each scan, in order.
        poses: Vec<Pose2>,
        /// The world file, or the built-in world's name.
        name: String,
    },
}

/// One map run, planned: a log or a world mapped with `plan` into `out`.
pub struct MapJob {
    /// The validated configuration.
    pub plan: Plan,
    /// What is mapped.
    pub source: MapSource,
    /// The output directory.
    pub out: PathBuf,
    /// The view of the map to write.
    pub export: ExportOptions,
    /// Every file the run reads (configuration, world, log): no output may replace one.
    pub inputs: Vec<PathBuf>,
}

impl MapJob {
    /// `fusemap map`: a world file (simulated) or a log, not both, with `config` (or the
    /// defaults); `crop` is checked now, before hours of mapping could end in its refusal.
    pub fn plan(
        config: Option<&Path>,
        world: Option<&Path>,
        log: Option<&Path>,
        out: &Path,
        crop: Option<Crop>,
    ) -> Result<Self, JobError> {
        let plan = plan_of(config)?;
        let export = ExportOptions::of(&plan, crop);
        if let Some(c) = &crop {
            crop_area(&plan.geometry, c, export.export_cells)?;
        }
        let mut inputs: Vec<PathBuf> = config.map(Path::to_path_buf).into_iter().collect();
        let source = match (world, log) {
            (Some(w), None) => {
                inputs.push(w.to_path_buf());
                let wf = fusemap_io::world_file::load_world_with(w, &plan.limits)?;
                let name = w.display().to_string();
                MapSource::World { world: wf.world, scanner: wf.scanner, poses: wf.poses, name }
            }
            (None, Some(l)) => {
                inputs.push(l.to_path_buf());
                MapSource::Log(l.to_path_buf())
            }
            (Some(_), Some(_)) => {
                return Err(JobError::Arguments("give either --world FILE or a LOG, not both".into()))
            }
            (None, None) => {
                return Err(JobError::Arguments(
                    "nothing to map: give a LOG (CARMEN, ROS 1 bag, MCAP, rosbag2 directory) or --world FILE".into(),
                ))
            }
        };
        Ok(Self { plan, source, out: out.to_path_buf(), export, inputs })
    }

    /// A built-in world (`fusemap demo --corridor`) with `config` (or the defaults).
    pub fn world(
        config: Option<&Path>,
        world: World,
        scanner: ScannerSpec,
        poses: Vec<Pose2>,
        name: &str,
        out: &Path,
    ) -> Result<Self, JobError> {
        let plan = plan_of(config)?;
        let export = ExportOptions::of(&plan, None);
        let inputs = config.map(Path::to_path_buf).into_iter().collect();
        let source = MapSource::World { world, scanner, poses, name: name.to_string() };
        Ok(Self { plan, source, out: out.to_path_buf(), export, inputs })
    }

    /// Maps and writes the output set; the summary, as `summary.json` has it.
    pub fn run(self, progress: &mut dyn FnMut(Progress)) -> Result<Summary, JobError> {
        let started = Instant::now();
        let outputs = prepare(&self.out, &self.inputs)?;
        match &self.source {
            MapSource::Log(path) => {
                let input = path.display().to_string();
                // fusemap-io errors already name the file (and the line or message); the
                // engine's refusals (a map past limits.map_cells) and the pipeline's (a log
                // with no scans, a lidar topic the log lacks) do not: named here.
                let run = crate::map_log(&self.plan, path, progress).map_err(|error| match error {
                    PipelineError::Read(e) => JobError::File(e),
                    error => JobError::Run { input: input.clone(), error },
                })?;
                let log = Some(serde_json::to_value(&run.report)?);
                let record = RunRecord {
                    source_kind: &run.format.to_string(),
                    source: &input,
                    started,
                    notes: run.notes,
                    log,
                    trajectory: Some(&run.trajectory),
                    validation: None,
                    calibration: None,
                    endpoints: Some(&run.endpoints),
                    map_from_odom: run.map_from_odom.as_ref().map(|(f, m)| (f.as_str(), *m)),
                    seconds: Seconds::of_log(&run.report),
                };
                Ok(finish(&run.engine, outputs, &self.export, record)?)
            }
            MapSource::World { world, scanner, poses, name } => {
                let t_map = Instant::now();
                let run = crate::world::map_world(&self.plan, world, scanner, poses, progress)
                    .map_err(|error| JobError::Run { input: name.clone(), error })?;
                let record = RunRecord {
                    source_kind: "world",
                    source: name,
                    started,
                    notes: run.notes,
                    log: None,
                    trajectory: None,
                    validation: None,
                    calibration: None,
                    endpoints: None,
                    map_from_odom: None,
                    seconds: Seconds { map: Some(t_map.elapsed().as_secs_f64()), ..Seconds::default() },
                };
                Ok(finish(&run.engine, outputs, &self.export, record)?)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_arguments_are_refused_before_anything_runs() {
        let dir = fusemap_io::testdata::temp_dir("job-plan");
        let out = dir.join("out");
        let e = MapJob::plan(None, None, None, &out, None).err().unwrap().to_string();
        assert!(e.starts_with("nothing to map"), "{e}");
        let (w, l) = (dir.join("w.toml"), dir.join("l.log"));
        let e = MapJob::plan(None, Some(&w), Some(&l), &out, None).err().unwrap().to_string();
        assert!(e.contains("not both"), "{e}");
        let huge = crate::outputs::parse_crop("0,0,1000,1000").unwrap();
        let e = MapJob::plan(None, None, Some(&l), &out, Some(huge)).err().unwrap().to_string();
        assert!(e.contains("limits.export_cells"), "{e}");
        assert!(!out.exists(), "planning wrote nothing");
        let job = MapJob::plan(None, None, Some(&l), &out, None).unwrap();
        assert!(matches!(&job.source, MapSource::Log(p) if p == &l));
        assert_eq!(job.inputs, [l]);
    }

    #[test]
    fn a_world_job_maps_and_writes_its_set() {
        let dir = fusemap_io::testdata::temp_dir("job-world");
        let out = dir.join("out");
        let poses: Vec<Pose2> = (0..40).map(|i| Pose2::new(0.1 * f64::from(i), 0.0, 0.0)).collect();
        let job = MapJob::world(None, fusemap_core::sim::corridor(), ScannerSpec::document(), poses, "corridor", &out)
            .unwrap();
        let summary = job.run(&mut |_| {}).unwrap();
        assert_eq!((summary.scans, summary.source.as_str()), (40, "corridor"));
        assert!(out.join("map.npz").is_file() && out.join("summary.json").is_file());
    }
}
