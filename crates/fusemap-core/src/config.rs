//! The run configuration: the design document's parameter table (§4.2) as one typed
//! value, and its validation.
//!
//! Parsing (TOML) lives in `fusemap-io`; this module only says what a valid
//! configuration is. Unknown keys are refused at parse time (`deny_unknown_fields`), so a
//! misspelt `p_ocupied` is an error and not a silently ignored line. Every validation
//! error names the field, in the path form the TOML file uses (`lidar[0].p_occ`).

use crate::geometry::{Mount3, PlanarMount, Point2};
use crate::grid::{GridGeometry, OccupancyParams};
use crate::sensor::{LidarModel, LidarParams, MaxRangePolicy};
use serde::{Deserialize, Serialize};

/// The whole configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The map.
    #[serde(default)]
    pub map: MapConfig,
    /// The lidars (one table per sensor: `[[lidar]]`).
    #[serde(default = "default_lidars")]
    pub lidar: Vec<LidarConfig>,
    /// How robot logs are read: topics, pose source, time synchronisation.
    #[serde(default)]
    pub log: LogConfig,
}

impl Default for Config {
    fn default() -> Self {
        Self { map: MapConfig::default(), lidar: default_lidars(), log: LogConfig::default() }
    }
}

/// Where a log's scans get their poses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseSource {
    /// The pose written on the scan line if the log has one (CARMEN), else the odometry
    /// topic, else TF to the base frame.
    #[default]
    Auto,
    /// The pose on each scan line (CARMEN corrected logs).
    ScanLine,
    /// The odometry topic, interpolated at each scan's stamp.
    Odometry,
    /// Dynamic TF transforms to the base frame, interpolated at each scan's stamp.
    Tf,
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
    /// The LaserScan topic (ROS logs). If absent from the log and the log has exactly one
    /// scan topic, that one is used.
    pub scan_topic: String,
    /// The odometry topic (ROS logs).
    pub odom_topic: String,
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
}

impl Default for LogConfig {
    fn default() -> Self {
        Self {
            scan_topic: "/scan".into(),
            odom_topic: "/odom".into(),
            base_frame: "base_link".into(),
            pose_source: PoseSource::Auto,
            sync: SyncConfig::Interpolate,
            nearest_tolerance_s: 0.0,
            max_pose_gap_s: 0.5,
            gap_bridge_motion_m: 0.05,
            gap_bridge_motion_deg: 2.0,
            deskew: true,
            extrinsics: ExtrinsicsSource::Auto,
            extrinsics_tolerance_m: 0.02,
            extrinsics_tolerance_deg: 1.0,
            far_delay_s: 1.0,
        }
    }
}

fn default_lidars() -> Vec<LidarConfig> {
    vec![LidarConfig::default()]
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
        }
    }
}

/// One lidar: its inverse model and its mount.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LidarConfig {
    /// Name (the frame id of its messages).
    pub name: String,
    /// Occupancy probability of a beam's end cell.
    pub p_occ: f64,
    /// Occupancy probability of a crossed cell.
    pub p_free: f64,
    /// Shortest valid range, metres.
    pub min_range: f64,
    /// Longest valid range, metres (exclusive).
    pub max_range: f64,
    /// `skip` or `clear`.
    pub max_range_policy: MaxRangePolicy,
    /// Largest tilt of the scan plane from horizontal accepted, degrees.
    pub max_tilt_deg: f64,
    /// `base_from_sensor`.
    pub mount: Mount3,
}

impl Default for LidarConfig {
    fn default() -> Self {
        let p = LidarParams::default();
        Self {
            name: "laser".into(),
            p_occ: p.p_occ,
            p_free: p.p_free,
            min_range: p.min_range,
            max_range: p.max_range,
            max_range_policy: p.max_range_policy,
            max_tilt_deg: 2.0,
            mount: Mount3::default(),
        }
    }
}

/// A configuration error, naming the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ConfigError {
    /// The field, as a TOML path (`map.prior`, `lidar[0].mount`).
    pub field: String,
    /// What is wrong with it.
    pub message: String,
}

fn err(field: impl Into<String>, message: impl Into<String>) -> ConfigError {
    ConfigError { field: field.into(), message: message.into() }
}

fn finite(field: &str, v: f64) -> Result<f64, ConfigError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(field, format!("must be a finite number, got {v}")))
    }
}

fn probability(field: &str, v: f64) -> Result<f64, ConfigError> {
    finite(field, v)?;
    if v > 0.0 && v < 1.0 {
        Ok(v)
    } else {
        Err(err(field, format!("must be a probability strictly between 0 and 1, got {v}")))
    }
}

/// One validated lidar.
#[derive(Clone, Debug)]
pub struct PlannedLidar {
    /// Name (frame id).
    pub name: String,
    /// The inverse model with the planar mount.
    pub model: LidarModel,
    /// The mount as configured (3D).
    pub mount: Mount3,
    /// Largest accepted scan-plane tilt, radians.
    pub max_tilt: f64,
}

/// A validated configuration, ready to build a map and sensor models.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The grid's placement.
    pub geometry: GridGeometry,
    /// The grid's probabilities.
    pub occupancy: OccupancyParams,
    /// Each lidar: name, model and the 3D mount it was reduced from.
    pub lidars: Vec<PlannedLidar>,
    /// How logs are read.
    pub log: LogConfig,
}

