//! One `[[sensor]]` table per sensor: what it is, where its messages are, where it sits on
//! the robot, how its clock is off, and the noise to assume where its messages carry none.
//!
//! Every kind shares `kind`, `name`, `topic`, `frame`, `enabled`, `time_offset_s` and
//! `base_from_sensor`; the other keys belong to one kind each, and a key given for the
//! wrong kind is an error naming it (a `p_occ` on an IMU is a mistake, not a no-op).
//!
//! Kinds not listed at all are looked for in the log under their usual topics (`/scan` or
//! the log's only scan topic, `/odom`, `/imu`, `/fix`), so a log with no config still maps
//! (a camera on `/camera/labels`, `/camera/depth` and `/camera/camera_info`);
//! a kind that is listed is used exactly as written (its topic must be in the log), and
//! `enabled = false` switches a kind off, auto-detection included.

use crate::geometry::{Mount3, PlanarMount};
use crate::sensor::{LidarModel, LidarParams, MaxRangePolicy, ScanFilters};
use serde::{Deserialize, Serialize};

use super::{check_mount, err, finite, probability, FieldError};

/// What a sensor is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorKind {
    /// A 2D lidar (`sensor_msgs/LaserScan`, CARMEN laser lines): mapped.
    Lidar,
    /// Wheel odometry (`nav_msgs/Odometry`, CARMEN `ODOM`): predicts the pose.
    WheelOdometry,
    /// An IMU (`sensor_msgs/Imu`): its gyro corrects the heading rate.
    Imu,
    /// A GNSS/RTK receiver (`sensor_msgs/NavSatFix`): absolute position fixes.
    Gnss,
    /// Absolute poses (`geometry_msgs/PoseWithCovarianceStamped`), e.g. from a localiser.
    Pose,
    /// A semantic camera: a class-label image, an aligned depth image and their
    /// `CameraInfo` ([`CameraModel`](crate::sensor::CameraModel)). Never auto-detected.
    Camera,
}

impl SensorKind {
    /// Every kind, in table order.
    pub const ALL: [SensorKind; 6] = [
        SensorKind::Lidar,
        SensorKind::WheelOdometry,
        SensorKind::Imu,
        SensorKind::Gnss,
        SensorKind::Pose,
        SensorKind::Camera,
    ];

    /// The config spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            SensorKind::Lidar => "lidar",
            SensorKind::WheelOdometry => "wheel_odometry",
            SensorKind::Imu => "imu",
            SensorKind::Gnss => "gnss",
            SensorKind::Pose => "pose",
            SensorKind::Camera => "camera",
        }
    }

    /// The name a sensor of this kind gets when the config gives none (`laser` for a
    /// lidar, as CARMEN and ROS drivers call it).
    pub fn default_name(self) -> &'static str {
        match self {
            SensorKind::Lidar => "laser",
            k => k.as_str(),
        }
    }

    /// The topic looked for when the config names none (for a camera, its label images).
    pub fn default_topic(self) -> &'static str {
        match self {
            SensorKind::Lidar => "/scan",
            SensorKind::WheelOdometry => "/odom",
            SensorKind::Imu => "/imu",
            SensorKind::Gnss => "/fix",
            SensorKind::Pose => "/pose",
            SensorKind::Camera => "/camera/labels",
        }
    }
}

