//! Sensor tables of the scenario: rates, noise, the failures the design document names
//! (§2.2), mounts and clock offsets.

use crate::checks::{finite, non_negative, positive, probability};
use crate::world::Rect;
use fusemap_core::field_error::FieldError;
use fusemap_core::geometry::{Datum, Mount3};
use serde::{Deserialize, Serialize};

fn check_mount(field: &str, m: &Mount3) -> Result<(), FieldError> {
    for (k, v) in [("x", m.x), ("y", m.y), ("z", m.z), ("roll", m.roll), ("pitch", m.pitch), ("yaw", m.yaw)] {
        finite(&format!("{field}.{k}"), v)?;
    }
    Ok(())
}

fn check_offset(field: &str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v.abs() <= 10.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be finite and within ±10 s, got {v}")))
    }
}

/// The 2D lidar (`sensor_msgs/LaserScan`, REP 117 for invalid ranges).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LidarConfig {
    /// Topic name.
    pub topic: String,
    /// Scans per second.
    pub rate_hz: f64,
    /// Beams per scan.
    pub beams: usize,
    /// Field of view, degrees, centred on the sensor's x axis: the first beam at
    /// `-fov/2`, the last at `+fov/2` (or one increment short of it for 360°).
    pub fov_deg: f64,
    /// Shortest range reported as valid, metres.
    pub range_min_m: f64,
    /// Longest range; beyond it the beam reports `+inf` (no return, REP 117).
    pub range_max_m: f64,
    /// Time from the first to the last beam of a scan, seconds (the design document's
    /// 50 ms sweep, §4.1); `time_increment = sweep_time_s / (beams - 1)`.
    pub sweep_time_s: f64,
    /// Gaussian range noise σ, metres.
    pub range_noise_std_m: f64,
    /// Probability that a beam meeting glass passes through it.
    pub glass_pass_probability: f64,
    /// Probability that a beam meeting polished steel is reflected specularly and
    /// returns the (longer) length of the bounced path: a flying point.
    pub steel_flying_probability: f64,
    /// Probability that a beam at a depth edge returns a mixed pixel (a range between
    /// foreground and background).
    pub edge_mixed_probability: f64,
    /// Range jump between neighbouring beams that counts as a depth edge, metres.
    pub edge_jump_m: f64,
    /// Probability that a beam reports NaN, `+inf` or 0 (one third each) regardless of
    /// what it hit.
    pub dropout_probability: f64,
    /// `base_link → laser` mount. Must be level (a 2D scan plane).
    pub mount: Mount3,
    /// The sensor clock minus true time, seconds: header stamps are `true time + offset`.
    pub time_offset_s: f64,
}

impl Default for LidarConfig {
    fn default() -> Self {
        Self {
            topic: "/scan".into(),
            rate_hz: 10.0,
            beams: 541,
            fov_deg: 270.0,
            range_min_m: 0.1,
            range_max_m: 20.0,
            sweep_time_s: 0.05,
            range_noise_std_m: 0.01,
            glass_pass_probability: 0.6,
            steel_flying_probability: 0.3,
            edge_mixed_probability: 0.5,
            edge_jump_m: 0.3,
            dropout_probability: 0.01,
            mount: Mount3 { x: 0.25, y: 0.0, z: 0.3, ..Mount3::default() },
            time_offset_s: 0.0,
        }
    }
}

impl LidarConfig {
    /// Angle of the first beam, radians.
    pub fn angle_min(&self) -> f64 {
        -self.fov_deg.to_radians() / 2.0
    }

    /// Angle between beams, radians. A full turn (`fov_deg = 360`) spaces the beams by
    /// `2π / beams` so the last beam does not repeat the first.
    pub fn angle_increment(&self) -> f64 {
        if self.fov_deg >= 360.0 {
            std::f64::consts::TAU / self.beams as f64
        } else if self.beams > 1 {
            self.fov_deg.to_radians() / (self.beams - 1) as f64
        } else {
            0.0
        }
    }

    /// Time between beams, seconds.
    pub fn time_increment(&self) -> f64 {
        if self.beams > 1 {
            self.sweep_time_s / (self.beams - 1) as f64
        } else {
            0.0
        }
    }

