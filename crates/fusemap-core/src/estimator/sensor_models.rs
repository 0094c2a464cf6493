//! How a sensor's message becomes an estimator input: the measurement models between a
//! driver's figures and the filter (Thrun, Burgard & Fox, *Probabilistic Robotics*,
//! ch. 5.4 for odometry as a motion measurement, ch. 7 for the EKF's measurement noise).
//! Pure arithmetic on the message's numbers; reading the messages is the pipeline's.

use super::FixQuality;
use serde::Serialize;

/// A 3 × 3 covariance `(x, y, θ)`.
pub type Covariance3 = [[f64; 3]; 3];

/// The covariance of one odometry increment, in the base frame at the increment's start,
/// from the pose covariances a driver published before (`previous`, with the heading
/// `previous_yaw`) and after it (`current`); `None` when it cannot be told.
///
/// `nav_msgs/Odometry` carries the covariance of the pose in `odom`, which grows as the
/// robot drives; the estimator wants the covariance of each increment. That is the growth
/// between consecutive messages, when the driver's covariance does grow. Many drivers
/// publish a constant one (ROS's diff_drive_controller does): its growth is zero, and
/// `None` lets the sensor's noise figures apply instead (reading a constant 0.01 m² as the
/// noise of every 20 ms step would make the odometry a hundred times too uncertain). The
/// growth is in `odom`; the increment's covariance is in the base frame at its start:
/// `Rᵀ(θ_prev) · ΔΣ · R(θ_prev)`.
pub fn odometry_increment_covariance(
    current: &Covariance3,
    previous: &Covariance3,
    previous_yaw: f64,
) -> Option<Covariance3> {
    if !previous_yaw.is_finite() {
        return None;
    }
    let mut d = [[0.0; 3]; 3];
    for (r, row) in d.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = current[r][k] - previous[r][k];
        }
    }
    let (sn, cs) = previous_yaw.sin_cos();
    let rt = [[cs, sn, 0.0], [-sn, cs, 0.0], [0.0, 0.0, 1.0]];
    let mut b = [[0.0; 3]; 3];
    for (i, row) in b.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|a| (0..3).map(|k| rt[i][a] * d[a][k] * rt[j][k]).sum::<f64>()).sum();
        }
    }
    (0..3).all(|i| b[i][i] > 0.0).then_some(b)
}

/// The base frame's yaw rate from a gyro mounted with rotation `base_from_imu`: the z
/// component of `R · ω`, and its variance, the (z, z) entry of `R Σ Rᵀ` (`None` when the
/// message's covariance gives none).
pub fn base_yaw_rate(
    base_from_imu: &[[f64; 3]; 3],
    angular_velocity: [f64; 3],
    covariance: &[f64; 9],
) -> (f64, Option<f64>) {
    let (r, w, c) = (base_from_imu, angular_velocity, covariance);
    let yaw_rate = r[2][0] * w[0] + r[2][1] * w[1] + r[2][2] * w[2];
    let var: f64 = (0..3).map(|a| (0..3).map(|b| r[2][a] * c[a * 3 + b] * r[2][b]).sum::<f64>()).sum();
    (yaw_rate, (var.is_finite() && var > 0.0).then_some(var))
}

/// Why a GNSS fix gives no position (`sensor_msgs/NavSatFix` checked against its
/// definition and the Earth), in the order the checks run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FixProblem {
    /// A `status` outside -1..=2 or a `position_covariance_type` outside 0..=3: values
    /// the message definition does not have, so the rest cannot be trusted either.
    InvalidField,
    /// `STATUS_NO_FIX`.
    NoFix,
    /// A NaN or infinite latitude, longitude or altitude.
    NotFinite,
    /// A latitude beyond ±90°, a longitude beyond ±180° or an altitude outside the
    /// configured band: a receiver or driver fault, not a place.
    OutOfRange,
}

/// The altitude band a fix must lie in when the config gives none, metres above the
/// WGS 84 ellipsoid: from below the Dead Sea shore (geoid undulation included) to above
/// the highest road; a ground robot outside it has a faulty receiver.
pub const DEFAULT_ALTITUDE_RANGE_M: [f64; 2] = [-1000.0, 10000.0];