/// One `[[sensor]]` table as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    /// `lidar`, `wheel_odometry`, `imu`, `gnss`, `pose` or `camera`.
    pub kind: SensorKind,
    /// A name for reports; default: the kind, numbered when repeated.
    #[serde(default)]
    pub name: Option<String>,
    /// The topic (ROS) or message type (CARMEN); default: the kind's usual topic, or the
    /// log's only topic of that kind.
    #[serde(default)]
    pub topic: Option<String>,
    /// The sensor's frame id; default: the `header.frame_id` of its messages.
    #[serde(default)]
    pub frame: Option<String>,
    /// `false` ignores the sensor (and stops its kind being auto-detected).
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Seconds added to every stamp of this sensor (a known clock offset; the knob a time
    /// calibration turns).
    #[serde(default)]
    pub time_offset_s: f64,
    /// The mount `base_from_sensor` (for a camera: `base_from_camera_optical`, the optical
    /// frame of REP 103). Given, it is checked against the log's TF; left out, the log's TF
    /// is used, else identity (for a camera: a level forward camera at the base origin).
    #[serde(default)]
    pub base_from_sensor: Option<Mount3>,

    /// Lidar: occupancy probability of a beam's end cell.
    #[serde(default)]
    pub p_occ: Option<f64>,
    /// Lidar: occupancy probability of a crossed cell.
    #[serde(default)]
    pub p_free: Option<f64>,
    /// Lidar: shortest valid range, metres.
    #[serde(default)]
    pub min_range: Option<f64>,
    /// Lidar: longest valid range, metres (exclusive).
    #[serde(default)]
    pub max_range: Option<f64>,
    /// Lidar: `skip` or `clear`.
    #[serde(default)]
    pub max_range_policy: Option<MaxRangePolicy>,
    /// Lidar: largest tilt of the scan plane accepted, degrees.
    #[serde(default)]
    pub max_tilt_deg: Option<f64>,
    /// Lidar: the scan filters (`[sensor.filters.shadow]`, `.speckle`, `.angular_bounds`,
    /// `.box`); a filter table left out keeps that filter's defaults.
    #[serde(default)]
    pub filters: Option<ScanFilters>,

    /// Wheel odometry: translation σ after one metre, per axis, m/√m (default: the
    /// estimator's `odometry_translation_noise`).
    #[serde(default)]
    pub translation_noise_per_sqrt_m: Option<f64>,
    /// Wheel odometry: heading σ per radian turned, rad/√rad.
    #[serde(default)]
    pub rotation_noise_per_sqrt_rad: Option<f64>,
    /// Wheel odometry: heading σ per metre driven, rad/√m.
    #[serde(default)]
    pub rotation_noise_per_sqrt_m: Option<f64>,

    /// IMU: gyro rate σ, rad/s, where the message has no covariance (default: the
    /// estimator's `gyro_rate_sigma`).
    #[serde(default)]
    pub gyro_noise_rad_s: Option<f64>,
    /// IMU: use the message's orientation yaw when it provides one (REP 145).
    #[serde(default)]
    pub use_orientation: Option<bool>,

    /// GNSS: the local map frame's origin `[latitude°, longitude°, altitude m]`; default:
    /// the first good fix.
    #[serde(default)]
    pub datum: Option<[f64; 3]>,
    /// GNSS: smallest σ accepted for an RTK (`STATUS_GBAS_FIX`) fix, metres.
    #[serde(default)]
    pub sigma_floor_rtk_m: Option<f64>,
    /// GNSS: smallest σ accepted for an SBAS fix, metres.
    #[serde(default)]
    pub sigma_floor_sbas_m: Option<f64>,
    /// GNSS: smallest σ accepted for a plain fix, metres.
    #[serde(default)]
    pub sigma_floor_fix_m: Option<f64>,
    /// GNSS: σ used when the message says its covariance is unknown, metres.
    #[serde(default)]
    pub sigma_unknown_m: Option<f64>,
    /// GNSS: the altitudes a fix may have, `[lowest, highest]` metres above the WGS 84
    /// ellipsoid; fixes outside are dropped as receiver faults (default
    /// [`crate::estimator::DEFAULT_ALTITUDE_RANGE_M`]).
    #[serde(default)]
    pub altitude_range_m: Option<[f64; 2]>,

    /// Pose: position σ where the message's covariance is zero or unusable, metres
    /// (default: the estimator's `fallback_pose_sigma_m`).
    #[serde(default)]
    pub position_noise_m: Option<f64>,
    /// Pose: yaw σ where the message's covariance is zero or unusable, degrees.
    #[serde(default)]
    pub yaw_noise_deg: Option<f64>,

    /// Camera: the aligned depth images' topic (default `/camera/depth`).
    #[serde(default)]
    pub depth_topic: Option<String>,
    /// Camera: the `CameraInfo` topic (default `/camera/camera_info`).
    #[serde(default)]
    pub info_topic: Option<String>,
    /// Camera: use every `stride`-th pixel of every `stride`-th row.
    #[serde(default)]
    pub stride: Option<u32>,
    /// Camera: shortest depth used, metres.
    #[serde(default)]
    pub min_depth_m: Option<f64>,
    /// Camera: longest depth used, metres.
    #[serde(default)]
    pub max_depth_m: Option<f64>,
    /// Camera: `k` of the depth noise `σ = k·d²`, 1/m.
    #[serde(default)]
    pub depth_sigma_k: Option<f64>,
    /// Camera: base-frame height below which a point is floor, metres.
    #[serde(default)]
    pub floor_band_m: Option<f64>,
    /// Camera: top of the obstacle band, metres.
    #[serde(default)]
    pub obstacle_max_z_m: Option<f64>,
    /// Camera: occupancy probability of a cell a camera ray crossed (its weak free
    /// evidence).
    #[serde(default)]
    pub camera_p_free: Option<f64>,
    /// Camera: factor on every occupancy contribution of the camera.
    #[serde(default)]
    pub occupancy_weight: Option<f64>,
    /// Camera: factor on the semantic weight of a label contradicting its point's height.
    #[serde(default)]
    pub inconsistent_label_weight: Option<f64>,
    /// Camera: largest stamp difference of a label image and the depth image it is paired
    /// with, seconds.
    #[serde(default)]
    pub pair_tolerance_s: Option<f64>,
}