impl Config {
    /// Checks every field and builds the plan. The first problem found is returned.
    pub fn validate(&self) -> Result<Plan, ConfigError> {
        let m = &self.map;
        let res = finite("map.resolution", m.resolution)?;
        if res <= 0.0 {
            return Err(err("map.resolution", format!("must be > 0 metres, got {res}")));
        }
        let geometry = match m.origin {
            Some([x, y]) => {
                finite("map.origin", x)?;
                finite("map.origin", y)?;
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
        let occupancy = OccupancyParams {
            prior,
            clamp_min: cmin,
            clamp_max: cmax,
            occupied_threshold: occ_t,
            free_threshold: free_t,
        };

        if self.lidar.is_empty() {
            return Err(err("lidar", "at least one [[lidar]] table is needed"));
        }
        let mut lidars = Vec::new();
        for (i, l) in self.lidar.iter().enumerate() {
            let f = |name: &str| format!("lidar[{i}].{name}");
            if l.name.trim().is_empty() {
                return Err(err(f("name"), "must not be empty"));
            }
            if self.lidar[..i].iter().any(|o| o.name == l.name) {
                return Err(err(f("name"), format!("`{}` is used by two lidars", l.name)));
            }
            let p_occ = probability(&f("p_occ"), l.p_occ)?;
            let p_free = probability(&f("p_free"), l.p_free)?;
            if p_occ <= prior {
                return Err(err(f("p_occ"), format!("must be above the prior {prior}, got {p_occ}")));
            }
            if p_free >= prior {
                return Err(err(f("p_free"), format!("must be below the prior {prior}, got {p_free}")));
            }
            let min_r = finite(&f("min_range"), l.min_range)?;
            let max_r = finite(&f("max_range"), l.max_range)?;
            if min_r < 0.0 {
                return Err(err(f("min_range"), format!("must be >= 0, got {min_r}")));
            }
            if min_r >= max_r {
                return Err(err(f("max_range"), format!("must be above min_range ({min_r}), got {max_r}")));
            }
            let tilt = finite(&f("max_tilt_deg"), l.max_tilt_deg)?;
            if !(0.0..=90.0).contains(&tilt) {
                return Err(err(f("max_tilt_deg"), format!("must be within [0, 90] degrees, got {tilt}")));
            }
            let mount: PlanarMount =
                l.mount.to_planar(tilt.to_radians()).map_err(|e| err(f("mount"), e.to_string()))?;
            let params =
                LidarParams { p_occ, p_free, min_range: min_r, max_range: max_r, max_range_policy: l.max_range_policy };
            lidars.push(PlannedLidar {
                name: l.name.clone(),
                model: LidarModel::new(params, mount),
                mount: l.mount,
                max_tilt: tilt.to_radians(),
            });
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
            ("log.extrinsics_tolerance_m", g.extrinsics_tolerance_m),
            ("log.extrinsics_tolerance_deg", g.extrinsics_tolerance_deg),
            ("log.far_delay_s", g.far_delay_s),
        ] {
            if finite(name, v)? <= 0.0 {
                return Err(err(name, format!("must be > 0, got {v}")));
            }
        }
        for (name, v) in
            [("log.scan_topic", &g.scan_topic), ("log.odom_topic", &g.odom_topic), ("log.base_frame", &g.base_frame)]
        {
            if v.trim().is_empty() {
                return Err(err(name, "must not be empty"));
            }
        }
        Ok(Plan { geometry, occupancy, lidars, log: g.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        c.lidar[0].p_occ = 0.45;
        assert_eq!(field_of(c), "lidar[0].p_occ");
        let mut c = Config::default();
        c.lidar[0].p_free = 0.5;
        assert_eq!(field_of(c), "lidar[0].p_free");
        let mut c = Config::default();
        c.lidar[0].max_range = 0.05;
        assert_eq!(field_of(c), "lidar[0].max_range");
        let mut c = Config::default();
        c.lidar[0].min_range = f64::NAN;
        assert_eq!(field_of(c), "lidar[0].min_range");
        let mut c = Config::default();
        c.map.clamp_max = 0.4;
        assert_eq!(field_of(c), "map");
        let mut c = Config::default();
        c.lidar[0].mount.pitch = 0.5;
        assert_eq!(field_of(c), "lidar[0].mount");
        let mut c = Config::default();
        c.map.free_threshold = 0.7;
        assert_eq!(field_of(c), "map.free_threshold");
        let mut c = Config::default();
        c.lidar.push(LidarConfig::default());
        assert_eq!(field_of(c), "lidar[1].name");
        let mut c = Config::default();
        c.log.max_pose_gap_s = 0.0;
        assert_eq!(field_of(c), "log.max_pose_gap_s");
        let mut c = Config::default();
        c.log.scan_topic = " ".into();
        assert_eq!(field_of(c), "log.scan_topic");
        let mut c = Config::default();
        c.log.gap_bridge_motion_m = -1.0;
        assert_eq!(field_of(c), "log.gap_bridge_motion_m");
    }
}
