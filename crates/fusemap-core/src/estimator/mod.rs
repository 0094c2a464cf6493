//! The planar pose estimator: the `map → base_link` track a mapper uses, from wheel
//! odometry, a gyro, GNSS/RTK fixes, absolute headings and absolute poses.
//!
//! An extended Kalman filter over `[x, y, θ, gyro bias, odometry scale]` runs forward over
//! the whole log, then a Rauch–Tung–Striebel smoother runs backward over it. A filter alone
//! (robot_localization) can only use the past; offline, the smoother lets a fix after an RTK
//! dropout also correct the poses inside the dropout.
//!
//! | step | module |
//! |---|---|
//! | inputs, validation and sorting | [`EstimatorInput`] (`input.rs`) |
//! | odometry and gyro as functions of time, slip against the gyro | `streams.rs` |
//! | slip against precise fixes | `slip_fixes.rs` |
//! | gyro bias at rest, dead reckoning, heading initialisation | `init.rs` |
//! | prediction and gated Joseph-form update | `filter.rs`, `models.rs` |
//! | the forward pass | `run.rs` |
//! | the backward pass | `smoother.rs` |
//! | χ² gates | [`chi_square_quantile`] |
//!
//! Design choices, each explained where it is made:
//! - translation from the odometry scaled by the estimated scale (true distance = scale ×
//!   odometry distance), heading from the bias-corrected gyro; the odometry's heading
//!   increment only checks for slip (or predicts heading when there is no gyro);
//! - the filter stops at every measurement's own stamp, interpolating the odometry and the
//!   gyro integral there (offline, both sides are known), so nothing is extrapolated;
//! - the heading comes from the earliest absolute source and is carried back to the first
//!   odometry stamp, so the track starts with the odometry and never claims a heading it
//!   has not observed ([`HeadingInit`]);
//! - wheel slip is detected twice — odometry yaw against the gyro, odometry distance against
//!   precise fixes — and a slipping stretch predicts with the speed from before the slip
//!   and an inflated noise, so it cannot drag the track; stretches are reported;
//! - fixes pass a χ² gate; when a few rejected fixes in a row agree with each other (the
//!   filter drifted, e.g. after correlated fix errors), the position uncertainty is reopened;
//! - every rejected or ignored input is counted by reason in the [`EstimatorReport`].
//!
//! ```
//! use fusemap_core::estimator::{estimate, EstimatorConfig, EstimatorInput};
//! use fusemap_core::geometry::Pose2;
//! use fusemap_core::time::Stamp;
//! // Odometry alone: the map frame is the start pose.
//! let inputs: Vec<EstimatorInput> = (0..=100)
//!     .map(|i| EstimatorInput::Odometry {
//!         stamp: Stamp(i * 20_000_000),
//!         pose: Pose2::new(0.01 * i as f64, 0.0, 0.0),
//!         covariance: None,
//!     })
//!     .collect();
//! let est = estimate(&inputs, &EstimatorConfig::default()).unwrap();
//! let (pose, _) = est.pose_at(Stamp(1_010_000_000)).unwrap();
//! assert!((pose.x - 0.505).abs() < 1e-9);
//! assert!(est.pose_at(Stamp(3_000_000_000)).is_err());
//! ```

mod chi2;
mod config;
mod error;
mod filter;
mod init;
mod input;
mod linalg;
mod models;
mod output;
mod report;
mod run;
mod second_pass;
mod sensor_models;
mod slip_fixes;
mod smoother;
mod stale_orientation;
mod streams;

#[cfg(test)]
mod scenario_tests;
#[cfg(test)]
mod test_drive;

pub use chi2::{chi_square_cdf, chi_square_quantile};
pub use config::EstimatorConfig;
pub use error::EstimatorError;
pub use input::{share_repeated, EstimatorInput, FixQuality, Repeated, SameBits};
pub use output::{Estimate, StateSample};
pub use report::{
    CorrectionReport, EstimatorReport, FixQualityCount, FixRejection, GyroReport, HeadingInit, HeadingSource,
    InnovationStats, OdometryReport, RejectedFix, SlipStretch,
};
pub use sensor_models::{
    base_yaw_rate, check_fix, odometry_increment_covariance, FixProblem, GnssCovariance, GnssCovarianceKind, GnssNoise,
    DEFAULT_ALTITUDE_RANGE_M,
};
pub use stale_orientation::{StaleOrientation, STALE_TURN_RAD};

use run::RunCounts;
use std::collections::HashSet;
use streams::{GyroTrack, OdometryTrack, SlipDetector};

/// Estimates the `map_from_base` track from `inputs` (any order; sorted stably by stamp).
///
/// The track spans the wheel odometry: corrections outside it are counted and ignored.
/// Non-finite inputs are counted and skipped; covariances that are not positive definite
/// are replaced by the configuration's figures (counted).
///
/// With `smoothed_fix_gate`, accepted fixes that fail the gate against the smoothed track
/// are removed and the estimate is run once more (see `second_pass`).
pub fn estimate(inputs: &[EstimatorInput], cfg: &EstimatorConfig) -> Result<Estimate, EstimatorError> {
    second_pass::estimate_with_hindsight(inputs, cfg)
}

