//! The run configuration: the design document's parameter table (§4.2) as one typed
//! value, and its validation.
//!
//! Parsing (TOML) lives in `fusemap-io`; this module only says what a valid
//! configuration is. Unknown keys are refused at parse time (`deny_unknown_fields`), so a
//! misspelt `p_ocupied` is an error and not a silently ignored line. Every validation
//! error names the field, in the path form the TOML file uses (`lidar[0].p_occ`).

mod camera;
mod fusion;
mod limits;
mod log;
mod map;
mod output;
mod plan;
mod pose_sensor;
mod sensor;
mod slam;
mod validate;

pub use camera::{default_camera, default_class_color, ClassConfig, PlannedCamera, DEFAULT_PAIR_TOLERANCE_S};
pub use fusion::FusionConfig;
pub use limits::LimitsConfig;
pub use log::{ExtrinsicsSource, LogConfig, PoseSource, SyncConfig};
pub use map::MapConfig;
pub use output::{OutputConfig, PointsMode};
pub use plan::auto_sensor;
pub use sensor::{GnssNoise, OdometryNoise, PlannedLidar, PlannedSensor, SensorConfig, SensorKind};
pub use slam::{SlamConfig, SlamMode};
pub use validate::{Thresholds, ValidateConfig};

use crate::estimator::EstimatorConfig;
use crate::grid::{GridGeometry, OccupancyParams};
use crate::sensor::ClassTable;
use serde::{Deserialize, Serialize};

/// The whole configuration.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The map.
    #[serde(default)]
    pub map: MapConfig,
    /// The sensors, one `[[sensor]]` table each.
    #[serde(default)]
    pub sensor: Vec<SensorConfig>,
    /// The pose estimator (EKF + RTS smoother) fusing odometry, IMU, GNSS and poses.
    #[serde(default)]
    pub estimator: EstimatorConfig,
    /// How robot logs are read: topics, pose source, time synchronisation.
    #[serde(default)]
    pub log: LogConfig,
    /// How the sensors' evidence is combined: correlated sensors, the dynamic layer.
    #[serde(default)]
    pub fusion: FusionConfig,
    /// Scan matching, submaps and loop closure.
    #[serde(default)]
    pub slam: SlamConfig,
    /// Resource budgets: map cells, cells per ray, cells of a dense export.
    #[serde(default)]
    pub limits: LimitsConfig,
    /// The semantic classes of the cameras' label images, one `[[class]]` table each;
    /// none: [`ClassTable::production_default`].
    #[serde(default)]
    pub class: Vec<ClassConfig>,
    /// `fusemap validate`: the held-out share and the verdict's thresholds (§5).
    #[serde(default)]
    pub validate: ValidateConfig,
    /// Which optional map formats a run writes (`map.mcap`, `map.pcd`, `map.ply`).
    #[serde(default)]
    pub output: OutputConfig,
}

/// A configuration error names the field ([`FieldError`], the error of every parameter
/// check).
pub use crate::field_error::FieldError;

fn err(field: impl Into<String>, message: impl Into<String>) -> FieldError {
    FieldError::new(field, message)
}

fn finite(field: &str, v: f64) -> Result<f64, FieldError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(field, format!("must be a finite number, got {v}")))
    }
}

/// How far from the base a sensor's mount may be, metres: a sensor kilometres away is a
/// typo (or a hostile config), not a robot.
pub const MAX_MOUNT_OFFSET_M: f64 = 1000.0;

/// Checks a configured mount `m` of the table whose keys `f` names: every value finite,
/// the translation within [`MAX_MOUNT_OFFSET_M`].
fn check_mount(f: impl Fn(&str) -> String, m: &crate::geometry::Mount3) -> Result<(), FieldError> {
    for (k, v) in [("x", m.x), ("y", m.y), ("z", m.z), ("roll", m.roll), ("pitch", m.pitch), ("yaw", m.yaw)] {
        let field = f(&format!("base_from_sensor.{k}"));
        finite(&field, v)?;
        if k.len() == 1 && v.abs() > MAX_MOUNT_OFFSET_M {
            return Err(err(field, format!("must be within ±{MAX_MOUNT_OFFSET_M} m of the base, got {v}")));
        }
    }
    Ok(())
}

fn probability(field: &str, v: f64) -> Result<f64, FieldError> {
    finite(field, v)?;
    if v > 0.0 && v < 1.0 {
        Ok(v)
    } else {
        Err(err(field, format!("must be a probability strictly between 0 and 1, got {v}")))
    }
}

/// A validated configuration, ready to build a map and sensor models.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The grid's placement.
    pub geometry: GridGeometry,
    /// The grid's probabilities.
    pub occupancy: OccupancyParams,
    /// Each enabled lidar: name, model, the 3D mount it was reduced from, its topic.
    /// Without any `[[sensor]]` of kind lidar, one default lidar whose topic is found in
    /// the log; with every listed lidar disabled, none (a log run then refuses).
    pub lidars: Vec<PlannedLidar>,
    /// The enabled sensors that are not lidars, as configured (kinds not listed are
    /// auto-detected by the log pipeline with [`auto_sensor`]).
    pub sensors: Vec<PlannedSensor>,
    /// The enabled cameras listed in the config (a log run also maps one it finds on the
    /// default camera topics, unless the kind is disabled: `fusemap-pipeline`'s map pass).
    pub cameras: Vec<PlannedCamera>,
    /// The semantic classes of the label images.
    pub classes: ClassTable,
    /// Kinds listed only with `enabled = false`: not auto-detected either.
    pub disabled_kinds: Vec<SensorKind>,
    /// How logs are read.
    pub log: LogConfig,
    /// The pose estimator's figures.
    pub estimator: EstimatorConfig,
    /// How the sensors' evidence is combined.
    pub fusion: FusionConfig,
    /// The dynamic layer's parameters (from `[fusion]`).
    pub dynamic: crate::grid::DynamicParams,
    /// When SLAM runs.
    pub slam_mode: SlamMode,
    /// SLAM's parameters (from `[slam]`).
    pub slam: crate::slam::SlamParams,
    /// The resource budgets (`[limits]`).
    pub limits: LimitsConfig,
    /// `fusemap validate`'s held-out share (`[validate]`).
    pub holdout_share: f64,
    /// The validation verdict's thresholds (`[validate]`).
    pub validation: Thresholds,
    /// The optional map formats to write (`[output]`).
    pub output: OutputConfig,
}

