//! The estimator's inputs, and their validation into time-ordered streams.

use super::config::EstimatorConfig;
use super::linalg::{is_spd, Mat};
use super::report::{CorrectionReport, FixRejection, GyroReport, OdometryReport, RejectedFix};
use crate::geometry::{Point2, Pose2};
use crate::time::Stamp;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::sync::Arc;

/// The quality of a GNSS fix, as the caller maps its receiver's status (NavSatFix
/// `status`, NMEA GGA quality). Used for reporting; the weight of a fix is its covariance,
/// which the caller has already floored per status.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FixQuality {
    /// RTK with fixed integer ambiguities (centimetres).
    RtkFixed,
    /// A standalone or float fix (decimetres to metres).
    Fix,
    /// SBAS-augmented fix.
    Sbas,
    /// Unknown status.
    Unknown,
}

impl FixQuality {
    /// Every quality, in report order.
    pub const ALL: [FixQuality; 4] = [FixQuality::RtkFixed, FixQuality::Fix, FixQuality::Sbas, FixQuality::Unknown];

    pub(crate) fn index(self) -> usize {
        self as usize
    }
}

/// One sensor reading for the estimator. Stamps are the measurement times; inputs may
/// come in any order (they are sorted stably by stamp).
#[derive(Clone, Debug, PartialEq)]
pub enum EstimatorInput {
    /// Wheel odometry: `odom_from_base`. Consecutive messages give the motion increment.
    Odometry {
        /// Measurement time.
        stamp: Stamp,
        /// `odom_from_base`.
        pose: Pose2,
        /// Covariance of (x, y, yaw), read as the covariance of the increment since the
        /// previous message in the base frame at that message (ROS drivers differ; when it
        /// is absent or not positive definite the configuration's noise model is used).
        /// Behind an `Arc` (shared where it repeats: [`share_repeated`]) so that an input
        /// stays small: an hour's log holds a few hundred thousand of them. An increment's
        /// covariance from a driver whose covariance grows is its own allocation, about
        /// 90 bytes more than when it was inline; a driver's constant covariance gives no
        /// increment covariance at all.
        covariance: Option<Arc<[[f64; 3]; 3]>>,
    },
    /// Gyro z rate.
    Gyro {
        /// Measurement time.
        stamp: Stamp,
        /// Angular rate about the base z axis, rad/s (REP 103: counter-clockwise positive).
        yaw_rate: f64,
        /// Variance of the rate, (rad/s)², when the message carries one.
        variance: Option<f64>,
    },
    /// An absolute yaw from the IMU's orientation (only when it has one: a magnetometer or
    /// a dual-antenna receiver), in the map frame.
    Heading {
        /// Measurement time.
        stamp: Stamp,
        /// Yaw, radians.
        yaw: f64,
        /// Variance, rad².
        variance: f64,
    },
    /// A GNSS antenna position in the local ENU map frame (x east, y north).
    Position {
        /// Measurement time.
        stamp: Stamp,
        /// Antenna position, metres.
        enu: [f64; 2],
        /// Covariance, m² (already floored per fix status by the caller); shared, as above.
        covariance: Arc<[[f64; 2]; 2]>,
        /// The antenna in the base frame (`base_from_antenna` translation).
        antenna: Point2,
        /// Reported fix quality.
        quality: FixQuality,
    },
    /// An absolute `map_from_base` pose (`PoseWithCovarianceStamped`).
    Pose {
        /// Measurement time.
        stamp: Stamp,
        /// `map_from_base`.
        pose: Pose2,
        /// Covariance of (x, y, yaw); shared, as above.
        covariance: Arc<[[f64; 3]; 3]>,
    },
}

impl EstimatorInput {
    /// The measurement time.
    pub fn stamp(&self) -> Stamp {
        match self {
            EstimatorInput::Odometry { stamp, .. }
            | EstimatorInput::Gyro { stamp, .. }
            | EstimatorInput::Heading { stamp, .. }
            | EstimatorInput::Position { stamp, .. }
            | EstimatorInput::Pose { stamp, .. } => *stamp,
        }
    }
}

/// `value`, shared with `previous` when the two are the same to the bit: a driver repeats
/// one covariance in message after message, and an hour's log holds hundreds of thousands
/// of messages, so the inputs and the first pass keep one copy of a run of equal matrices.
/// (To the bit, not `==`: `-0.0` stays `-0.0`, so sharing never changes a value.)
pub fn share_repeated<T: SameBits>(previous: Option<&Arc<T>>, value: T) -> Arc<T> {
    match previous {
        Some(p) if p.same_bits(&value) => Arc::clone(p),
        _ => Arc::new(value),
    }
}

