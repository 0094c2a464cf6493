//! What the estimator tells its caller besides the track: which inputs it used, which it
//! rejected and why, how consistent the corrections were, and what it learnt about the
//! sensors.

use super::input::FixQuality;
use crate::time::Stamp;
use serde::Serialize;

/// Normalised innovation squared (NIS) statistics of one kind of correction. For a
/// consistent filter the NIS of accepted corrections averages the measurement's degrees of
/// freedom (Bar-Shalom et al., §5.4); a much larger mean says the noise figures are too
/// small, a much smaller one that they are too large.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct InnovationStats {
    /// Degrees of freedom of the measurement.
    pub dof: u32,
    /// Corrections whose innovation was evaluated.
    pub count: usize,
    /// Mean NIS of the accepted corrections (0 when none).
    pub mean_nis_accepted: f64,
    /// Share of evaluated corrections whose NIS was above the gate.
    pub share_above_gate: f64,
    #[serde(skip)]
    pub(crate) nis_sum_accepted: f64,
    #[serde(skip)]
    pub(crate) accepted: usize,
    #[serde(skip)]
    pub(crate) above: usize,
}

impl InnovationStats {
    pub(crate) fn new(dof: u32) -> Self {
        Self { dof, ..Default::default() }
    }

    pub(crate) fn record(&mut self, nis: f64, accepted: bool) {
        self.count += 1;
        if accepted {
            self.accepted += 1;
            self.nis_sum_accepted += nis;
        } else {
            self.above += 1;
        }
        self.mean_nis_accepted = if self.accepted > 0 { self.nis_sum_accepted / self.accepted as f64 } else { 0.0 };
        self.share_above_gate = self.above as f64 / self.count as f64;
    }
}

/// Counts for one kind of correction (fixes, absolute poses, headings, zero-rate updates).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CorrectionReport {
    /// Inputs of this kind received.
    pub received: usize,
    /// Applied to the filter.
    pub used: usize,
    /// Rejected by the Mahalanobis gate.
    pub rejected_gate: usize,
    /// Accepted by the filter, then rejected against the smoothed track (fixes only).
    pub rejected_smoothed_gate: usize,
    /// Rejected because a value (or the stamp) was NaN, infinite or absurd.
    pub rejected_not_finite: usize,
    /// Ignored because they fall outside the odometry's time span (the track).
    pub ignored_outside_track: usize,
    /// Covariances that were not positive definite, replaced by the configuration's figure.
    pub covariance_fallbacks: usize,
    /// Innovation consistency.
    pub innovation: InnovationStats,
}

impl CorrectionReport {
    pub(crate) fn new(dof: u32) -> Self {
        Self { innovation: InnovationStats::new(dof), ..Default::default() }
    }
}

/// Fix counts by reported quality.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FixQualityCount {
    /// The quality the caller reported.
    pub quality: FixQuality,
    /// Valid (finite) fixes received with it.
    pub received: usize,
    /// Applied to the filter.
    pub used: usize,
    /// Rejected by the gate.
    pub rejected_gate: usize,
}

/// Wheel odometry counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct OdometryReport {
    /// Messages received.
    pub received: usize,
    /// Messages forming the track.
    pub used: usize,
    /// Messages with a NaN or infinite pose, one beyond 10⁹ m (`MAX_POSITION_M`), or an
    /// absurd stamp: skipped.
    pub not_finite: usize,
    /// Messages repeating the previous stamp, skipped.
    pub duplicate_stamps: usize,
    /// Covariances present but not finite or not positive definite: the configuration's
    /// noise figures were used for that increment (an absent covariance uses them too,
    /// without being counted).
    pub covariance_fallbacks: usize,
    /// Increments longer than `max_odometry_gap_s`.
    pub gaps: usize,
    /// Increments flagged as slipping.
    pub slip_intervals: usize,
}

/// Gyro counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GyroReport {
    /// Samples received.
    pub received: usize,
    /// Samples used.
    pub used: usize,
    /// Samples with a NaN or infinite rate (or an absurd stamp), skipped.
    pub not_finite: usize,
    /// Samples whose yaw rate exceeds `max_gyro_rate_rad_s`, skipped.
    pub implausible: usize,
    /// Variances present but not finite or not positive: `gyro_rate_sigma` was used.
    pub variance_fallbacks: usize,
    /// Filter steps whose heading came from the odometry because no gyro covered them.
    pub steps_without_gyro: usize,
}

