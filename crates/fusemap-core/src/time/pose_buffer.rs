//! A time-indexed buffer of robot poses (after Cartographer's
//! `TransformInterpolationBuffer`): the pose at any stamp by interpolation, or an
//! explicit "no pose" — never an extrapolated guess.
//!
//! The design document (§4.1) puts it plainly: each scan must use the pose at its own
//! header stamp; using whatever pose is current in the callback thickens walls ("30 ms
//! off thickens walls") and tears corners. Its prototype matches each scan to the
//! nearest odometry sample within a tolerance (two-pointer over time-sorted streams);
//! interpolating between the two samples around the scan is better. Both are here as
//! [`SyncMode`]s so they can be compared on the same log.

use super::Stamp;
use crate::geometry::Pose2;

/// How a measurement's stamp is matched to the pose track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SyncMode {
    /// Linear interpolation in x, y and shortest-arc in θ between the samples around the
    /// stamp. Refused across a gap longer than the buffer's `max_gap`.
    Interpolate,
    /// The nearest sample, if within `tolerance_s` seconds (the document's prototype;
    /// half the scan period is a reasonable tolerance).
    Nearest {
        /// Largest accepted |t_scan − t_pose|, seconds.
        tolerance_s: f64,
    },
}

/// Why there is no pose for a stamp.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum NoPose {
    /// The buffer holds no pose.
    #[error("no pose has been received")]
    Empty,
    /// The stamp is before the first pose.
    #[error("{0:.3} s before the first pose")]
    BeforeStart(f64),
    /// The stamp is after the last pose.
    #[error("{0:.3} s after the last pose")]
    AfterEnd(f64),
    /// The stamp falls in a gap of the pose track longer than allowed.
    #[error("inside a {gap_s:.3} s gap of the pose track (limit {limit_s:.3} s)")]
    Gap {
        /// The gap's length, seconds.
        gap_s: f64,
        /// The allowed gap, seconds.
        limit_s: f64,
    },
    /// No pose within the nearest-neighbour tolerance.
    #[error("nearest pose is {distance_s:.3} s away (tolerance {tolerance_s:.3} s)")]
    TooFar {
        /// Distance to the nearest pose, seconds.
        distance_s: f64,
        /// The tolerance, seconds.
        tolerance_s: f64,
    },
}

/// What [`PoseBuffer::push`] did with a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushOutcome {
    /// Appended.
    Added,
    /// Same stamp as the last sample: dropped (the first one is kept).
    Duplicate,
    /// Older than the last sample: dropped.
    OutOfOrder,
    /// A non-finite pose, or one beyond [`MAX_POSITION_M`](crate::geometry::MAX_POSITION_M):
    /// dropped.
    NotFinite,
}

/// Poses by time, strictly increasing.
///
/// A gap longer than `max_gap` is refused unless the robot moved little across it: the
/// error of interpolating across a gap is bounded by the motion over it, not by its
/// duration. Odometry drivers and CARMEN loggers go quiet while the robot stands or
/// creeps (the raw Intel log pauses 0.5–3.5 s nearly 2,000 times, over a median 2.8 cm),
/// so a gap whose two ends differ by at most the bridge motion (see
/// [`PoseBuffer::bridging_gaps`]) is interpolated like a short one.
#[derive(Clone, Debug)]
pub struct PoseBuffer {
    stamps: Vec<Stamp>,
    poses: Vec<Pose2>,
    max_gap_ns: i64,
    bridge_translation: f64,
    bridge_rotation: f64,
}

impl PoseBuffer {
    /// An empty buffer refusing to interpolate across gaps longer than `max_gap_s`.
    pub fn new(max_gap_s: f64) -> Self {
        let max_gap_ns = if max_gap_s.is_finite() { (max_gap_s * 1e9).max(0.0) as i64 } else { i64::MAX };
        Self { stamps: Vec::new(), poses: Vec::new(), max_gap_ns, bridge_translation: -1.0, bridge_rotation: -1.0 }
    }

    /// Also interpolate across longer gaps whose two ends differ by at most
    /// `translation` metres and `rotation` radians (negative: never).
    pub fn bridging_gaps(mut self, translation: f64, rotation: f64) -> Self {
        self.bridge_translation = translation;
        self.bridge_rotation = rotation;
        self
    }