    pub(crate) fn validate(&self) -> Result<(), FieldError> {
        positive("lidar.rate_hz", self.rate_hz)?;
        if self.rate_hz > 1000.0 {
            return Err(FieldError::new("lidar.rate_hz", format!("must be at most 1000, got {}", self.rate_hz)));
        }
        if !(1..=100_000).contains(&self.beams) {
            return Err(FieldError::new("lidar.beams", format!("must lie in 1..=100000, got {}", self.beams)));
        }
        positive("lidar.fov_deg", self.fov_deg)?;
        if self.fov_deg > 360.0 {
            return Err(FieldError::new("lidar.fov_deg", format!("must be at most 360, got {}", self.fov_deg)));
        }
        non_negative("lidar.range_min_m", self.range_min_m)?;
        positive("lidar.range_max_m", self.range_max_m)?;
        if self.range_min_m >= self.range_max_m {
            return Err(FieldError::new("lidar.range_min_m", "must be below lidar.range_max_m"));
        }
        non_negative("lidar.sweep_time_s", self.sweep_time_s)?;
        if self.sweep_time_s * self.rate_hz > 1.0 {
            return Err(FieldError::new("lidar.sweep_time_s", "must not exceed the scan period 1 / lidar.rate_hz"));
        }
        non_negative("lidar.range_noise_std_m", self.range_noise_std_m)?;
        probability("lidar.glass_pass_probability", self.glass_pass_probability)?;
        probability("lidar.steel_flying_probability", self.steel_flying_probability)?;
        probability("lidar.edge_mixed_probability", self.edge_mixed_probability)?;
        positive("lidar.edge_jump_m", self.edge_jump_m)?;
        probability("lidar.dropout_probability", self.dropout_probability)?;
        check_mount("lidar.mount", &self.mount)?;
        self.mount.to_planar(1e-6).map_err(|e| FieldError::new("lidar.mount", e.to_string()))?;
        check_offset("lidar.time_offset_s", self.time_offset_s)
    }
}

/// Differential-drive wheel odometry (`nav_msgs/Odometry`, `odom → base_link`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OdometryConfig {
    /// Topic name.
    pub topic: String,
    /// Messages per second.
    pub rate_hz: f64,
    /// Distance between the wheels, metres.
    pub wheel_separation_m: f64,
    /// Reported / true wheel travel everywhere (a wrong wheel radius), e.g. 1.03.
    pub scale_error: f64,
    /// Reported / true travel of the left wheel while it is over a groove (it spins).
    pub slip_factor_left: f64,
    /// Reported / true travel of the right wheel while it is over a groove. Unequal
    /// slip turns the odometry's heading away from the truth.
    pub slip_factor_right: f64,
    /// White noise on each wheel's speed, m/s (per 5 ms integration step).
    pub wheel_noise_std_mps: f64,
    /// The pose covariance diagonal the message reports (x, y, z, roll, pitch, yaw).
    pub pose_covariance_diagonal: [f64; 6],
    /// The twist covariance diagonal the message reports.
    pub twist_covariance_diagonal: [f64; 6],
    /// The sensor clock minus true time, seconds.
    pub time_offset_s: f64,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            topic: "/odom".into(),
            rate_hz: 50.0,
            wheel_separation_m: 0.5,
            scale_error: 1.03,
            slip_factor_left: 1.15,
            slip_factor_right: 1.05,
            wheel_noise_std_mps: 0.02,
            pose_covariance_diagonal: [0.01, 0.01, 1e6, 1e6, 1e6, 0.03],
            twist_covariance_diagonal: [0.002, 0.002, 1e6, 1e6, 1e6, 0.005],
            time_offset_s: 0.0,
        }
    }
}

impl OdometryConfig {
    pub(crate) fn validate(&self) -> Result<(), FieldError> {
        positive("odometry.rate_hz", self.rate_hz)?;
        if self.rate_hz > 200.0 {
            return Err(FieldError::new(
                "odometry.rate_hz",
                format!("must be at most 200 (the truth rate), got {}", self.rate_hz),
            ));
        }
        positive("odometry.wheel_separation_m", self.wheel_separation_m)?;
        positive("odometry.scale_error", self.scale_error)?;
        positive("odometry.slip_factor_left", self.slip_factor_left)?;
        positive("odometry.slip_factor_right", self.slip_factor_right)?;
        non_negative("odometry.wheel_noise_std_mps", self.wheel_noise_std_mps)?;
        for (i, v) in self.pose_covariance_diagonal.iter().enumerate() {
            non_negative(&format!("odometry.pose_covariance_diagonal[{i}]"), *v)?;
        }
        for (i, v) in self.twist_covariance_diagonal.iter().enumerate() {
            non_negative(&format!("odometry.twist_covariance_diagonal[{i}]"), *v)?;
        }
        check_offset("odometry.time_offset_s", self.time_offset_s)
    }
}

