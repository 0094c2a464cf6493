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
    /// The same figures over time: a filter consistent on average can still be
    /// overconfident for a stretch (a multipath street, a slipping floor), which the mean
    /// hides.
    pub over_time: NisOverTime,
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

    pub(crate) fn record(&mut self, stamp: Stamp, nis: f64, accepted: bool) {
        self.count += 1;
        if accepted {
            self.accepted += 1;
            self.nis_sum_accepted += nis;
        } else {
            self.above += 1;
        }
        self.mean_nis_accepted = if self.accepted > 0 { self.nis_sum_accepted / self.accepted as f64 } else { 0.0 };
        self.share_above_gate = self.above as f64 / self.count as f64;
        self.over_time.record(stamp, nis, accepted);
    }
}

/// The most bins [`NisOverTime`] holds: a run of any length reads as a curve of a
/// hundred-odd points, and the report stays small.
pub const NIS_BINS: usize = 128;

/// NIS statistics in consecutive stretches of equal length from the first correction's
/// stamp. A stretch starts at one second and doubles (neighbouring bins merged) whenever a
/// stamp would need more than [`NIS_BINS`] bins: bounded memory, whatever the run's
/// length.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct NisOverTime {
    /// The first bin's start (the first correction's stamp).
    pub start: Stamp,
    /// Length of a bin, seconds.
    pub bin_s: f64,
    /// The bins, in time order; a bin without a correction has `count` 0.
    pub bins: Vec<NisBin>,
    #[serde(skip)]
    bin_ns: i64,
}

/// One stretch of [`NisOverTime`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct NisBin {
    /// Corrections evaluated in it.
    pub count: usize,
    /// Of those, accepted by the gate.
    pub accepted: usize,
    /// Mean NIS of the accepted ones (0 when none).
    pub mean_nis_accepted: f64,
    #[serde(skip)]
    nis_sum: f64,
}

impl NisBin {
    fn merge(a: Self, b: Self) -> Self {
        let (accepted, nis_sum) = (a.accepted + b.accepted, a.nis_sum + b.nis_sum);
        Self { count: a.count + b.count, accepted, nis_sum, mean_nis_accepted: mean(nis_sum, accepted) }
    }
}

fn mean(sum: f64, n: usize) -> f64 {
    if n > 0 {
        sum / n as f64
    } else {
        0.0
    }
}

impl NisOverTime {
    fn record(&mut self, stamp: Stamp, nis: f64, accepted: bool) {
        if self.bin_ns == 0 {
            (self.start, self.bin_ns) = (stamp, 1_000_000_000);
        }
        // Corrections come in time order; one before the first (never, but a caller's
        // order is not ours to trust) counts in the first bin.
        let since = i128::from(stamp.0) - i128::from(self.start.0);
        let mut k = (since.max(0) / i128::from(self.bin_ns)) as usize;
        while k >= NIS_BINS {
            self.bins = self.bins.chunks(2).map(|p| p.iter().copied().fold(NisBin::default(), NisBin::merge)).collect();
            self.bin_ns = self.bin_ns.saturating_mul(2);
            k = (since.max(0) / i128::from(self.bin_ns)) as usize;
        }
        if self.bins.len() <= k {
            self.bins.resize(k + 1, NisBin::default());
        }
        let b = &mut self.bins[k];
        b.count += 1;
        if accepted {
            b.accepted += 1;
            b.nis_sum += nis;
            b.mean_nis_accepted = mean(b.nis_sum, b.accepted);
        }
        self.bin_s = self.bin_ns as f64 * 1e-9;
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// However long the run, the bins number at most `NIS_BINS`, they hold every
        /// correction, and each equals binning the same corrections directly at the final
        /// width: merging on the way loses nothing.
        #[test]
        fn the_bins_are_direct_binning_at_the_final_width(
            steps in proptest::collection::vec((0i64..5_000_000_000_000, 0.0f64..20.0, any::<bool>()), 1..300),
        ) {
            let mut stamps: Vec<i64> = steps.iter().map(|s| s.0).collect();
            stamps.sort_unstable();
            let mut stats = InnovationStats::new(2);
            for (&t, &(_, nis, ok)) in stamps.iter().zip(&steps) {
                stats.record(Stamp(t), nis, ok);
            }
            let o = &stats.over_time;
            prop_assert!(o.bins.len() <= NIS_BINS && o.start == Stamp(stamps[0]));
            prop_assert_eq!(o.bins.iter().map(|b| b.count).sum::<usize>(), steps.len());
            let width = (o.bin_s * 1e9).round() as i64;
            prop_assert!(width >= 1_000_000_000);
            let mut direct = vec![(0usize, 0usize, 0.0f64); o.bins.len()];
            for (&t, &(_, nis, ok)) in stamps.iter().zip(&steps) {
                let d = &mut direct[((t - stamps[0]) / width) as usize];
                d.0 += 1;
                if ok {
                    d.1 += 1;
                    d.2 += nis;
                }
            }
            for (b, d) in o.bins.iter().zip(&direct) {
                prop_assert_eq!((b.count, b.accepted), (d.0, d.1));
                prop_assert!((b.mean_nis_accepted - mean(d.2, d.1)).abs() <= 1e-9 * (1.0 + d.2));
            }
        }
    }

    #[test]
    fn a_short_run_keeps_one_second_bins() {
        let mut stats = InnovationStats::new(1);
        for (t, nis) in [(0, 1.0), (400_000_000, 3.0), (2_500_000_000, 9.0)] {
            stats.record(Stamp(10_000_000_000 + t), nis, nis < 5.0);
        }
        let o = &stats.over_time;
        assert_eq!((o.start, o.bin_s, o.bins.len()), (Stamp(10_000_000_000), 1.0, 3));
        assert_eq!((o.bins[0].count, o.bins[0].mean_nis_accepted), (2, 2.0));
        assert_eq!((o.bins[1].count, o.bins[2].count, o.bins[2].accepted), (0, 1, 0));
    }
}