fn yes() -> bool {
    true
}

impl SensorConfig {
    /// A table of `kind` with every key at its default.
    pub fn new(kind: SensorKind) -> Self {
        Self {
            kind,
            name: None,
            topic: None,
            frame: None,
            enabled: true,
            time_offset_s: 0.0,
            base_from_sensor: None,
            p_occ: None,
            p_free: None,
            min_range: None,
            max_range: None,
            max_range_policy: None,
            max_tilt_deg: None,
            filters: None,
            translation_noise_per_sqrt_m: None,
            rotation_noise_per_sqrt_rad: None,
            rotation_noise_per_sqrt_m: None,
            gyro_noise_rad_s: None,
            use_orientation: None,
            datum: None,
            sigma_floor_rtk_m: None,
            sigma_floor_sbas_m: None,
            sigma_floor_fix_m: None,
            sigma_unknown_m: None,
            altitude_range_m: None,
            position_noise_m: None,
            yaw_noise_deg: None,
            depth_topic: None,
            info_topic: None,
            stride: None,
            min_depth_m: None,
            max_depth_m: None,
            depth_sigma_k: None,
            floor_band_m: None,
            obstacle_max_z_m: None,
            camera_p_free: None,
            occupancy_weight: None,
            inconsistent_label_weight: None,
            pair_tolerance_s: None,
        }
    }

