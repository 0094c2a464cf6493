//! How far to trust the pose track's motion, learnt from how well it has agreed with the
//! scan matches: the odometry keeps its own covariance, scaled to what it shows.
//!
//! The configured odometry model (`odometry_*`: a floor plus a share of each step's
//! distance and turn) is a guess made before the log was seen. Every matched scan
//! measures the track's motion against the lidar's; the mean squared disagreement in units
//! of the model's σ, averaged over the last few dozen scans, says how much better or worse
//! the track is than the model (the variance component of the odometry, Förstner's
//! variance-component estimation in its running form). The model's σ is scaled by its
//! square root, within `[1/10, 10]`:
//!
//! - good odometry (a corrected log replayed, wheel odometry on a clean floor) agrees with
//!   the matches to the matcher's own noise: its edges become stiff in the pose graph, and
//!   a match that would move a scan far from it needs a good score to be believed. SLAM
//!   then never makes good odometry worse.
//! - bad odometry (slipping wheels, a heading bias) disagrees: its edges become soft and the
//!   matches carry the track, as they must.
//!
//! The average is taken over logarithms (a geometric mean, corrected for the mean of
//! `ln χ²`), so one failed match or one wheel slip moves it by little: an arithmetic mean
//! of squares is ruled by its largest sample.

use super::params::SlamParams;
use crate::geometry::{normalize_angle, Pose2};

/// The weight of one scan in the running average (about the last 20 scans).
const RATE: f64 = 0.05;
/// A squared disagreement counts at most as 5 σ …
const CLIP: f64 = 25.0;
/// … and at least as 10⁻³ σ (the logarithm of an exact agreement).
const FLOOR: f64 = 1e-6;
/// The scale stays within [1/K, K].
const K: f64 = 10.0;
/// `E[ln χ²]` with 2 degrees of freedom (`ln 2 − γ`): translation, x and y …
const LN_CHI2_2: f64 = 0.115_931_515_658_412_4;
/// … and with 1 (`−γ − ln 2`): rotation.
const LN_CHI2_1: f64 = -1.270_362_845_461_478;

/// The running agreement of the track's motion with the matches.
#[derive(Clone, Copy, Debug)]
pub(super) struct OdometryAgreement {
    /// Mean of ln(squared disagreement in translation, in units of the model's σ).
    translation: f64,
    /// … in rotation.
    rotation: f64,
}

impl Default for OdometryAgreement {
    /// Before any evidence, the model as configured.
    fn default() -> Self {
        Self { translation: LN_CHI2_2, rotation: LN_CHI2_1 }
    }
}

/// The configured model's σ (translation, rotation) of a motion `d`.
pub(super) fn model_sigmas(p: &SlamParams, d: Pose2) -> (f64, f64) {
    (
        p.odometry_floor_m + p.odometry_translation_per_m * d.x.hypot(d.y),
        p.odometry_floor_rad + p.odometry_rotation_per_rad * normalize_angle(d.theta).abs(),
    )
}

impl OdometryAgreement {
    /// The σ (translation, rotation) of the track's motion `d`, as the agreement so far
    /// says.
    pub(super) fn sigmas(&self, p: &SlamParams, d: Pose2) -> (f64, f64) {
        let (st, sr) = model_sigmas(p, d);
        let scale = |mean_ln: f64, bias: f64| (0.5 * (mean_ln - bias)).exp().clamp(1.0 / K, K);
        (st * scale(self.translation, LN_CHI2_2), sr * scale(self.rotation, LN_CHI2_1))
    }

    /// Takes one matched scan: the track moved by `track`, the matches by `matched`.
    pub(super) fn observe(&mut self, p: &SlamParams, track: Pose2, matched: Pose2) {
        let (st, sr) = model_sigmas(p, track);
        // The model's σ is per axis: x and y each.
        let et = (matched.x - track.x).hypot(matched.y - track.y) / st;
        let er = normalize_angle(matched.theta - track.theta).abs() / sr;
        if et.is_finite() && er.is_finite() {
            let ln = |e: f64| (e * e).clamp(FLOOR, CLIP).ln();
            self.translation += RATE * (ln(et) - self.translation);
            self.rotation += RATE * (ln(er) - self.rotation);
        }
    }