/// The last value handed out by [`share_repeated`], for a stream that keeps no previous
/// element of its own to share with.
pub struct Repeated<T>(Option<Arc<T>>);

impl<T: SameBits> Repeated<T> {
    /// Nothing handed out yet.
    pub fn new() -> Self {
        Self(None)
    }

    /// `value`, shared with the last value when the same to the bit.
    pub fn share(&mut self, value: T) -> Arc<T> {
        let shared = share_repeated(self.0.as_ref(), value);
        self.0 = Some(Arc::clone(&shared));
        shared
    }
}

impl<T: SameBits> Default for Repeated<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// Equality of floating-point values to the bit.
pub trait SameBits {
    /// Whether `self` and `other` have the same bits.
    fn same_bits(&self, other: &Self) -> bool;
}

impl SameBits for f64 {
    fn same_bits(&self, other: &Self) -> bool {
        self.to_bits() == other.to_bits()
    }
}

impl<T: SameBits, const N: usize> SameBits for [T; N] {
    fn same_bits(&self, other: &Self) -> bool {
        self.iter().zip(other).all(|(a, b)| a.same_bits(b))
    }
}

/// A validated correction.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Correction {
    Position { z: [f64; 2], r: Mat<2, 2>, antenna: Point2, quality: FixQuality },
    Heading { yaw: f64, var: f64 },
    Pose { z: [f64; 3], r: Mat<3, 3> },
}

/// Odometry samples (finite, strictly increasing stamps) with their raw covariances.
pub(crate) struct RawOdometry {
    pub stamps: Vec<Stamp>,
    pub poses: Vec<Pose2>,
    pub covariances: Vec<Option<Arc<Mat<3, 3>>>>,
}

/// Gyro samples (finite, strictly increasing stamps) with their variances.
pub(crate) struct RawGyro {
    pub stamps: Vec<Stamp>,
    pub rates: Vec<f64>,
    pub variances: Vec<f64>,
}

/// The inputs split by kind, validated and in time order.
pub(crate) struct Sorted {
    pub odometry: RawOdometry,
    pub gyro: RawGyro,
    pub corrections: Vec<(Stamp, Correction)>,
}

/// Counters filled while sorting.
pub(crate) struct InputCounts {
    pub odometry: OdometryReport,
    pub gyro: GyroReport,
    pub fixes: CorrectionReport,
    pub poses: CorrectionReport,
    pub headings: CorrectionReport,
    pub rejected_fixes: Vec<RejectedFix>,
}

/// Stamps within ±146 years of the epoch: differences of two such stamps cannot overflow.
fn sane(t: Stamp) -> bool {
    t.0.unsigned_abs() < 1 << 62
}

/// Counts an input with an absurd stamp as not finite.
fn count_insane(input: &EstimatorInput, counts: &mut InputCounts) {
    match input {
        EstimatorInput::Odometry { .. } => {
            counts.odometry.received += 1;
            counts.odometry.not_finite += 1;
        }
        EstimatorInput::Gyro { .. } => {
            counts.gyro.received += 1;
            counts.gyro.not_finite += 1;
        }
        EstimatorInput::Heading { .. } => {
            counts.headings.received += 1;
            counts.headings.rejected_not_finite += 1;
        }
        EstimatorInput::Position { stamp, .. } => {
            counts.fixes.received += 1;
            counts.fixes.rejected_not_finite += 1;
            counts.rejected_fixes.push(RejectedFix { stamp: *stamp, reason: FixRejection::NotFinite, nis: f64::NAN });
        }
        EstimatorInput::Pose { .. } => {
            counts.poses.received += 1;
            counts.poses.rejected_not_finite += 1;
        }
    }
}

fn finite3(m: &Mat<3, 3>) -> bool {
    m.iter().flatten().all(|v| v.is_finite())
}