    /// The keys given that belong to another kind, by name.
    pub(super) fn foreign_keys(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        let mut check = |given: bool, key: &'static str, kind: SensorKind| {
            if given && self.kind != kind {
                v.push(key);
            }
        };
        check(self.p_occ.is_some(), "p_occ", SensorKind::Lidar);
        check(self.p_free.is_some(), "p_free", SensorKind::Lidar);
        check(self.min_range.is_some(), "min_range", SensorKind::Lidar);
        check(self.max_range.is_some(), "max_range", SensorKind::Lidar);
        check(self.max_range_policy.is_some(), "max_range_policy", SensorKind::Lidar);
        check(self.max_tilt_deg.is_some(), "max_tilt_deg", SensorKind::Lidar);
        check(self.filters.is_some(), "filters", SensorKind::Lidar);
        let odo = SensorKind::WheelOdometry;
        check(self.translation_noise_per_sqrt_m.is_some(), "translation_noise_per_sqrt_m", odo);
        check(self.rotation_noise_per_sqrt_rad.is_some(), "rotation_noise_per_sqrt_rad", odo);
        check(self.rotation_noise_per_sqrt_m.is_some(), "rotation_noise_per_sqrt_m", odo);
        check(self.gyro_noise_rad_s.is_some(), "gyro_noise_rad_s", SensorKind::Imu);
        check(self.use_orientation.is_some(), "use_orientation", SensorKind::Imu);
        let g = SensorKind::Gnss;
        check(self.datum.is_some(), "datum", g);
        check(self.sigma_floor_rtk_m.is_some(), "sigma_floor_rtk_m", g);
        check(self.sigma_floor_sbas_m.is_some(), "sigma_floor_sbas_m", g);
        check(self.sigma_floor_fix_m.is_some(), "sigma_floor_fix_m", g);
        check(self.sigma_unknown_m.is_some(), "sigma_unknown_m", g);
        check(self.altitude_range_m.is_some(), "altitude_range_m", g);
        check(self.position_noise_m.is_some(), "position_noise_m", SensorKind::Pose);
        check(self.yaw_noise_deg.is_some(), "yaw_noise_deg", SensorKind::Pose);
        let c = SensorKind::Camera;
        check(self.depth_topic.is_some(), "depth_topic", c);
        check(self.info_topic.is_some(), "info_topic", c);
        check(self.stride.is_some(), "stride", c);
        check(self.min_depth_m.is_some(), "min_depth_m", c);
        check(self.max_depth_m.is_some(), "max_depth_m", c);
        check(self.depth_sigma_k.is_some(), "depth_sigma_k", c);
        check(self.floor_band_m.is_some(), "floor_band_m", c);
        check(self.obstacle_max_z_m.is_some(), "obstacle_max_z_m", c);
        check(self.camera_p_free.is_some(), "camera_p_free", c);
        check(self.occupancy_weight.is_some(), "occupancy_weight", c);
        check(self.inconsistent_label_weight.is_some(), "inconsistent_label_weight", c);
        check(self.pair_tolerance_s.is_some(), "pair_tolerance_s", c);
        v
    }
}

/// Noise figures of a wheel odometry where its messages carry none: σ growing with the
/// square root of distance and rotation (a random walk per metre and per radian, the
/// continuous form of Thrun et al., *Probabilistic Robotics* §5.4). `None`: the
/// estimator's default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OdometryNoise {
    /// Translation σ after one metre, m/√m.
    pub translation_per_sqrt_m: Option<f64>,
    /// Heading σ per radian turned, rad/√rad.
    pub rotation_per_sqrt_rad: Option<f64>,
    /// Heading σ per metre driven, rad/√m.
    pub rotation_per_sqrt_m: Option<f64>,
}

/// GNSS σ floors by fix status (the estimator's measurement model).
pub use crate::estimator::GnssNoise;

/// What a sensor adds to a run, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedSensor {
    /// Its kind.
    pub kind: SensorKind,
    /// Its name.
    pub name: String,
    /// The configured topic; `None`: look for the kind's usual one.
    pub topic: Option<String>,
    /// The configured frame id.
    pub frame: Option<String>,
    /// Seconds added to its stamps.
    pub time_offset_s: f64,
    /// The configured mount.
    pub base_from_sensor: Option<Mount3>,
    /// Odometry noise (kind `wheel_odometry`).
    pub odometry: OdometryNoise,
    /// Gyro σ, rad/s (kind `imu`; `None`: the estimator's default).
    pub gyro_noise_rad_s: Option<f64>,
    /// Whether to use IMU orientation (kind `imu`).
    pub use_orientation: bool,
    /// The GNSS datum, if configured.
    pub datum: Option<[f64; 3]>,
    /// GNSS σ floors.
    pub gnss: GnssNoise,
    /// The altitudes a GNSS fix may have, `[lowest, highest]` metres.
    pub altitude_range_m: [f64; 2],
    /// Pose σ fallbacks: position m, yaw rad (`None`: the estimator's defaults).
    pub pose_noise: (Option<f64>, Option<f64>),
    /// `true` when the table was written in the config, `false` when auto-detected.
    pub explicit: bool,
}

