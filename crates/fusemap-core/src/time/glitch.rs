//! Pose glitches: samples of a pose stream that imply a motion no robot makes.
//!
//! One odometry sample or CARMEN pose a kilometre off (a driver's overflow, a bit flip, an
//! uninitialised field) is a real failure of real logs. Drawn with, it stretches the map's
//! bounding box to cover it, and interpolated between, it sweeps scans across the world.
//! A sample is judged against its neighbours in stamp order by the speed and turn rate it
//! implies. A few consecutive samples that agree with each other but not with what came
//! before are a real discontinuity (an odometry reset, a relocalisation), not a glitch:
//! a run of [`RUN`] mutually consistent samples is kept, a shorter one is rejected.
//!
//! Samples that share a stamp say nothing about speed: each is judged against the last
//! sample of its run with an *earlier* stamp. A stream whose stamps are too coarse to
//! tell its samples apart (the `%g`-printed stamps of some CARMEN logs, where hundreds of
//! scans carry `1.13486e+09`) is therefore not judged where they coincide, rather than
//! read as moving metres in no time.

use super::Stamp;
use crate::geometry::{normalize_angle, Pose2};

/// Consecutive mutually consistent samples that make a run real rather than a glitch.
pub const RUN: usize = 3;

/// Stamp jitter allowed on top of the time between two samples, seconds: two samples a
/// millisecond apart in stamp may carry poses measured 50 ms apart.
const JITTER_S: f64 = 0.05;

/// The fastest motion a pose stream may imply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Metres per second.
    pub max_speed_m_s: f64,
    /// Radians per second.
    pub max_turn_rate_rad_s: f64,
}

impl MotionLimits {
    /// Whether moving from `a` to `b` is possible within the limits.
    pub fn plausible(&self, a: (Stamp, Pose2), b: (Stamp, Pose2)) -> bool {
        let dt = b.0.secs_since(a.0).abs() + JITTER_S;
        let dist = (b.1.x - a.1.x).hypot(b.1.y - a.1.y);
        let turn = normalize_angle(b.1.theta - a.1.theta).abs();
        dist <= self.max_speed_m_s * dt && turn <= self.max_turn_rate_rad_s * dt
    }
}

/// Which of `samples` to keep (`true`) when read in stamp order (equal stamps in the
/// order given). Non-finite poses are left for the caller to refuse and never anchor a
/// run. A stream with fewer than `RUN` (3) finite samples is kept whole: nothing to judge by.
pub fn plausible_samples(samples: &[(Stamp, Pose2)], limits: &MotionLimits) -> Vec<bool> {
    let mut keep = vec![true; samples.len()];
    let mut order: Vec<usize> = (0..samples.len()).filter(|&i| samples[i].1.is_finite()).collect();
    if order.len() < RUN {
        return keep;
    }
    order.sort_by_key(|&i| samples[i].0);
    // `main`: the run being extended; `pending`: a run that broke off from it. A sample
    // joins `main` when consistent with its last sample, else `pending`, else starts a new
    // `pending` (the old one, too short, was a glitch). A `pending` run that reaches RUN
    // samples becomes `main`: a real jump; the old main is kept only if it was a run.
    let mut main = Run::default();
    let mut pending = Run::default();
    let mut reject = |run: &Run| run.items.iter().for_each(|&i| keep[i] = false);
    for i in order {
        let fits = |run: &Run| run.anchor(samples, i).is_none_or(|j| limits.plausible(samples[j], samples[i]));
        if fits(&main) {
            main.push(samples, i);
        } else if !pending.items.is_empty() && fits(&pending) {
            pending.push(samples, i);
        } else {
            reject(&pending);
            pending = Run::default();
            pending.push(samples, i);
        }
        // A run becomes real only once it spans two stamps: samples of one stamp were never
        // judged against each other, and three of them agreeing proves nothing.
        if pending.items.len() >= RUN && pending.before_last.is_some() {
            if main.items.len() < RUN {
                reject(&main);
            }
            main = std::mem::take(&mut pending);
        }
    }
    reject(&pending);
    if main.items.len() < RUN {
        reject(&main);
    }
    keep
}

/// Samples in stamp order, with the last one whose stamp is before the newest one's.
#[derive(Default)]
struct Run {
    items: Vec<usize>,
    before_last: Option<usize>,
}

impl Run {
    fn push(&mut self, samples: &[(Stamp, Pose2)], i: usize) {
        if let Some(&j) = self.items.last() {
            if samples[j].0 < samples[i].0 {
                self.before_last = Some(j);
            }
        }
        self.items.push(i);
    }