    /// Samples held.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// First and last stamp.
    pub fn span(&self) -> Option<(Stamp, Stamp)> {
        Some((*self.stamps.first()?, *self.stamps.last()?))
    }

    /// The samples, in time order.
    pub fn samples(&self) -> impl Iterator<Item = (Stamp, Pose2)> + '_ {
        self.stamps.iter().copied().zip(self.poses.iter().copied())
    }

    /// Appends a sample; samples must come in increasing time order. Duplicates, older
    /// samples and non-finite poses are dropped and reported.
    pub fn push(&mut self, stamp: Stamp, pose: Pose2) -> PushOutcome {
        if !pose.is_position() {
            return PushOutcome::NotFinite;
        }
        if let Some(&last) = self.stamps.last() {
            if stamp == last {
                return PushOutcome::Duplicate;
            }
            if stamp < last {
                return PushOutcome::OutOfOrder;
            }
        }
        self.stamps.push(stamp);
        self.poses.push(pose);
        PushOutcome::Added
    }

    /// The pose at `t` under `mode`.
    pub fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
        match mode {
            SyncMode::Interpolate => self.interpolate(t),
            SyncMode::Nearest { tolerance_s } => self.nearest(t, tolerance_s),
        }
    }

    /// Interpolated pose at `t`.
    pub fn interpolate(&self, t: Stamp) -> Result<Pose2, NoPose> {
        let (first, last) = self.span().ok_or(NoPose::Empty)?;
        if t < first {
            return Err(NoPose::BeforeStart(first.secs_since(t)));
        }
        if t > last {
            return Err(NoPose::AfterEnd(t.secs_since(last)));
        }
        // First index with stamp >= t.
        let i = self.stamps.partition_point(|&s| s < t);
        if self.stamps[i] == t {
            return Ok(self.poses[i]);
        }
        let (t0, t1) = (self.stamps[i - 1], self.stamps[i]);
        // In i128: two stamps of a hostile log can be further apart than i64 holds.
        let gap = i128::from(t1.0) - i128::from(t0.0);
        let (p0, p1) = (self.poses[i - 1], self.poses[i]);
        let small_motion = p0.translation().distance(p1.translation()) <= self.bridge_translation
            && crate::geometry::normalize_angle(p1.theta - p0.theta).abs() <= self.bridge_rotation;
        if gap > i128::from(self.max_gap_ns) && !small_motion {
            return Err(NoPose::Gap { gap_s: gap as f64 * 1e-9, limit_s: self.max_gap_ns as f64 * 1e-9 });
        }
        let f = (i128::from(t.0) - i128::from(t0.0)) as f64 / gap as f64;
        Ok(self.poses[i - 1].interpolate(self.poses[i], f))
    }

    /// The nearest sample to `t` within `tolerance_s` (ties go to the earlier sample).
    pub fn nearest(&self, t: Stamp, tolerance_s: f64) -> Result<Pose2, NoPose> {
        if self.stamps.is_empty() {
            return Err(NoPose::Empty);
        }
        let i = self.stamps.partition_point(|&s| s < t);
        // In i128: two stamps of a hostile log can lie further apart than i64 holds.
        let mut best: Option<(u128, usize)> = None;
        for j in [i.wrapping_sub(1), i] {
            if let Some(&s) = self.stamps.get(j) {
                let d = (i128::from(s.0) - i128::from(t.0)).unsigned_abs();
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, j));
                }
            }
        }
        let (d, j) = best.ok_or(NoPose::Empty)?;
        let distance_s = d as f64 * 1e-9;
        if distance_s <= tolerance_s {
            Ok(self.poses[j])
        } else {
            Err(NoPose::TooFar { distance_s, tolerance_s })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn s(sec: f64) -> Stamp {
        Stamp::from_secs_f64(sec).unwrap()
    }

    fn buffer() -> PoseBuffer {
        let mut b = PoseBuffer::new(0.5);
        for (t, x) in [(0.0, 0.0), (0.1, 1.0), (0.2, 2.0), (1.0, 3.0)] {
            assert_eq!(b.push(s(t), Pose2::new(x, 0.0, x)), PushOutcome::Added);
        }
        b
    }

    #[test]
    fn stamps_further_apart_than_i64_holds_are_a_gap() {
        let mut b = PoseBuffer::new(1.0);
        b.push(Stamp(i64::MIN), Pose2::new(0.0, 0.0, 0.0));
        b.push(Stamp(i64::MAX), Pose2::new(1.0, 0.0, 0.0));
        assert!(matches!(b.interpolate(Stamp(0)), Err(NoPose::Gap { .. })));
        assert_eq!(b.interpolate(Stamp(i64::MAX)).unwrap().x, 1.0);
    }

    #[test]
    fn interpolates_inside_refuses_outside() {
        let b = buffer();
        let p = b.interpolate(s(0.15)).unwrap();
        assert!((p.x - 1.5).abs() < 1e-9);
        assert_eq!(b.interpolate(s(0.1)).unwrap().x, 1.0);
        assert!(matches!(b.interpolate(s(-0.01)), Err(NoPose::BeforeStart(_))));
        assert!(matches!(b.interpolate(s(1.01)), Err(NoPose::AfterEnd(_))));
        // 0.2 → 1.0 is a 0.8 s gap: no pose inside it.
        assert!(matches!(b.interpolate(s(0.5)), Err(NoPose::Gap { .. })));
        assert_eq!(b.interpolate(s(1.0)).unwrap().x, 3.0);
        assert_eq!(PoseBuffer::new(1.0).interpolate(s(0.0)), Err(NoPose::Empty));
    }

    #[test]
    fn small_motion_gaps_are_bridged_when_asked() {
        let mut b = PoseBuffer::new(0.5).bridging_gaps(0.01, 0.01);
        b.push(s(0.0), Pose2::new(1.0, 2.0, 0.3));
        b.push(s(3.0), Pose2::new(1.0005, 2.0, 0.3));
        b.push(s(6.0), Pose2::new(1.5, 2.0, 0.3));
        assert!((b.interpolate(s(1.5)).unwrap().x - 1.00025).abs() < 1e-9);
        // The robot moved 0.5 m during the second pause: refused.
        assert!(matches!(b.interpolate(s(4.5)), Err(NoPose::Gap { .. })));
    }

    #[test]
    fn nearest_within_tolerance() {
        let b = buffer();
        assert_eq!(b.nearest(s(0.13), 0.05).unwrap().x, 1.0);
        assert_eq!(b.nearest(s(0.17), 0.05).unwrap().x, 2.0);
        assert!(matches!(b.nearest(s(0.5), 0.05), Err(NoPose::TooFar { .. })));
        assert_eq!(b.nearest(s(1.04), 0.05).unwrap().x, 3.0);
    }

    #[test]
    fn bad_samples_are_dropped_and_reported() {
        let mut b = buffer();
        assert_eq!(b.push(s(1.0), Pose2::default()), PushOutcome::Duplicate);
        assert_eq!(b.push(s(0.5), Pose2::default()), PushOutcome::OutOfOrder);
        assert_eq!(b.push(s(2.0), Pose2::new(f64::NAN, 0.0, 0.0)), PushOutcome::NotFinite);
        assert_eq!(b.len(), 4);
    }

    #[test]
    fn interpolation_crosses_the_angle_wrap() {
        let mut b = PoseBuffer::new(1.0);
        b.push(s(0.0), Pose2::new(0.0, 0.0, 3.1));
        b.push(s(0.1), Pose2::new(0.0, 0.0, -3.1));
        let th = b.interpolate(s(0.05)).unwrap().theta;
        assert!((th.abs() - std::f64::consts::PI).abs() < 1e-9, "{th}");
    }

    proptest! {
        #[test]
        fn interpolation_is_within_the_neighbours(t in 0.0..1.0f64) {
            let mut b = PoseBuffer::new(10.0);
            for i in 0..=10 {
                b.push(s(i as f64 * 0.1), Pose2::new((i * i) as f64, -(i as f64), 0.0));
            }
            let p = b.interpolate(s(t)).unwrap();
            let lo = (t / 0.1).floor();
            let (a, c) = (lo * lo, (lo + 1.0) * (lo + 1.0));
            prop_assert!(p.x >= a - 1e-6 && p.x <= c + 1e-6);
        }
    }
}