impl Config {
    /// Checks every field and builds the plan. The first problem found is returned.
    pub fn validate(&self) -> Result<Plan, FieldError> {
        let (geometry, occupancy) = self.map.validate()?;
        let plan::PlannedSensors { mut lidars, cameras, others: sensors } =
            plan::plan_sensors(&self.sensor, occupancy.prior)?;
        let lidar_listed = self.sensor.iter().any(|s| s.kind == SensorKind::Lidar);
        if lidars.is_empty() && !lidar_listed {
            lidars.push(sensor::default_lidar());
        }
        self.log.validate()?;
        let disabled_kinds = SensorKind::ALL
            .into_iter()
            .filter(|k| {
                let mut listed = self.sensor.iter().filter(|s| s.kind == *k);
                listed.clone().next().is_some() && listed.all(|s| !s.enabled)
            })
            .collect();
        let classes = camera::class_table(&self.class)?;
        self.estimator.validate()?;
        let dynamic = self.fusion.validate(occupancy.occupied_threshold)?;
        let mut slam = self.slam.validate()?;
        let motion = self.log.motion_limits();
        (slam.max_track_speed_m_s, slam.max_track_turn_rate_rad_s) = (motion.max_speed_m_s, motion.max_turn_rate_rad_s);
        self.limits.validate()?;
        let validation = self.validate.validate(self.log.extrinsics_tolerance_deg)?;
        self.check_rays(geometry.resolution(), &lidars, &cameras, &slam)?;
        self.check_correlated(&lidars, &cameras, &sensors)?;
        Ok(Plan {
            geometry,
            occupancy,
            lidars,
            sensors,
            cameras,
            classes,
            disabled_kinds,
            log: self.log.clone(),
            estimator: self.estimator.clone(),
            fusion: self.fusion.clone(),
            dynamic,
            slam_mode: self.slam.mode,
            slam,
            limits: self.limits,
            holdout_share: self.validate.holdout_share,
            validation,
            output: self.output,
        })
    }

    /// Every ray a sensor or SLAM may cast within `limits.ray_cells`.
    fn check_rays(
        &self,
        res: f64,
        lidars: &[PlannedLidar],
        cameras: &[PlannedCamera],
        slam: &crate::slam::SlamParams,
    ) -> Result<(), FieldError> {
        let limits = self.limits;
        for (i, l) in lidars.iter().enumerate() {
            let key = lidar_key(&self.sensor, i, "max_range");
            limits.check_ray(&key, l.model.params().max_range, "map.resolution", res)?;
        }
        for (i, c) in cameras.iter().enumerate() {
            limits.check_ray(&camera_key(&self.sensor, i), c.params.max_depth_m, "map.resolution", res)?;
        }
        limits.check_ray("slam.max_range_m", slam.max_range_m, "slam.resolution_m", slam.resolution)
    }

    /// Every name of `fusion.correlated` is an enabled sensor's.
    fn check_correlated(
        &self,
        lidars: &[PlannedLidar],
        cameras: &[PlannedCamera],
        sensors: &[PlannedSensor],
    ) -> Result<(), FieldError> {
        for (i, group) in self.fusion.correlated.iter().enumerate() {
            for name in group {
                let known = lidars.iter().any(|l| &l.name == name)
                    || cameras.iter().any(|c| &c.name == name)
                    || sensors.iter().any(|s| &s.name == name);
                if !known {
                    return Err(err(format!("fusion.correlated[{i}]"), format!("no enabled sensor is named `{name}`")));
                }
            }
        }
        Ok(())
    }
}

/// The key of the `i`-th planned lidar's `key` (`sensor[2].max_range`), or the default
/// lidar's (no `[[sensor]] kind = "lidar"` listed).
fn lidar_key(tables: &[SensorConfig], i: usize, key: &str) -> String {
    let listed = tables.iter().enumerate().filter(|(_, s)| s.kind == SensorKind::Lidar && s.enabled).nth(i);
    match listed {
        Some((k, _)) => format!("sensor[{k}].{key}"),
        None => format!("the default lidar's {key}"),
    }
}

/// The key of the `i`-th planned camera's depth limit.
fn camera_key(tables: &[SensorConfig], i: usize) -> String {
    let listed = tables.iter().enumerate().filter(|(_, s)| s.kind == SensorKind::Camera && s.enabled).nth(i);
    match listed {
        Some((k, _)) => format!("sensor[{k}].max_depth_m"),
        None => "the default camera's max_depth_m".into(),
    }
}

#[cfg(test)]
mod tests;