/// The IMU (`sensor_msgs/Imu` without orientation, REP 145).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImuConfig {
    /// Topic name.
    pub topic: String,
    /// Messages per second.
    pub rate_hz: f64,
    /// Constant gyro bias about the IMU's z axis, rad/s.
    pub gyro_bias_radps: f64,
    /// Gyro white noise σ per sample, rad/s.
    pub gyro_noise_std_radps: f64,
    /// Constant accelerometer bias (x, y, z), m/s².
    pub accel_bias_mps2: [f64; 3],
    /// Accelerometer white noise σ per sample, m/s².
    pub accel_noise_std_mps2: f64,
    /// `base_link → imu_link` mount.
    pub mount: Mount3,
    /// The sensor clock minus true time, seconds.
    pub time_offset_s: f64,
}

impl Default for ImuConfig {
    fn default() -> Self {
        Self {
            topic: "/imu/data".into(),
            rate_hz: 100.0,
            gyro_bias_radps: 0.005,
            gyro_noise_std_radps: 0.002,
            accel_bias_mps2: [0.05, -0.03, 0.0],
            accel_noise_std_mps2: 0.05,
            mount: Mount3 { x: 0.0, y: 0.0, z: 0.15, ..Mount3::default() },
            time_offset_s: 0.0,
        }
    }
}

impl ImuConfig {
    pub(crate) fn validate(&self) -> Result<(), FieldError> {
        positive("imu.rate_hz", self.rate_hz)?;
        if self.rate_hz > 200.0 {
            return Err(FieldError::new(
                "imu.rate_hz",
                format!("must be at most 200 (the truth rate), got {}", self.rate_hz),
            ));
        }
        finite("imu.gyro_bias_radps", self.gyro_bias_radps)?;
        non_negative("imu.gyro_noise_std_radps", self.gyro_noise_std_radps)?;
        for (i, v) in self.accel_bias_mps2.iter().enumerate() {
            finite(&format!("imu.accel_bias_mps2[{i}]"), *v)?;
        }
        non_negative("imu.accel_noise_std_mps2", self.accel_noise_std_mps2)?;
        check_mount("imu.mount", &self.mount)?;
        check_offset("imu.time_offset_s", self.time_offset_s)
    }
}

/// What a GNSS zone does to the fixes taken inside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ZoneKind {
    /// Multipath / partial sky view: float solution (status FIX), Gauss–Markov
    /// correlated error, occasional unreported outliers.
    Degraded,
    /// No usable satellites: no fix at all.
    Dropout,
}

/// What the receiver publishes in a dropout zone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DropoutMode {
    /// Nothing at all.
    #[default]
    Silent,
    /// Messages with status NO_FIX (-1), NaN position and covariance type UNKNOWN.
    NoFix,
}

/// A rectangle of the hall where GNSS reception is degraded or absent.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GnssZone {
    /// A name for reports.
    pub name: String,
    /// Degraded or dropout.
    pub kind: ZoneKind,
    /// Where, metres in the map frame (tested against the antenna position).
    pub area: Rect,
}

/// The RTK GNSS receiver (`sensor_msgs/NavSatFix`). Outside every zone it has an RTK
/// fixed solution (status GBAS_FIX = 2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GnssConfig {
    /// Topic name.
    pub topic: String,
    /// Fixes per second.
    pub rate_hz: f64,
    /// WGS84 latitude of the map origin, degrees.
    pub datum_lat_deg: f64,
    /// WGS84 longitude of the map origin, degrees.
    pub datum_lon_deg: f64,
    /// WGS84 ellipsoidal height of the map origin (the floor), metres.
    pub datum_alt_m: f64,
    /// `base_link → gps`: the antenna lever arm (only the translation matters).
    pub mount: Mount3,
    /// Horizontal σ of an RTK fixed solution, metres (white).
    pub good_sigma_m: f64,
    /// σ of the Gauss–Markov error in degraded zones, metres per horizontal axis.
    pub degraded_sigma_m: f64,
    /// Correlation time of the degraded error, seconds.
    pub degraded_tau_s: f64,
    /// Probability that a fix in a degraded zone carries an outlier its covariance does
    /// not report.
    pub outlier_probability: f64,
    /// Smallest outlier, metres (horizontal, random direction).
    pub outlier_min_m: f64,
    /// Largest outlier, metres.
    pub outlier_max_m: f64,
    /// What the receiver publishes in dropout zones.
    pub dropout_mode: DropoutMode,
    /// The zones.
    pub zones: Vec<GnssZone>,
    /// The sensor clock minus true time, seconds.
    pub time_offset_s: f64,
}

