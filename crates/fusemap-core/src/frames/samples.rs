//! The stamped samples of one dynamic edge, and the transform between them at a stamp
//! (after Cartographer's `TransformInterpolationBuffer`: interpolate inside, refuse
//! outside).
//!
//! Stamps and transforms are kept in two sorted `Vec`s so a lookup binary-searches a
//! dense array of integers; most samples arrive in order and are appended, the rest are
//! inserted in place.

use crate::geometry::Pose3;
use crate::time::Stamp;

/// Two transforms closer than this (metres, radians) are the same value. Far below any
/// calibration's precision, far above the rounding of a re-serialised `f64`/`f32`.
pub(super) const SAME_TRANSLATION_M: f64 = 1e-9;
/// See [`SAME_TRANSLATION_M`].
pub(super) const SAME_ROTATION_RAD: f64 = 1e-9;

/// How far apart two transforms are: metres between the translations, radians between
/// the rotations.
pub(super) fn difference(a: &Pose3, b: &Pose3) -> (f64, f64) {
    (a.distance_to(b), a.angle_to(b))
}

/// True when two transforms are the same value up to rounding.
pub(super) fn same(a: &Pose3, b: &Pose3) -> bool {
    let (dt, dr) = difference(a, b);
    dt <= SAME_TRANSLATION_M && dr <= SAME_ROTATION_RAD
}

/// What [`Samples::insert`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Inserted {
    /// After every held sample.
    Appended,
    /// Before the latest sample, put in stamp order.
    OutOfOrder,
    /// The same value at the same stamp was already held.
    Identical,
    /// A different value at the same stamp was held and kept: (metres, radians) apart.
    Conflict(f64, f64),
}

/// Why there is no transform at a stamp. Durations in nanoseconds, as `i128` so that
/// differences of extreme `i64` stamps cannot overflow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Miss {
    /// Before the first sample by this much.
    Before(i128),
    /// After the last sample by this much.
    After(i128),
    /// Between two samples this far apart.
    Gap(i128),
}

/// When the interval between two samples is too long to interpolate across.
///
/// The error of interpolating over a silence is bounded by the motion over it, not by
/// its length: odometry drivers and CARMEN loggers go quiet while the robot stands (the
/// Intel bag's `odom → base_link` pauses longer than 0.5 s before 15 % of its scans), so
/// a long gap whose two ends differ by at most the bridge motion is interpolated like a
/// short one (as [`crate::time::PoseBuffer::bridging_gaps`] does for planar poses).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct GapRule {
    /// Longest interval interpolated whatever the motion, nanoseconds.
    pub(super) max_gap_ns: i128,
    /// Longer intervals are interpolated when the ends are at most this far apart, metres
    /// (negative: never) …
    pub(super) bridge_m: f64,
    /// … and their rotations at most this far apart, radians.
    pub(super) bridge_rad: f64,
}

impl GapRule {
    /// Interpolation across `max_gap_ns` at most, no bridging.
    #[cfg(test)]
    pub(super) fn max_gap(max_gap_ns: i128) -> Self {
        Self { max_gap_ns, bridge_m: -1.0, bridge_rad: -1.0 }
    }

    fn allows(&self, gap_ns: i128, a: &Pose3, b: &Pose3) -> bool {
        if gap_ns <= self.max_gap_ns {
            return true;
        }
        let (dt, dr) = difference(a, b);
        dt <= self.bridge_m && dr <= self.bridge_rad
    }
}

/// Samples of one edge, sorted by stamp, one per stamp. Never empty once created.
#[derive(Clone, Debug)]
pub(super) struct Samples {
    stamps: Vec<Stamp>,
    poses: Vec<Pose3>,
}

impl Samples {
    /// One sample.
    pub(super) fn new(stamp: Stamp, pose: Pose3) -> Self {
        Self { stamps: vec![stamp], poses: vec![pose] }
    }

    /// Number of samples.
    pub(super) fn len(&self) -> usize {
        self.stamps.len()
    }