/// One forward filter and backward smoother over `inputs`, but those whose index is in
/// `skip` (without a copy of the others: the inputs of a long log are tens of MB).
pub(crate) fn estimate_once(
    inputs: &[EstimatorInput],
    skip: &HashSet<usize>,
    cfg: &EstimatorConfig,
) -> Result<Estimate, EstimatorError> {
    estimate_held(inputs, skip, cfg, smoother::HELD_RECORDS)
}

/// [`estimate_once`] with the smoother holding at most `held` records at once.
pub(crate) fn estimate_held(
    inputs: &[EstimatorInput],
    skip: &HashSet<usize>,
    cfg: &EstimatorConfig,
    held: usize,
) -> Result<Estimate, EstimatorError> {
    cfg.validate().map_err(|e| EstimatorError::Config(e.to_string()))?;
    if (0..inputs.len()).all(|i| skip.contains(&i)) {
        return Err(EstimatorError::NoInputs);
    }
    let (sorted, mut counts) = input::sort_inputs(inputs, skip, cfg);
    let fixes_received = counts.fixes.received;
    let Some(odo) = OdometryTrack::build(sorted.odometry, cfg, &mut counts.odometry) else {
        return Err(EstimatorError::NoOdometry {
            odometry: counts.odometry.received,
            gyro: counts.gyro.received,
            fixes: fixes_received,
        });
    };
    let gyro = GyroTrack::build(sorted.gyro, cfg);
    let slip = SlipDetector::new(&odo, gyro.as_ref(), cfg);
    let init = init::initialise(&odo, gyro.as_ref(), &sorted.corrections, cfg)?;
    let mut by_quality = run::quality_counts();
    for (_, c) in &sorted.corrections {
        if let input::Correction::Position { quality, .. } = c {
            by_quality[quality.index()].received += 1;
        }
    }
    let mut rc = RunCounts {
        fixes: counts.fixes,
        poses: counts.poses,
        headings: counts.headings,
        zero_rate: CorrectionReport::new(1),
        by_quality,
        rejected_fixes: counts.rejected_fixes,
        gate_resets: 0,
        gate_resets_refused: 0,
        stationary_s: 0.0,
        steps_without_gyro: 0,
    };
    let fix_slip = slip_fixes::FixSlipCheck::new(&sorted.corrections, &odo, cfg);
    let sources = run::MotionSources { odo: &odo, gyro: gyro.as_ref(), slip: &slip, fix_slip: &fix_slip };
    let forward = |pass: run::Pass, counts: &mut run::RunCounts| {
        run::run(&sources, &sorted.corrections, &init, cfg, counts, &pass)
    };
    let track = smoother::filter_and_smooth(forward, &mut rc, held)?;

    let slip_stretches = slip_stretches(&odo, &track.slip, cfg.slip_merge_gap_s);
    counts.odometry.slip_intervals = track.slip.iter().filter(|&&s| s).count();
    counts.gyro.steps_without_gyro = rc.steps_without_gyro;
    let last = track.last.unwrap_or((init.x, init.p));
    let report = EstimatorReport {
        fixes: rc.fixes,
        fixes_by_quality: rc.by_quality,
        rejected_fixes: {
            let mut r = rc.rejected_fixes;
            r.sort_by_key(|f| f.stamp);
            r
        },
        poses: rc.poses,
        headings: rc.headings,
        zero_rate: rc.zero_rate,
        odometry: counts.odometry,
        gyro: counts.gyro,
        gyro_bias: last.0[3],
        gyro_bias_sigma: last.1[3][3].sqrt(),
        odometry_scale: last.0[4],
        odometry_scale_sigma: last.1[4][4].sqrt(),
        slip_stretches,
        heading_init: init.info,
        gate_resets: rc.gate_resets,
        gate_resets_refused: rc.gate_resets_refused,
        stationary_s: rc.stationary_s,
        steps: track.smoothed.len(),
    };
    Ok(Estimate { filtered: track.filtered, smoothed: track.smoothed, report, max_gap_s: cfg.max_sample_gap_s })
}

/// Merges slipping intervals closer than `merge_gap_s` into stretches.
fn slip_stretches(odo: &OdometryTrack, slip: &[bool], merge_gap_s: f64) -> Vec<SlipStretch> {
    let mut out: Vec<SlipStretch> = Vec::new();
    for (i, iv) in odo.intervals.iter().enumerate().filter(|(i, _)| slip[*i]) {
        let (a, b) = (odo.stamps[i], odo.stamps[i + 1]);
        let d = iv.delta.x.hypot(iv.delta.y);
        match out.last_mut() {
            Some(s) if a.secs_since(s.end) <= merge_gap_s => {
                s.end = b;
                s.odometry_distance_m += d;
            }
            _ => out.push(SlipStretch { start: a, end: b, odometry_distance_m: d }),
        }
    }
    out
}
