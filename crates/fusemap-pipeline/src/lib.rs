//! # fusemap-pipeline
//!
//! The log → map pipeline as a library: a recording read as a time-ordered stream of every
//! sensor (never loaded whole), its sensors bound to topics, the pose track chosen and
//! built (odometry, TF, poses on CARMEN scan lines, or the estimator fusing odometry, IMU,
//! GNSS and absolute poses), every lidar mapped through the engine, and a report of what
//! happened. One call, [`map_log`], runs a whole mapping pass in memory: the `fusemap` CLI,
//! a Python binding or a calibration search all use it the same way. [`outputs`] writes a
//! finished run's files, the same for every command.
//!
//! | concept | module |
//! |---|---|
//! | the time-ordered merge of sensor streams | [`merge`] |
//! | the two passes over a recording | [`recording`] |
//! | configured sensors bound to the log's topics | [`sensors`] |
//! | choosing and building the pose track | [`track`] |
//! | the estimator's inputs from log messages | [`estimation`] |
//! | sensor mounts from TF or config | [`extrinsics`] |
//! | the mapping pass | [`run`] |
//! | the run report | [`report`] |
//! | the output files and `summary.json` | [`outputs`] |
//! | a command's arguments checked and resolved into a run | [`job`] |
//! | the production-line demo: simulated, mapped three ways, scored, drawn | [`demo`] |
//! | the log doctor's figures | [`doctor`] |
//! | §5's validation: M1, M2, M3, held-out hit rates, entropy, verdict | [`validate`] |
//! | self-calibration: the lidar's mount and the odometry's scale from their motions | [`calibrate`] |
//! | GNSS quality over time, odometry against the gyro | [`pose_sensors_report`] |

#![warn(missing_docs)]

pub mod calibrate;
pub mod camera;
pub mod demo;
pub mod doctor;
pub mod estimation;
pub mod estimation_report;
pub mod extrinsics;
pub mod gnss_fixes;
pub mod in_memory;
mod insert;
pub mod job;
mod lidar_frames;
pub(crate) mod log_findings;
mod map_pass;
pub mod merge;
pub mod outputs;
mod pass_notes;
pub mod pose_sensors_report;
pub mod progress;
pub mod recording;
pub mod repeats;
pub mod report;
pub mod run;
pub mod scenario;
pub mod sensors;
pub mod simulate;
pub mod slam;
pub mod slam_bench;
pub mod slam_summary;
pub mod sync;
pub mod track;
pub mod validate;
pub mod world;

pub use run::{map_inventory, map_log, map_with_track, MapRun, PassMaps, Progress};

pub(crate) use sync::offset_ns;

/// Why a run could not be done.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading the log failed, or writing a file beside it (slam-bench's dumps): the error
    /// names the file and the place in it.
    #[error(transparent)]
    Read(#[from] fusemap_io::Error),
    /// The engine refused a measurement.
    #[error(transparent)]
    Engine(#[from] fusemap_core::fusion::EngineError),
    /// The log and the configuration do not allow a run: the stage that refused, and why.
    #[error("{0}")]
    Refused(Refusal),
    /// Writing a text report failed.
    #[error("cannot format the report")]
    Format(#[from] std::fmt::Error),
}

impl PipelineError {
    /// A refusal by `stage`, saying `why`.
    pub fn refused(stage: Stage, why: impl Into<String>) -> Self {
        Self::Refused(Refusal { stage, why: why.into() })
    }

    /// The stage that refused the run, if it was refused: a map past its budget, which
    /// the engine refuses, is the budget's.
    pub fn refusal_stage(&self) -> Option<Stage> {
        match self {
            Self::Refused(r) => Some(r.stage),
            Self::Engine(e) => Stage::of_engine_error(e),
            _ => None,
        }
    }
}

/// Why the log and the configuration allow no run: the stage that said so, for a caller
/// to act on (a budget to raise, a pose source to add), and the sentence a user reads.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{why}")]
pub struct Refusal {
    /// Which stage refused.
    pub stage: Stage,
    /// Why, naming the sensor, topic, key or stamp concerned.
    pub why: String,
}

/// The stage of a run that refused it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Binding the configured sensors to the log's topics: no scans, no lidar, a topic the
    /// log lacks or that two sensors claim, a camera whose streams are unusable.
    Sensors,
    /// A sensor's mount (the configuration's or TF's) cannot be placed.
    Mounts,
    /// No pose track can be built: odometry, TF, scan-line poses or the estimator.
    Poses,
    /// A budget of `[limits]` is met: the maps' tiles, SLAM's grids, the returns of an
    /// endpoint cloud.
    Budget,
    /// A built-in configuration or scenario is not valid.
    Configuration,
    /// A world scan the engine refused.
    World,
    /// `fusemap validate` has nothing it can judge.
    Validation,
    /// `fusemap slam-bench` cannot score a log.
    Benchmark,
}

impl Stage {
    /// The stage an engine error refuses a run at, when it is a refusal: a map past its
    /// budget is the budget's; any other engine error is a fault, not a refusal.
    pub fn of_engine_error(e: &fusemap_core::fusion::EngineError) -> Option<Stage> {
        matches!(e, fusemap_core::fusion::EngineError::MapBudget { .. }).then_some(Stage::Budget)
    }

    /// Its name in snake case (`"budget"`), as the Python package's exceptions carry it.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Sensors => "sensors",
            Stage::Mounts => "mounts",
            Stage::Poses => "poses",
            Stage::Budget => "budget",
            Stage::Configuration => "configuration",
            Stage::World => "world",
            Stage::Validation => "validation",
            Stage::Benchmark => "benchmark",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_is_named_as_serde_names_it() {
        for stage in [
            Stage::Sensors,
            Stage::Mounts,
            Stage::Poses,
            Stage::Budget,
            Stage::Configuration,
            Stage::World,
            Stage::Validation,
            Stage::Benchmark,
        ] {
            assert_eq!(serde_json::to_value(stage).unwrap(), stage.name(), "{stage:?}");
        }
        use fusemap_core::fusion::{BudgetKey, EngineError};
        let budget = EngineError::MapBudget {
            key: BudgetKey::MemoryMib,
            limit: 1,
            tiles: 0,
            tile_bytes: 0,
            maps: 1,
            stamp: fusemap_core::time::Stamp(0),
        };
        assert_eq!(PipelineError::Engine(budget).refusal_stage(), Some(Stage::Budget));
        let fault = EngineError::UnknownSensor(fusemap_core::measurement::SensorId(3));
        assert_eq!(PipelineError::Engine(fault).refusal_stage(), None);
        let e = PipelineError::refused(Stage::Budget, "past limits.memory_mib");
        assert_eq!((e.refusal_stage(), e.to_string().as_str()), (Some(Stage::Budget), "past limits.memory_mib"));
    }
}