impl Default for GnssConfig {
    fn default() -> Self {
        Self {
            topic: "/gnss/fix".into(),
            rate_hz: 5.0,
            // An industrial park near Munich.
            datum_lat_deg: 48.137_154,
            datum_lon_deg: 11.576_124,
            datum_alt_m: 520.0,
            mount: Mount3 { x: -0.1, y: 0.0, z: 0.8, ..Mount3::default() },
            good_sigma_m: 0.02,
            degraded_sigma_m: 0.5,
            degraded_tau_s: 20.0,
            outlier_probability: 0.05,
            outlier_min_m: 2.0,
            outlier_max_m: 6.0,
            dropout_mode: DropoutMode::Silent,
            zones: vec![
                GnssZone {
                    name: "loading_bay".into(),
                    kind: ZoneKind::Degraded,
                    area: Rect::new(20.0, 0.0, 30.0, 9.0),
                },
                GnssZone { name: "mezzanine".into(), kind: ZoneKind::Dropout, area: Rect::new(8.0, 10.8, 20.0, 15.0) },
            ],
            time_offset_s: 0.0,
        }
    }
}

impl GnssConfig {
    /// The map frame's datum.
    pub fn datum(&self) -> Result<Datum, FieldError> {
        Datum::new(self.datum_lat_deg, self.datum_lon_deg, self.datum_alt_m)
            .map_err(|e| FieldError::new("gnss.datum", e.to_string()))
    }

    pub(crate) fn validate(&self) -> Result<(), FieldError> {
        positive("gnss.rate_hz", self.rate_hz)?;
        if self.rate_hz > 200.0 {
            return Err(FieldError::new("gnss.rate_hz", format!("must be at most 200, got {}", self.rate_hz)));
        }
        self.datum()?;
        check_mount("gnss.mount", &self.mount)?;
        non_negative("gnss.good_sigma_m", self.good_sigma_m)?;
        non_negative("gnss.degraded_sigma_m", self.degraded_sigma_m)?;
        positive("gnss.degraded_tau_s", self.degraded_tau_s)?;
        probability("gnss.outlier_probability", self.outlier_probability)?;
        non_negative("gnss.outlier_min_m", self.outlier_min_m)?;
        non_negative("gnss.outlier_max_m", self.outlier_max_m)?;
        if self.outlier_min_m > self.outlier_max_m {
            return Err(FieldError::new("gnss.outlier_min_m", "must not exceed gnss.outlier_max_m"));
        }
        for (i, z) in self.zones.iter().enumerate() {
            z.area.check(&format!("gnss.zones[{i}].area"))?;
        }
        check_offset("gnss.time_offset_s", self.time_offset_s)
    }

    /// The zone kind at `p` (dropout wins over degraded), `None` in good reception.
    pub fn zone_at(&self, p: fusemap_core::geometry::Point2) -> Option<ZoneKind> {
        let mut kind = None;
        for z in self.zones.iter().filter(|z| z.area.contains(p)) {
            if z.kind == ZoneKind::Dropout {
                return Some(ZoneKind::Dropout);
            }
            kind = Some(z.kind);
        }
        kind
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::geometry::Point2;

    #[test]
    fn beam_layout() {
        let l = LidarConfig::default();
        assert!((l.angle_min() + 135f64.to_radians()).abs() < 1e-12);
        let last = l.angle_min() + l.angle_increment() * (l.beams - 1) as f64;
        assert!((last - 135f64.to_radians()).abs() < 1e-12);
        assert!((l.time_increment() * 540.0 - 0.05).abs() < 1e-15);
        let full = LidarConfig { fov_deg: 360.0, beams: 360, ..LidarConfig::default() };
        assert!((full.angle_increment() - 1f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn dropout_zones_win_over_degraded_ones() {
        let mut g = GnssConfig::default();
        g.zones.push(GnssZone {
            name: "overlap".into(),
            kind: ZoneKind::Degraded,
            area: Rect::new(8.0, 10.8, 9.0, 12.0),
        });
        assert_eq!(g.zone_at(Point2::new(8.5, 11.0)), Some(ZoneKind::Dropout));
        assert_eq!(g.zone_at(Point2::new(25.0, 3.0)), Some(ZoneKind::Degraded));
        assert_eq!(g.zone_at(Point2::new(3.0, 3.0)), None);
    }
}