    /// First and last stamp.
    pub(super) fn span(&self) -> (Stamp, Stamp) {
        (self.stamps[0], self.stamps[self.stamps.len() - 1])
    }

    /// The longest interval between consecutive samples, nanoseconds (0 for one sample).
    pub(super) fn longest_gap_ns(&self) -> i128 {
        self.stamps.windows(2).map(|w| w[1].0 as i128 - w[0].0 as i128).max().unwrap_or(0)
    }

    /// Adds a sample in stamp order; at an already held stamp the first value stays.
    pub(super) fn insert(&mut self, stamp: Stamp, pose: Pose3) -> Inserted {
        let last = self.stamps[self.stamps.len() - 1];
        if stamp > last {
            self.stamps.push(stamp);
            self.poses.push(pose);
            return Inserted::Appended;
        }
        let i = self.stamps.partition_point(|&s| s < stamp);
        if self.stamps[i] == stamp {
            let (dt, dr) = difference(&self.poses[i], &pose);
            return if dt <= SAME_TRANSLATION_M && dr <= SAME_ROTATION_RAD {
                Inserted::Identical
            } else {
                Inserted::Conflict(dt, dr)
            };
        }
        self.stamps.insert(i, stamp);
        self.poses.insert(i, pose);
        Inserted::OutOfOrder
    }