/// A stretch of wheel slip: odometry disagreed with the gyro beyond its noise, and its
/// noise was inflated there.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlipStretch {
    /// First slipping increment's start.
    pub start: Stamp,
    /// Last slipping increment's end.
    pub end: Stamp,
    /// Distance the odometry reported over the stretch, metres.
    pub odometry_distance_m: f64,
}

/// Where the heading came from.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum HeadingSource {
    /// Course over ground: the dead-reckoned path fitted to good fixes (2D Procrustes).
    CourseOverGround {
        /// Fixes in the fit.
        fixes: usize,
        /// Distance between the first and last fix, metres.
        distance_m: f64,
        /// RMS residual of the fit, metres.
        residual_rms_m: f64,
    },
    /// An absolute yaw from the IMU.
    ImuHeading,
    /// An absolute pose.
    AbsolutePose,
    /// No absolute heading or position in the inputs: the map frame is the start pose.
    StartPose,
}

/// How the heading was initialised.
///
/// The filter does not start without a heading. The heading is found first (from the
/// earliest absolute source) and carried back to the start of the track through the
/// dead-reckoned heading, so the track begins with the odometry and the early poses are
/// as good as the fit allows; the smoother then refines them with everything after.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HeadingInit {
    /// The stamp of the measurement that fixed the heading (`None` for [`HeadingSource::StartPose`]).
    pub stamp: Option<Stamp>,
    /// The source.
    pub source: HeadingSource,
    /// The heading given to the start of the track, radians (ENU: 0 = east, counter-clockwise).
    pub start_heading_rad: f64,
    /// Its standard deviation, radians.
    pub start_heading_sigma_rad: f64,
}

/// Why a fix was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FixRejection {
    /// Its NIS was above the Mahalanobis gate.
    Gate,
    /// A coordinate or the lever arm was NaN or infinite.
    NotFinite,
    /// Outside the odometry's time span.
    OutsideTrack,
    /// Accepted by the filter but above the gate against the smoothed track: removed and
    /// the estimate run again.
    SmoothedGate,
}

/// One fix that was not used.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RejectedFix {
    /// The fix's stamp.
    pub stamp: Stamp,
    /// Why.
    pub reason: FixRejection,
    /// Its normalised innovation squared (gate rejections; NaN otherwise).
    pub nis: f64,
}

/// Everything the estimator counted and learnt.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EstimatorReport {
    /// GNSS position fixes.
    pub fixes: CorrectionReport,
    /// Fix counts by quality.
    pub fixes_by_quality: Vec<FixQualityCount>,
    /// Every fix not used, with the reason, in time order (for plots and audits).
    pub rejected_fixes: Vec<RejectedFix>,
    /// Absolute poses.
    pub poses: CorrectionReport,
    /// IMU absolute headings.
    pub headings: CorrectionReport,
    /// Gyro rates used as bias measurements while standing still.
    pub zero_rate: CorrectionReport,
    /// Wheel odometry.
    pub odometry: OdometryReport,
    /// Gyro.
    pub gyro: GyroReport,
    /// Gyro bias at the end of the log (the smoother's and the filter's last state agree),
    /// rad/s: the true rate is the measured rate minus this.
    pub gyro_bias: f64,
    /// Its standard deviation, rad/s.
    pub gyro_bias_sigma: f64,
    /// Odometry scale at the end of the log: true distance = scale × odometry distance.
    pub odometry_scale: f64,
    /// Its standard deviation.
    pub odometry_scale_sigma: f64,
    /// Stretches of wheel slip.
    pub slip_stretches: Vec<SlipStretch>,
    /// Heading initialisation.
    pub heading_init: HeadingInit,
    /// Times the position uncertainty was reopened after consistent gate rejections.
    pub gate_resets: usize,
    /// Runs of rejected fixes that agreed with each other but were farther off than the
    /// odometry could have drifted since the last fix taken (`gate_reset_max_drift`): a
    /// jump of the receiver, left rejected (counted once until the filter takes a fix).
    pub gate_resets_refused: usize,
    /// Time spent standing still (zero-rate updates), seconds.
    pub stationary_s: f64,
    /// Filter steps (samples of the track).
    pub steps: usize,
}