    /// The factors (translation, rotation) the model's σ is scaled by.
    pub(super) fn scales(&self) -> [f64; 2] {
        let scale = |mean_ln: f64, bias: f64| (0.5 * (mean_ln - bias)).exp().clamp(1.0 / K, K);
        [scale(self.translation, LN_CHI2_2), scale(self.rotation, LN_CHI2_1)]
    }

    /// True when `matched` lies within `gate` σ of the track's motion `track` in both
    /// translation and rotation.
    ///
    /// The gate is never tighter than the model itself: odometry that agrees to a tenth of
    /// its model most of the time still stalls, slips and jumps now and then (the robust
    /// average above ignores those, as it should for the edges' weight), and a scan that
    /// follows such a jump must still be found.
    pub(super) fn plausible(&self, p: &SlamParams, track: Pose2, matched: Pose2, gate: f64) -> bool {
        let (st, sr) = self.sigmas(p, track);
        let (mt, mr) = model_sigmas(p, track);
        let (st, sr) = (st.max(mt), sr.max(mr));
        (matched.x - track.x).hypot(matched.y - track.y) <= gate * st
            && normalize_angle(matched.theta - track.theta).abs() <= gate * sr
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn good_odometry_stiffens_and_bad_odometry_softens() {
        let p = SlamParams::default();
        let step = Pose2::new(1.0, 0.0, 0.2);
        let (st0, sr0) = model_sigmas(&p, step);
        let mut good = OdometryAgreement::default();
        let mut bad = OdometryAgreement::default();
        for k in 0..200 {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            // The matches wobble by 5 mm and 0.1° around good odometry …
            good.observe(&p, step, Pose2::new(1.0 + sign * 0.005, 0.0, 0.2 + sign * 0.1f64.to_radians()));
            // … and disagree with bad odometry by 30 cm and 6° every step.
            bad.observe(&p, step, Pose2::new(1.3, 0.0, 0.2 + 6f64.to_radians()));
        }
        let (gt, gr) = good.sigmas(&p, step);
        let (bt, br) = bad.sigmas(&p, step);
        assert!(gt <= 0.11 * st0 && gr <= 0.11 * sr0, "{gt} {gr}");
        assert!(bt > st0 && br > sr0, "{bt} {br}");
        // A 30° jump is implausible against good odometry, not against bad.
        let jump = Pose2::new(1.0, 0.0, 0.2 + 30f64.to_radians());
        assert!(!good.plausible(&p, step, jump, 5.0));
        assert!(bad.plausible(&p, step, jump, 5.0));
        // One wild disagreement moves a settled estimate by little.
        let mut once = good;
        once.observe(&p, step, Pose2::new(5.0, 3.0, 2.0));
        assert!(once.sigmas(&p, step).1 < 2.0 * gr, "{} {gr}", once.sigmas(&p, step).1);
        // Noise of exactly the model's size is read as the model.
        let mut rng = crate::sim::SplitMix64::new(3);
        let mut same = OdometryAgreement::default();
        let mut mean = (0.0, 0.0);
        for k in 0..20_000 {
            let m = Pose2::new(1.0 + st0 * rng.gaussian(), st0 * rng.gaussian(), 0.2 + sr0 * rng.gaussian());
            same.observe(&p, step, m);
            if k >= 1000 {
                let (a, b) = same.sigmas(&p, step);
                mean = (mean.0 + a / st0 / 19_000.0, mean.1 + b / sr0 / 19_000.0);
            }
        }
        assert!((mean.0 - 1.0).abs() < 0.1 && (mean.1 - 1.0).abs() < 0.1, "{mean:?}");
    }
}