/// Checks a fix's fields: `Ok` when it gives a position.
pub fn check_fix(
    status: i8,
    covariance_type: u8,
    [latitude, longitude, altitude]: [f64; 3],
    altitude_range_m: [f64; 2],
) -> Result<(), FixProblem> {
    if !(-1..=2).contains(&status) || covariance_type > 3 {
        return Err(FixProblem::InvalidField);
    }
    if status == -1 {
        return Err(FixProblem::NoFix);
    }
    if !(latitude.is_finite() && longitude.is_finite() && altitude.is_finite()) {
        return Err(FixProblem::NotFinite);
    }
    let [low, high] = altitude_range_m;
    if latitude.abs() > 90.0 || longitude.abs() > 180.0 || !(low..=high).contains(&altitude) {
        return Err(FixProblem::OutOfRange);
    }
    Ok(())
}

/// GNSS σ floors by fix status: a receiver's own covariance is often optimistic, and
/// below its floor a fix would pin the track harder than its real error allows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GnssNoise {
    /// Floor for RTK fixes (`STATUS_GBAS_FIX`), m.
    pub floor_rtk_m: f64,
    /// Floor for SBAS fixes, m.
    pub floor_sbas_m: f64,
    /// Floor for plain fixes, m.
    pub floor_fix_m: f64,
    /// σ when the covariance is unknown, m.
    pub unknown_m: f64,
}

/// How a fix states its covariance (`sensor_msgs/NavSatFix`'s `position_covariance_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GnssCovarianceKind {
    /// None given.
    Unknown,
    /// The diagonal only (`APPROXIMATED` or `DIAGONAL_KNOWN`).
    Diagonal,
    /// The whole matrix.
    Known,
}

/// The horizontal covariance a fix gives the estimator, and how it was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GnssCovariance {
    /// East–north covariance, m².
    pub enu: [[f64; 2]; 2],
    /// The fix gave no usable covariance: the unknown σ (or the floor, if larger) applied.
    pub unknown: bool,
    /// A variance was raised to the floor of the fix's quality.
    pub floored: bool,
}

impl GnssNoise {
    /// The floor for a fix of `quality`, m.
    pub fn floor(&self, quality: FixQuality) -> f64 {
        match quality {
            FixQuality::RtkFixed => self.floor_rtk_m,
            FixQuality::Sbas => self.floor_sbas_m,
            _ => self.floor_fix_m,
        }
    }

