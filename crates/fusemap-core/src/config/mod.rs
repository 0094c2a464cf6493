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
mod sensor;
mod slam;

pub use camera::{default_camera, default_class_color, ClassConfig, PlannedCamera, DEFAULT_PAIR_TOLERANCE_S};
pub use fusion::FusionConfig;
pub use limits::LimitsConfig;
pub use sensor::{auto_sensor, GnssNoise, OdometryNoise, PlannedLidar, PlannedSensor, SensorConfig, SensorKind};
pub use slam::{SlamConfig, SlamMode};

use crate::estimator::EstimatorConfig;
use crate::geometry::Point2;
use crate::grid::{GridGeometry, OccupancyParams, PassThroughParams};
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
}

/// Where a log's scans get their poses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseSource {
    /// The pose written on the scan line if the log has one (CARMEN), else the estimator
    /// when the log has an IMU, GNSS or poses, else the odometry topic, else TF to the base
    /// frame.
    #[default]
    Auto,
    /// The pose on each scan line (CARMEN corrected logs).
    ScanLine,
    /// The odometry topic, interpolated at each scan's stamp.
    Odometry,
    /// Dynamic TF transforms to the base frame, interpolated at each scan's stamp.
    Tf,
    /// The pose estimator: wheel odometry, IMU, GNSS and absolute poses fused by an
    /// extended Kalman filter and smoothed over the whole log (`auto` picks it when the log
    /// carries an IMU, GNSS or poses).
    Estimator,
}

/// How the pose at a scan's stamp is found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SyncConfig {
    /// Interpolate between the poses around the stamp.
    #[default]
    Interpolate,
    /// The nearest pose within `nearest_tolerance_s` (the design document's prototype).
    Nearest,
}

/// Where the laser's mount comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtrinsicsSource {
    /// `/tf_static` base → laser when the log has it, else the config's mount.
    #[default]
    Auto,
    /// Always the log's TF; a log without it is an error.
    Tf,
    /// Always the config's mount (TF, if present, is still compared and reported).
    Config,
}

/// How robot logs are read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogConfig {
    /// The robot's base frame.
    pub base_frame: String,
    /// Where scan poses come from.
    pub pose_source: PoseSource,
    /// Interpolation or nearest neighbour.
    pub sync: SyncConfig,
    /// Nearest-neighbour tolerance, seconds; 0 means half the median scan period.
    pub nearest_tolerance_s: f64,
    /// Longest gap in the pose track to interpolate across, seconds.
    pub max_pose_gap_s: f64,
    /// Interpolate across a longer gap when the robot moved at most this far over it,
    /// metres (0 disables).
    pub gap_bridge_motion_m: f64,
    /// … and turned at most this much, degrees.
    pub gap_bridge_motion_deg: f64,
    /// A pose sample implying a faster motion than this (from its neighbours in stamp
    /// order) is a glitch: rejected and counted, on every pose source. Metres per second.
    pub max_speed_m_s: f64,
    /// … or a faster turn than this, degrees per second.
    pub max_turn_rate_deg_s: f64,
    /// Place each beam with the pose at its own time (needs `time_increment`).
    pub deskew: bool,
    /// Where the laser mount comes from.
    pub extrinsics: ExtrinsicsSource,
    /// Largest accepted difference between TF and config mount translation, metres.
    pub extrinsics_tolerance_m: f64,
    /// Largest accepted difference between TF and config mount yaw, degrees.
    pub extrinsics_tolerance_deg: f64,
    /// A header stamp further than this from its receive time is reported, seconds.
    pub far_delay_s: f64,
    /// How far (seconds of header stamp) the time-ordered merge of the log's streams waits
    /// for a late message before releasing a later one: messages that arrive later than
    /// this behind their stream are counted and dropped. Bounds the memory of a run.
    pub reorder_window_s: f64,
}

impl LogConfig {
    /// The pose-glitch limits (`max_speed_m_s`, `max_turn_rate_deg_s`).
    pub fn motion_limits(&self) -> crate::time::MotionLimits {
        crate::time::MotionLimits {
            max_speed_m_s: self.max_speed_m_s,
            max_turn_rate_rad_s: self.max_turn_rate_deg_s.to_radians(),
        }
    }
}