    /// The transform at `stamp`: a held sample, or the interpolation (linear translation,
    /// slerp rotation) between the two around it when `rule` allows their gap.
    pub(super) fn at(&self, stamp: Stamp, rule: &GapRule) -> Result<Pose3, Miss> {
        let (first, last) = self.span();
        if stamp < first {
            return Err(Miss::Before(first.0 as i128 - stamp.0 as i128));
        }
        if stamp > last {
            return Err(Miss::After(stamp.0 as i128 - last.0 as i128));
        }
        // First index with a stamp >= `stamp`; it exists since stamp <= last.
        let i = self.stamps.partition_point(|&s| s < stamp);
        if self.stamps[i] == stamp {
            return Ok(self.poses[i]);
        }
        // stamp > first, so i >= 1.
        let (t0, t1) = (self.stamps[i - 1].0 as i128, self.stamps[i].0 as i128);
        let gap = t1 - t0;
        let (a, b) = (&self.poses[i - 1], &self.poses[i]);
        if !rule.allows(gap, a, b) {
            return Err(Miss::Gap(gap));
        }
        let f = (stamp.0 as i128 - t0) as f64 / gap as f64;
        Ok(a.interpolate(b, f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn yaw(x: f64, theta: f64) -> Pose3 {
        Pose3::new([x, 0.0, 0.0], [0.0, 0.0, (theta / 2.0).sin(), (theta / 2.0).cos()])
    }

    #[test]
    fn interpolates_at_the_midpoint_and_refuses_outside() {
        let mut s = Samples::new(Stamp(1_000), yaw(1.0, 0.2));
        assert_eq!(s.insert(Stamp(2_000), yaw(3.0, 0.6)), Inserted::Appended);
        let m = s.at(Stamp(1_500), &GapRule::max_gap(i128::MAX)).unwrap().to_mount();
        assert!((m.x - 2.0).abs() < 1e-12 && (m.yaw - 0.4).abs() < 1e-12, "{m:?}");
        let q = s.at(Stamp(1_250), &GapRule::max_gap(i128::MAX)).unwrap().to_mount();
        assert!((q.x - 1.5).abs() < 1e-12 && (q.yaw - 0.3).abs() < 1e-12, "{q:?}");
        assert_eq!(s.at(Stamp(1_000), &GapRule::max_gap(0)), Ok(yaw(1.0, 0.2)));
        assert_eq!(s.at(Stamp(2_000), &GapRule::max_gap(0)), Ok(yaw(3.0, 0.6)));
        assert_eq!(s.at(Stamp(999), &GapRule::max_gap(i128::MAX)), Err(Miss::Before(1)));
        assert_eq!(s.at(Stamp(2_003), &GapRule::max_gap(i128::MAX)), Err(Miss::After(3)));
        assert_eq!(s.at(Stamp(1_500), &GapRule::max_gap(999)), Err(Miss::Gap(1_000)));
        assert!(s.at(Stamp(1_500), &GapRule::max_gap(1_000)).is_ok());
    }

    #[test]
    fn long_gaps_are_bridged_only_over_small_motion() {
        let mut s = Samples::new(Stamp(0), yaw(1.0, 0.3));
        s.insert(Stamp(3_000), yaw(1.0004, 0.31));
        s.insert(Stamp(6_000), yaw(1.5, 0.31));
        s.insert(Stamp(9_000), yaw(1.5, 0.5));
        let rule = GapRule { max_gap_ns: 1_000, bridge_m: 0.01, bridge_rad: 0.02 };
        let m = s.at(Stamp(1_500), &rule).unwrap().to_mount();
        assert!((m.x - 1.0002).abs() < 1e-12 && (m.yaw - 0.305).abs() < 1e-12, "{m:?}");
        // Moved 0.5 m, then turned 0.19 rad, during the next two pauses: refused.
        assert_eq!(s.at(Stamp(4_500), &rule), Err(Miss::Gap(3_000)));
        assert_eq!(s.at(Stamp(7_500), &rule), Err(Miss::Gap(3_000)));
        assert_eq!(s.at(Stamp(1_500), &GapRule::max_gap(1_000)), Err(Miss::Gap(3_000)));
    }

    #[test]
    fn duplicates_and_conflicts_keep_the_first() {
        let mut s = Samples::new(Stamp(0), yaw(1.0, 0.0));
        assert_eq!(s.insert(Stamp(0), yaw(1.0, 0.0)), Inserted::Identical);
        let Inserted::Conflict(dt, dr) = s.insert(Stamp(0), yaw(1.5, 0.1)) else { panic!("conflict expected") };
        assert!((dt - 0.5).abs() < 1e-12 && (dr - 0.1).abs() < 1e-12);
        assert_eq!(s.len(), 1);
        assert_eq!(s.at(Stamp(0), &GapRule::max_gap(0)), Ok(yaw(1.0, 0.0)));
    }

    #[test]
    fn extreme_stamps_do_not_overflow() {
        let mut s = Samples::new(Stamp(i64::MIN), yaw(0.0, 0.0));
        s.insert(Stamp(i64::MAX), yaw(2.0, 0.0));
        assert_eq!(s.longest_gap_ns(), u64::MAX as i128);
        let m = s.at(Stamp(0), &GapRule::max_gap(i128::MAX)).unwrap();
        assert!((m.translation[0] - 1.0).abs() < 1e-9);
        assert_eq!(s.at(Stamp(0), &GapRule::max_gap(10)), Err(Miss::Gap(u64::MAX as i128)));
    }

    proptest! {
        #[test]
        fn any_insertion_order_gives_sorted_unique_stamps(stamps in prop::collection::vec(-50i64..50, 1..40)) {
            let mut s = Samples::new(Stamp(stamps[0]), yaw(stamps[0] as f64, 0.0));
            for &t in &stamps[1..] {
                let before = s.len();
                let r = s.insert(Stamp(t), yaw(t as f64, 0.0));
                prop_assert_eq!(s.len() - before, usize::from(matches!(r, Inserted::Appended | Inserted::OutOfOrder)));
            }
            prop_assert!(s.stamps.windows(2).all(|w| w[0] < w[1]));
            let mut unique = stamps.clone();
            unique.sort_unstable();
            unique.dedup();
            prop_assert_eq!(s.len(), unique.len());
            // Each pose was x = stamp: interpolation anywhere inside reproduces x = t.
            let (lo, hi) = s.span();
            for t in lo.0..=hi.0 {
                let p = s.at(Stamp(t), &GapRule::max_gap(i128::MAX)).unwrap();
                prop_assert!((p.translation[0] - t as f64).abs() < 1e-9);
            }
        }
    }
}