/// Sorts the inputs stably by stamp, drops non-finite values (counted) and replaces
/// covariances that are not positive definite by the configuration's figures (counted).
pub(crate) fn sort_inputs(
    inputs: &[EstimatorInput],
    skip: &HashSet<usize>,
    cfg: &EstimatorConfig,
) -> (Sorted, InputCounts) {
    let mut order: Vec<usize> = (0..inputs.len()).filter(|i| !skip.contains(i)).collect();
    order.sort_by_key(|&i| inputs[i].stamp());
    let mut s = Sorter {
        cfg,
        counts: InputCounts {
            odometry: OdometryReport::default(),
            gyro: GyroReport::default(),
            fixes: CorrectionReport::new(2),
            poses: CorrectionReport::new(3),
            headings: CorrectionReport::new(1),
            rejected_fixes: Vec::new(),
        },
        odometry: RawOdometry { stamps: Vec::new(), poses: Vec::new(), covariances: Vec::new() },
        gyro: RawGyro { stamps: Vec::new(), rates: Vec::new(), variances: Vec::new() },
        corrections: Vec::new(),
    };
    for i in order {
        if !sane(inputs[i].stamp()) {
            count_insane(&inputs[i], &mut s.counts);
            continue;
        }
        match &inputs[i] {
            EstimatorInput::Odometry { stamp, pose, covariance } => s.odometry(*stamp, *pose, covariance.as_ref()),
            &EstimatorInput::Gyro { stamp, yaw_rate, variance } => s.gyro(stamp, yaw_rate, variance),
            &EstimatorInput::Heading { stamp, yaw, variance } => s.heading(stamp, yaw, variance),
            &EstimatorInput::Position { stamp, enu, ref covariance, antenna, quality } => {
                s.position(stamp, enu, **covariance, antenna, quality)
            }
            EstimatorInput::Pose { stamp, pose, covariance } => s.pose(*stamp, *pose, **covariance),
        }
    }
    let Sorter { mut counts, odometry, gyro, corrections, .. } = s;
    counts.odometry.used = odometry.stamps.len();
    counts.gyro.used = gyro.stamps.len();
    (Sorted { odometry, gyro, corrections }, counts)
}

/// The streams [`sort_inputs`] builds, input by input in stamp order, with what it counts.
struct Sorter<'a> {
    cfg: &'a EstimatorConfig,
    counts: InputCounts,
    odometry: RawOdometry,
    gyro: RawGyro,
    corrections: Vec<(Stamp, Correction)>,
}