impl Default for LogConfig {
    fn default() -> Self {
        Self {
            base_frame: "base_link".into(),
            pose_source: PoseSource::Auto,
            sync: SyncConfig::Interpolate,
            nearest_tolerance_s: 0.0,
            max_pose_gap_s: 0.5,
            gap_bridge_motion_m: 0.05,
            gap_bridge_motion_deg: 2.0,
            max_speed_m_s: 20.0,
            max_turn_rate_deg_s: 720.0,
            deskew: true,
            extrinsics: ExtrinsicsSource::Auto,
            extrinsics_tolerance_m: 0.02,
            extrinsics_tolerance_deg: 1.0,
            far_delay_s: 1.0,
            reorder_window_s: 2.0,
        }
    }
}

/// The map's geometry and probabilities.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapConfig {
    /// Cell side, metres.
    pub resolution: f64,
    /// Lower-left corner of cell (0, 0), metres; `None` puts cell centres on multiples of
    /// the resolution.
    pub origin: Option<[f64; 2]>,
    /// Prior occupancy probability of an unobserved cell.
    pub prior: f64,
    /// Lower clamp on a cell's probability.
    pub clamp_min: f64,
    /// Upper clamp on a cell's probability.
    pub clamp_max: f64,
    /// A cell is occupied above this probability.
    pub occupied_threshold: f64,
    /// A cell is free below this probability.
    pub free_threshold: f64,
    /// Free evidence behind confidently occupied cells (`[map.pass_through]`).
    #[serde(default)]
    pub pass_through: PassThroughParams,
}

impl Default for MapConfig {
    fn default() -> Self {
        let p = OccupancyParams::default();
        Self {
            resolution: 0.05,
            origin: None,
            prior: p.prior,
            clamp_min: p.clamp_min,
            clamp_max: p.clamp_max,
            occupied_threshold: p.occupied_threshold,
            free_threshold: p.free_threshold,
            // The configured map handles the lidar's pass-throughs; the core type's
            // default is the plain model.
            pass_through: PassThroughParams::default(),
        }
    }
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
    /// The enabled cameras. Only cameras listed in the config: they are never
    /// auto-detected.
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
}