/// A lidar of the plan.
#[derive(Clone, Debug)]
pub struct PlannedLidar {
    /// Its name.
    pub name: String,
    /// The inverse model with the mount reduced to the plane.
    pub model: LidarModel,
    /// The full 3D mount (identity when none was configured).
    pub mount: Mount3,
    /// Whether the mount was written in the config (then checked against the log's TF).
    pub mount_given: bool,
    /// Largest accepted tilt, radians.
    pub max_tilt: f64,
    /// The configured topic; `None`: auto.
    pub topic: Option<String>,
    /// The configured frame id.
    pub frame: Option<String>,
    /// Seconds added to its stamps.
    pub time_offset_s: f64,
    /// `true` when written in the config.
    pub explicit: bool,
}

pub(super) fn plan_lidar(i: usize, s: &SensorConfig, name: String, prior: f64) -> Result<PlannedLidar, FieldError> {
    let f = |name: &str| format!("sensor[{i}].{name}");
    let d = LidarParams::default();
    let p_occ = probability(&f("p_occ"), s.p_occ.unwrap_or(d.p_occ))?;
    let p_free = probability(&f("p_free"), s.p_free.unwrap_or(d.p_free))?;
    if p_occ <= prior {
        return Err(err(f("p_occ"), format!("must be above the prior {prior}, got {p_occ}")));
    }
    if p_free >= prior {
        return Err(err(f("p_free"), format!("must be below the prior {prior}, got {p_free}")));
    }
    let min_r = finite(&f("min_range"), s.min_range.unwrap_or(d.min_range))?;
    let max_r = finite(&f("max_range"), s.max_range.unwrap_or(d.max_range))?;
    if min_r < 0.0 {
        return Err(err(f("min_range"), format!("must be >= 0, got {min_r}")));
    }
    if min_r >= max_r {
        return Err(err(f("max_range"), format!("must be above min_range ({min_r}), got {max_r}")));
    }
    let tilt = finite(&f("max_tilt_deg"), s.max_tilt_deg.unwrap_or(2.0))?;
    if !(0.0..=90.0).contains(&tilt) {
        return Err(err(f("max_tilt_deg"), format!("must be within [0, 90] degrees, got {tilt}")));
    }
    let mount3 = s.base_from_sensor.unwrap_or_default();
    check_mount(f, &mount3)?;
    let mount: PlanarMount =
        mount3.to_planar(tilt.to_radians()).map_err(|e| err(f("base_from_sensor"), e.to_string()))?;
    let params = LidarParams {
        p_occ,
        p_free,
        min_range: min_r,
        max_range: max_r,
        max_range_policy: s.max_range_policy.unwrap_or(d.max_range_policy),
        filters: s.filters.unwrap_or_default(),
    };
    params.filters.validate().map_err(|e| e.within(&f("filters")))?;
    Ok(PlannedLidar {
        name,
        model: LidarModel::new(params, mount),
        mount: mount3,
        mount_given: s.base_from_sensor.is_some(),
        max_tilt: tilt.to_radians(),
        topic: s.topic.clone(),
        frame: s.frame.clone(),
        time_offset_s: s.time_offset_s,
        explicit: true,
    })
}

/// The lidar mapped when the config lists none: the document's inverse model (§3.2),
/// identity mount, its topic found in the log.
pub(super) fn default_lidar() -> PlannedLidar {
    let d = LidarParams::default();
    PlannedLidar {
        name: SensorKind::Lidar.default_name().into(),
        model: LidarModel::new(d, PlanarMount::default()),
        mount: Mount3::default(),
        mount_given: false,
        max_tilt: 2f64.to_radians(),
        topic: None,
        frame: None,
        time_offset_s: 0.0,
        explicit: false,
    }
}