impl Sorter<'_> {
    /// An odometry pose: a position, at a new stamp; its covariance where it is usable
    /// and asked for.
    fn odometry(&mut self, stamp: Stamp, pose: Pose2, covariance: Option<&Arc<[[f64; 3]; 3]>>) {
        let counts = &mut self.counts.odometry;
        counts.received += 1;
        if !pose.is_position() {
            counts.not_finite += 1;
            return;
        }
        if self.odometry.stamps.last() == Some(&stamp) {
            counts.duplicate_stamps += 1;
            return;
        }
        let cov = match covariance {
            Some(c) if self.cfg.use_odometry_covariance => {
                if finite3(c) && is_spd(c) {
                    Some(Arc::clone(c))
                } else {
                    counts.covariance_fallbacks += 1;
                    None
                }
            }
            _ => None,
        };
        self.odometry.stamps.push(stamp);
        self.odometry.poses.push(pose);
        self.odometry.covariances.push(cov);
    }

    /// A yaw rate: finite, within `max_gyro_rate_rad_s`, at a new stamp.
    fn gyro(&mut self, stamp: Stamp, yaw_rate: f64, variance: Option<f64>) {
        let (counts, cfg) = (&mut self.counts.gyro, self.cfg);
        counts.received += 1;
        if !yaw_rate.is_finite() {
            counts.not_finite += 1;
            return;
        }
        if yaw_rate.abs() > cfg.max_gyro_rate_rad_s {
            counts.implausible += 1;
            return;
        }
        if self.gyro.stamps.last() == Some(&stamp) {
            return;
        }
        let var = match variance {
            Some(v) if v.is_finite() && v > 0.0 => v,
            Some(_) => {
                counts.variance_fallbacks += 1;
                cfg.gyro_rate_sigma.powi(2)
            }
            None => cfg.gyro_rate_sigma.powi(2),
        };
        self.gyro.stamps.push(stamp);
        self.gyro.rates.push(yaw_rate);
        self.gyro.variances.push(var);
    }

    /// An absolute heading, with the fallback variance where its own is unusable.
    fn heading(&mut self, stamp: Stamp, yaw: f64, variance: f64) {
        let counts = &mut self.counts.headings;
        counts.received += 1;
        if !yaw.is_finite() {
            counts.rejected_not_finite += 1;
            return;
        }
        let var = if variance.is_finite() && variance > 0.0 {
            variance
        } else {
            counts.covariance_fallbacks += 1;
            self.cfg.fallback_heading_sigma_rad.powi(2)
        };
        self.corrections.push((stamp, Correction::Heading { yaw, var }));
    }

    /// A GNSS position in the ENU frame: finite and within reach of the map frame.
    fn position(&mut self, stamp: Stamp, enu: [f64; 2], covariance: Mat<2, 2>, antenna: Point2, q: FixQuality) {
        let counts = &mut self.counts;
        counts.fixes.received += 1;
        let far = enu[0].abs().max(enu[1].abs()) > crate::geometry::MAX_POSITION_M;
        if !(enu[0].is_finite() && enu[1].is_finite() && antenna.is_finite()) || far {
            counts.fixes.rejected_not_finite += 1;
            counts.rejected_fixes.push(RejectedFix { stamp, reason: FixRejection::NotFinite, nis: f64::NAN });
            return;
        }
        let r = if is_spd(&covariance) {
            covariance
        } else {
            counts.fixes.covariance_fallbacks += 1;
            let fix_var = self.cfg.fallback_fix_sigma_m.powi(2);
            [[fix_var, 0.0], [0.0, fix_var]]
        };
        self.corrections.push((stamp, Correction::Position { z: enu, r, antenna, quality: q }));
    }

    /// A full pose (a localiser's), with the fallback covariance where its own is unusable.
    fn pose(&mut self, stamp: Stamp, pose: Pose2, covariance: Mat<3, 3>) {
        let counts = &mut self.counts.poses;
        counts.received += 1;
        if !pose.is_position() {
            counts.rejected_not_finite += 1;
            return;
        }
        let r = if finite3(&covariance) && is_spd(&covariance) {
            covariance
        } else {
            counts.covariance_fallbacks += 1;
            let (m, a) = (self.cfg.fallback_pose_sigma_m.powi(2), self.cfg.fallback_pose_sigma_rad.powi(2));
            [[m, 0.0, 0.0], [0.0, m, 0.0], [0.0, 0.0, a]]
        };
        self.corrections.push((stamp, Correction::Pose { z: [pose.x, pose.y, pose.theta], r }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::estimate;
    use crate::time::PoseTrack;

    #[test]
    fn equal_matrices_in_a_row_share_one_copy() {
        let a = share_repeated(None, [[1.0, 0.0], [0.0, 1.0]]);
        let b = share_repeated(Some(&a), [[1.0, 0.0], [0.0, 1.0]]);
        assert!(Arc::ptr_eq(&a, &b));
        let c = share_repeated(Some(&b), [[2.0, 0.0], [0.0, 1.0]]);
        assert!(!Arc::ptr_eq(&b, &c));
        assert_eq!(*c, [[2.0, 0.0], [0.0, 1.0]]);
        // To the bit: a zero's sign is kept, and the same NaN is the same value.
        let z = share_repeated(None, 0.0);
        let m = share_repeated(Some(&z), -0.0);
        assert!(!Arc::ptr_eq(&z, &m) && m.is_sign_negative());
        let n = share_repeated(None, f64::NAN);
        assert!(Arc::ptr_eq(&n, &share_repeated(Some(&n), f64::NAN)));
    }

    /// An hour's log gives the estimator hundreds of thousands of inputs: the matrices are
    /// shared, not inline, so an input stays small.
    #[test]
    fn an_input_is_at_most_56_bytes() {
        assert!(std::mem::size_of::<EstimatorInput>() <= 56, "{}", std::mem::size_of::<EstimatorInput>());
    }

    /// Found by the estimator fuzz target: a heading claiming a variance of 10¹²² and an
    /// absolute pose 10¹²² m out made the smoother hand out NaN poses.
    #[test]
    fn absurd_values_never_make_a_nan_pose() {
        let odo = |t: i64, y: f64| EstimatorInput::Odometry {
            stamp: Stamp(t * 100_000_000),
            pose: Pose2::new(0.0, y, 0.0),
            covariance: None,
        };
        let mut inputs: Vec<EstimatorInput> = (11..60).map(|t| odo(t, if t == 11 { -32.341 } else { 0.0 })).collect();
        inputs.push(EstimatorInput::Heading { stamp: Stamp(1_995_000_000), yaw: 0.0, variance: 2.6e122 });
        let r = [[0.23, 0.0, 0.0], [0.0, 0.23, 0.0], [0.0, 0.0, 0.27]];
        let pose = Pose2::new(2.6e122, 32.5, 0.0);
        inputs.push(EstimatorInput::Pose { stamp: Stamp(2_395_000_000), pose, covariance: r.into() });
        if let Ok(e) = estimate(&inputs, &EstimatorConfig::default()) {
            assert!(e.samples().iter().all(|(_, p)| p.is_finite()));
            assert_eq!(e.report.poses.rejected_not_finite, 1, "the pose 10¹²² m out is no pose");
        }
    }
}