impl Config {
    /// Checks every field and builds the plan. The first problem found is returned.
    pub fn validate(&self) -> Result<Plan, FieldError> {
        let m = &self.map;
        let res = finite("map.resolution", m.resolution)?;
        if res <= 0.0 {
            return Err(err("map.resolution", format!("must be > 0 metres, got {res}")));
        }
        let geometry = match m.origin {
            Some([x, y]) => {
                finite("map.origin", x)?;
                finite("map.origin", y)?;
                // Beyond 10⁹ m an f64 no longer resolves a position to 10⁻⁷ m, and the cell
                // of a point near the origin is rounded (at 10¹⁵ a quarter of the updates
                // went to the wrong cell); no pose a robot has is that far out either.
                let max = crate::geometry::MAX_POSITION_M;
                if x.abs() > max || y.abs() > max {
                    return Err(err("map.origin", format!("must be within ±{max:e} m, got [{x}, {y}]")));
                }
                GridGeometry::new(res, Point2::new(x, y))
            }
            None => GridGeometry::centered(res),
        }
        .map_err(|e| err("map", e.to_string()))?;
        let prior = probability("map.prior", m.prior)?;
        let cmin = probability("map.clamp_min", m.clamp_min)?;
        let cmax = probability("map.clamp_max", m.clamp_max)?;
        if !(cmin < prior && prior < cmax) {
            return Err(err("map", format!("need clamp_min < prior < clamp_max, got {cmin} / {prior} / {cmax}")));
        }
        let occ_t = probability("map.occupied_threshold", m.occupied_threshold)?;
        let free_t = probability("map.free_threshold", m.free_threshold)?;
        if free_t >= occ_t {
            return Err(err("map.free_threshold", format!("must be below occupied_threshold ({occ_t}), got {free_t}")));
        }
        let pt = m.pass_through;
        probability("map.pass_through.threshold", pt.threshold)?;
        if pt.threshold <= prior {
            return Err(err(
                "map.pass_through.threshold",
                format!("must be above the prior {prior}, got {}", pt.threshold),
            ));
        }
        if !(0.0..=1.0).contains(&finite("map.pass_through.weight", pt.weight)?) {
            return Err(err("map.pass_through.weight", format!("must be within [0, 1], got {}", pt.weight)));
        }
        if pt.margin_cells > 10_000 {
            return Err(err(
                "map.pass_through.margin_cells",
                format!("must be at most 10000, got {}", pt.margin_cells),
            ));
        }
        let occupancy = OccupancyParams {
            prior,
            clamp_min: cmin,
            clamp_max: cmax,
            occupied_threshold: occ_t,
            free_threshold: free_t,
            pass_through: pt,
        };

        let sensor::PlannedSensors { mut lidars, cameras, others: sensors } =
            sensor::plan_sensors(&self.sensor, prior)?;
        let lidar_listed = self.sensor.iter().any(|s| s.kind == SensorKind::Lidar);
        if lidars.is_empty() && !lidar_listed {
            lidars.push(sensor::default_lidar());
        }
        let g = &self.log;
        finite("log.nearest_tolerance_s", g.nearest_tolerance_s)?;
        if g.nearest_tolerance_s < 0.0 {
            return Err(err("log.nearest_tolerance_s", "must be >= 0 (0 = half the scan period)"));
        }
        for (name, v) in
            [("log.gap_bridge_motion_m", g.gap_bridge_motion_m), ("log.gap_bridge_motion_deg", g.gap_bridge_motion_deg)]
        {
            if finite(name, v)? < 0.0 {
                return Err(err(name, format!("must be >= 0, got {v}")));
            }
        }
        for (name, v) in [
            ("log.max_pose_gap_s", g.max_pose_gap_s),
            ("log.max_speed_m_s", g.max_speed_m_s),
            ("log.max_turn_rate_deg_s", g.max_turn_rate_deg_s),
            ("log.extrinsics_tolerance_m", g.extrinsics_tolerance_m),
            ("log.extrinsics_tolerance_deg", g.extrinsics_tolerance_deg),
            ("log.far_delay_s", g.far_delay_s),
        ] {
            if finite(name, v)? <= 0.0 {
                return Err(err(name, format!("must be > 0, got {v}")));
            }
        }
        if finite("log.reorder_window_s", g.reorder_window_s)? < 0.0 {
            return Err(err("log.reorder_window_s", format!("must be >= 0, got {}", g.reorder_window_s)));
        }
        if g.base_frame.trim().is_empty() {
            return Err(err("log.base_frame", "must not be empty"));
        }
        let disabled_kinds = SensorKind::ALL
            .into_iter()
            .filter(|k| {
                let mut listed = self.sensor.iter().filter(|s| s.kind == *k);
                listed.clone().next().is_some() && listed.all(|s| !s.enabled)
            })
            .collect();
        let classes = camera::class_table(&self.class)?;
        self.estimator.validate()?;
        let dynamic = self.fusion.validate(occ_t)?;
        let mut slam = self.slam.validate()?;
        let motion = g.motion_limits();
        (slam.max_track_speed_m_s, slam.max_track_turn_rate_rad_s) = (motion.max_speed_m_s, motion.max_turn_rate_rad_s);
        let limits = self.limits;
        limits.validate()?;
        for (i, l) in lidars.iter().enumerate() {
            limits.check_ray(
                &lidar_key(&self.sensor, i, "max_range"),
                l.model.params().max_range,
                "map.resolution",
                res,
            )?;
        }
        for (i, c) in cameras.iter().enumerate() {
            limits.check_ray(&camera_key(&self.sensor, i), c.params.max_depth_m, "map.resolution", res)?;
        }
        limits.check_ray("slam.max_range_m", slam.max_range_m, "slam.resolution_m", slam.resolution)?;
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
        Ok(Plan {
            geometry,
            occupancy,
            lidars,
            sensors,
            cameras,
            classes,
            disabled_kinds,
            log: g.clone(),
            estimator: self.estimator.clone(),
            fusion: self.fusion.clone(),
            dynamic,
            slam_mode: self.slam.mode,
            slam,
            limits,
        })
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
mod tests {
    use super::*;
    use crate::geometry::Mount3;

    #[test]
    fn unlisted_kinds_are_auto_and_disabled_lidars_are_not_mapped() {
        let p = Config::default().validate().unwrap();
        assert_eq!(p.lidars.len(), 1);
        assert!(!p.lidars[0].explicit && p.lidars[0].topic.is_none());
        assert!(p.sensors.is_empty());
        let c = Config {
            sensor: vec![
                SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Lidar) },
                SensorConfig { topic: Some("/wheels".into()), ..SensorConfig::new(SensorKind::WheelOdometry) },
            ],
            ..Default::default()
        };
        let p = c.validate().unwrap();
        assert!(p.lidars.is_empty());
        assert_eq!(p.sensors.len(), 1);
        assert_eq!(p.sensors[0].topic.as_deref(), Some("/wheels"));
        assert_eq!(p.sensors[0].name, "wheel_odometry");
        assert!(auto_sensor(SensorKind::Imu).is_some_and(|s| !s.explicit));
        assert!(auto_sensor(SensorKind::Lidar).is_none());
    }