    /// The sample `i` (not earlier than any in the run) is judged against: the run's last
    /// sample with an earlier stamp; `None` when every sample shares `i`'s stamp.
    fn anchor(&self, samples: &[(Stamp, Pose2)], i: usize) -> Option<usize> {
        let &j = self.items.last()?;
        if samples[j].0 < samples[i].0 {
            Some(j)
        } else {
            self.before_last
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const LIMITS: MotionLimits = MotionLimits { max_speed_m_s: 20.0, max_turn_rate_rad_s: 12.0 };

    /// A robot at 1 m/s turning at 0.2 rad/s, sampled at 20 Hz.
    fn drive(n: usize) -> Vec<(Stamp, Pose2)> {
        (0..n)
            .map(|k| {
                let t = k as f64 * 0.05;
                (Stamp::from_secs_f64(100.0 + t).unwrap(), Pose2::new(t, 0.1 * t * t, 0.2 * t))
            })
            .collect()
    }

    fn rejected(keep: &[bool]) -> Vec<usize> {
        keep.iter().enumerate().filter(|(_, k)| !**k).map(|(i, _)| i).collect()
    }

    #[test]
    fn a_clean_drive_keeps_every_sample() {
        assert!(plausible_samples(&drive(200), &LIMITS).iter().all(|k| *k));
    }

    #[test]
    fn one_far_sample_is_rejected_wherever_it_is() {
        for at in [0, 1, 57, 198, 199] {
            let mut s = drive(200);
            s[at].1.x += 1000.0;
            assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![at], "glitch at {at}");
        }
    }

    #[test]
    fn a_heading_flip_and_a_short_burst_are_rejected() {
        let mut s = drive(200);
        s[40].1.theta += std::f64::consts::PI;
        s[90].1.y -= 5e3;
        s[91].1.y -= 5e3;
        assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![40, 90, 91]);
    }

    #[test]
    fn a_reset_of_odometry_is_a_real_jump_and_kept() {
        let mut s = drive(200);
        for p in &mut s[120..] {
            p.1.x -= 50.0;
        }
        assert!(rejected(&plausible_samples(&s, &LIMITS)).is_empty());
    }

    #[test]
    fn the_order_of_the_input_does_not_matter() {
        let mut s = drive(100);
        s[30].1.x = 1e8;
        s.reverse();
        assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![69]);
    }

    #[test]
    fn non_finite_poses_are_left_alone_and_anchor_nothing() {
        let mut s = drive(50);
        s[10].1.x = f64::NAN;
        s[11].1.x += 300.0;
        assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![11]);
        assert!(plausible_samples(&s[..2], &LIMITS).iter().all(|k| *k));
    }

    #[test]
    fn samples_sharing_a_stamp_are_judged_against_the_last_earlier_one() {
        // Stamps printed too coarsely to tell samples apart: metres between samples of one
        // stamp are no glitch.
        let s: Vec<_> = drive(200).into_iter().map(|(_, p)| (Stamp(1_134_860_000_000_000_000), p)).collect();
        let s: Vec<_> = s.into_iter().map(|(t, p)| (t, Pose2::new(p.x * 40.0, p.y, p.theta * 20.0))).collect();
        assert!(rejected(&plausible_samples(&s, &LIMITS)).is_empty());
        // Repeated stamps: a far sample sharing its predecessor's stamp is still caught, and
        // so is one sharing its successor's.
        let mut s = drive(100);
        for k in (0..100).step_by(2) {
            s[k + 1].0 = s[k].0;
        }
        s[41].1.x += 500.0;
        s[60].1.y -= 500.0;
        assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![41, 60]);
    }

    #[test]
    fn glitches_sharing_one_stamp_do_not_make_a_run() {
        // Three far samples at one stamp, off the drive and off each other.
        let mut s = drive(60);
        let t = s[30].0;
        for x in [1e3, -3e3, 5e6] {
            s.push((t, Pose2::new(x, 0.0, 0.0)));
        }
        assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![60, 61, 62]);
    }

    proptest! {
        /// Any single glitch farther than the limits allow is the only sample rejected.
        #[test]
        fn any_single_glitch_is_caught(n in 10usize..120, at in 0usize..120, dx in 60.0f64..1e9, dy in -1e9f64..1e9) {
            let at = at % n;
            let mut s = drive(n);
            s[at].1.x += dx;
            s[at].1.y += dy;
            prop_assert_eq!(rejected(&plausible_samples(&s, &LIMITS)), vec![at]);
        }
    }
}