    /// The east–north covariance for a fix whose message gives `c` (ENU, m², row-major
    /// 3 × 3) of `kind`, floored by its `quality`.
    pub fn covariance(&self, c: &[f64; 9], kind: GnssCovarianceKind, quality: FixQuality) -> GnssCovariance {
        let floor = self.floor(quality);
        let usable = c[0].is_finite() && c[4].is_finite() && c[1].is_finite() && c[0] > 0.0 && c[4] > 0.0;
        let (mut enu, unknown) = match kind {
            GnssCovarianceKind::Unknown => (None, true),
            _ if !usable => (None, true),
            GnssCovarianceKind::Known => (Some([[c[0], c[1]], [c[3], c[4]]]), false),
            GnssCovarianceKind::Diagonal => (Some([[c[0], 0.0], [0.0, c[4]]]), false),
        };
        let enu = enu.get_or_insert_with(|| {
            let v = self.unknown_m.max(floor).powi(2);
            [[v, 0.0], [0.0, v]]
        });
        let f2 = floor * floor;
        let floored = enu[0][0] < f2 || enu[1][1] < f2;
        enu[0][0] = enu[0][0].max(f2);
        enu[1][1] = enu[1][1].max(f2);
        GnssCovariance { enu: *enu, unknown, floored }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixes_are_checked_against_the_definition_and_the_earth() {
        let band = DEFAULT_ALTITUDE_RANGE_M;
        assert_eq!(check_fix(2, 2, [48.1, 11.5, 500.0], band), Ok(()));
        assert_eq!(check_fix(-1, 2, [f64::NAN, 11.5, 500.0], band), Err(FixProblem::NoFix));
        assert_eq!(check_fix(3, 2, [48.1, 11.5, 500.0], band), Err(FixProblem::InvalidField));
        assert_eq!(check_fix(0, 4, [48.1, 11.5, 500.0], band), Err(FixProblem::InvalidField));
        assert_eq!(check_fix(0, 0, [48.1, f64::INFINITY, 500.0], band), Err(FixProblem::NotFinite));
        assert_eq!(check_fix(0, 0, [48.1, 11.5, f64::NAN], band), Err(FixProblem::NotFinite));
        for bad in [[91.0, 11.5, 500.0], [1e308, 11.5, 500.0], [48.1, -180.5, 500.0], [48.1, 11.5, 1e6]] {
            assert_eq!(check_fix(0, 0, bad, band), Err(FixProblem::OutOfRange), "{bad:?}");
        }
        assert_eq!(check_fix(0, 0, [-90.0, 180.0, -1000.0], band), Ok(()));
        assert_eq!(check_fix(0, 0, [48.1, 11.5, 500.0], [0.0, 100.0]), Err(FixProblem::OutOfRange));
    }

    #[test]
    fn a_constant_odometry_covariance_gives_no_increment_covariance() {
        let c = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.001]];
        assert_eq!(odometry_increment_covariance(&c, &c, 0.3), None);
        assert_eq!(odometry_increment_covariance(&c, &c, f64::NAN), None);
    }

    #[test]
    fn a_growing_covariance_is_rotated_into_the_base_frame() {
        let prev = [[0.0; 3]; 3];
        // Grown along odom's x by 0.04 m²; the robot faces +y (90°): along its own y.
        let cur = [[0.04, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.001]];
        let b = odometry_increment_covariance(&cur, &prev, std::f64::consts::FRAC_PI_2).unwrap();
        assert!((b[0][0] - 0.01).abs() < 1e-12 && (b[1][1] - 0.04).abs() < 1e-12, "{b:?}");
        assert!((b[2][2] - 0.001).abs() < 1e-12);
    }

    #[test]
    fn a_gyro_mounted_upside_down_reads_the_rate_negated() {
        let flipped = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        let cov = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4e-4];
        assert_eq!(base_yaw_rate(&flipped, [0.0, 0.0, 0.5], &cov), (-0.5, Some(4e-4)));
        assert_eq!(base_yaw_rate(&flipped, [0.0, 0.0, 0.5], &[0.0; 9]).1, None);
    }

    #[test]
    fn gnss_covariances_are_floored_by_quality() {
        let noise = GnssNoise { floor_rtk_m: 0.02, floor_sbas_m: 0.5, floor_fix_m: 1.0, unknown_m: 3.0 };
        let tiny = [1e-6, 0.0, 0.0, 0.0, 1e-6, 0.0, 0.0, 0.0, 1e-6];
        let rtk = noise.covariance(&tiny, GnssCovarianceKind::Diagonal, FixQuality::RtkFixed);
        assert!(rtk.floored && !rtk.unknown && (rtk.enu[0][0] - 4e-4).abs() < 1e-15);
        let plain = noise.covariance(&tiny, GnssCovarianceKind::Known, FixQuality::Fix);
        assert_eq!(plain.enu, [[1.0, 0.0], [0.0, 1.0]]);
        let unknown = noise.covariance(&tiny, GnssCovarianceKind::Unknown, FixQuality::Fix);
        assert!(unknown.unknown && !unknown.floored && unknown.enu[1][1] == 9.0);
        let broken = [f64::NAN; 9];
        assert!(noise.covariance(&broken, GnssCovarianceKind::Known, FixQuality::Fix).unknown);
        let wide = [4.0, 0.5, 0.0, 0.5, 9.0, 0.0, 0.0, 0.0, 1.0];
        let known = noise.covariance(&wide, GnssCovarianceKind::Known, FixQuality::Fix);
        assert_eq!((known.enu, known.floored), ([[4.0, 0.5], [0.5, 9.0]], false));
    }
}