    #[test]
    fn defaults_are_the_documents() {
        let p = Config::default().validate().unwrap();
        assert_eq!(p.geometry.resolution(), 0.05);
        assert_eq!(p.occupancy.prior, 0.5);
        let (name, m) = (&p.lidars[0].name, &p.lidars[0].model);
        assert_eq!(name, "laser");
        assert_eq!(m.params().p_occ, 0.9);
        assert_eq!(m.params().p_free, 0.4);
        assert_eq!(m.params().min_range, 0.1);
        assert_eq!(m.params().max_range, 10.0);
    }

    fn field_of(c: Config) -> String {
        c.validate().unwrap_err().field
    }

    #[test]
    fn each_rule_names_its_field() {
        let mut c = Config::default();
        c.map.resolution = 0.0;
        assert_eq!(field_of(c), "map.resolution");
        let mut c = Config::default();
        c.map.prior = 1.0;
        assert_eq!(field_of(c), "map.prior");
        let mut c = Config::default();
        c.sensor.push(SensorConfig { p_occ: Some(0.45), ..SensorConfig::new(SensorKind::Lidar) });
        assert_eq!(field_of(c), "sensor[0].p_occ");
        // Two tables of one kind on one topic (a thousand GNSS sensors on `/fix`).
        let mut c = Config::default();
        let fix = SensorConfig { topic: Some("/fix".into()), ..SensorConfig::new(SensorKind::Gnss) };
        c.sensor.extend([
            fix.clone(),
            SensorConfig { topic: Some("/odom".into()), ..SensorConfig::new(SensorKind::WheelOdometry) },
            fix.clone(),
        ]);
        assert_eq!(field_of(c.clone()), "sensor[2].topic");
        c.sensor[0].enabled = false;
        assert!(c.validate().is_ok(), "a disabled table reads nothing");
        let lidar = |f: fn(&mut SensorConfig)| {
            let mut c = Config::default();
            let mut s = SensorConfig::new(SensorKind::Lidar);
            f(&mut s);
            c.sensor.push(s);
            field_of(c)
        };
        assert_eq!(lidar(|s| s.p_free = Some(0.5)), "sensor[0].p_free");
        let far = Mount3 { x: 1e300, ..Default::default() };
        assert_eq!(
            lidar(|s| s.base_from_sensor = Some(Mount3 { x: 1e300, ..Default::default() })),
            "sensor[0].base_from_sensor.x"
        );
        let mut c = Config::default();
        c.sensor.push(SensorConfig { base_from_sensor: Some(far), ..SensorConfig::new(SensorKind::Imu) });
        assert_eq!(field_of(c), "sensor[0].base_from_sensor.x");
        assert_eq!(lidar(|s| s.max_range = Some(0.05)), "sensor[0].max_range");
        assert_eq!(lidar(|s| s.min_range = Some(f64::NAN)), "sensor[0].min_range");
        assert_eq!(
            lidar(|s| s.base_from_sensor = Some(Mount3 { pitch: 0.5, ..Default::default() })),
            "sensor[0].base_from_sensor"
        );
        assert_eq!(lidar(|s| s.gyro_noise_rad_s = Some(0.1)), "sensor[0].gyro_noise_rad_s");
        assert_eq!(lidar(|s| s.time_offset_s = f64::INFINITY), "sensor[0].time_offset_s");
        let mut c = Config::default();
        c.map.clamp_max = 0.4;
        assert_eq!(field_of(c), "map");
        let mut c = Config::default();
        c.map.free_threshold = 0.7;
        assert_eq!(field_of(c), "map.free_threshold");
        let mut c = Config {
            sensor: vec![SensorConfig::new(SensorKind::Lidar), SensorConfig::new(SensorKind::Lidar)],
            ..Default::default()
        };
        c.sensor[1].name = Some("laser".into());
        assert_eq!(field_of(c), "sensor[1].name");
        let c = Config {
            sensor: vec![SensorConfig { datum: Some([91.0, 0.0, 0.0]), ..SensorConfig::new(SensorKind::Gnss) }],
            ..Default::default()
        };
        assert_eq!(field_of(c), "sensor[0].datum");
        let mut c = Config::default();
        c.log.max_pose_gap_s = 0.0;
        assert_eq!(field_of(c), "log.max_pose_gap_s");
        let mut c = Config::default();
        c.log.base_frame = " ".into();
        assert_eq!(field_of(c), "log.base_frame");
        let mut c = Config::default();
        c.estimator.gate_probability = 1.5;
        assert_eq!(field_of(c), "estimator.gate_probability");
        let mut c = Config::default();
        c.log.gap_bridge_motion_m = -1.0;
        assert_eq!(field_of(c), "log.gap_bridge_motion_m");
        let map = |f: fn(&mut PassThroughParams)| {
            let mut c = Config::default();
            f(&mut c.map.pass_through);
            field_of(c)
        };
        assert_eq!(map(|p| p.weight = 1.5), "map.pass_through.weight");
        assert_eq!(map(|p| p.threshold = 0.3), "map.pass_through.threshold");
        assert_eq!(map(|p| p.threshold = f64::NAN), "map.pass_through.threshold");
        assert_eq!(map(|p| p.margin_cells = 1_000_000), "map.pass_through.margin_cells");
        let filters = |f: fn(&mut crate::sensor::ScanFilters)| {
            let mut filters = crate::sensor::ScanFilters::default();
            f(&mut filters);
            let mut c = Config::default();
            c.sensor.push(SensorConfig { filters: Some(filters), ..SensorConfig::new(SensorKind::Lidar) });
            field_of(c)
        };
        assert_eq!(filters(|f| f.speckle.window = 0), "sensor[0].filters.speckle.window");
        assert_eq!(filters(|f| f.self_box.max = [-1.0, 0.0]), "sensor[0].filters.box");
        let c = Config {
            sensor: vec![SensorConfig {
                filters: Some(crate::sensor::ScanFilters::default()),
                ..SensorConfig::new(SensorKind::Imu)
            }],
            ..Default::default()
        };
        assert_eq!(field_of(c), "sensor[0].filters");
    }

    #[test]
    fn a_configured_map_handles_pass_throughs_and_the_core_default_does_not() {
        let plan = Config::default().validate().unwrap();
        assert_eq!(plan.occupancy.pass_through, PassThroughParams::default());
        assert!(!plan.occupancy.pass_through.is_off());
        assert!(OccupancyParams::default().pass_through.is_off());
        // Filters are off by default everywhere (lossless on the corrected CARMEN logs).
        assert!(!plan.lidars[0].model.params().filters.any());
    }
}
