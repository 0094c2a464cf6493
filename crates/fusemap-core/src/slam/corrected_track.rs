//! The pose track SLAM hands back: the prediction track corrected by the optimised scan
//! poses, as a `map ← odom` correction that varies slowly along the log.
//!
//! At each scan the correction is `C = slam_pose ∘ track_pose⁻¹`; between scans it is
//! interpolated (linear in translation, shortest arc in rotation) and applied on the left
//! of the track, so the track's own fine motion (odometry, gyro) still places every
//! measurement between two scans — the de-skewed beams, a camera frame — at its stamp.
//! Where the base track moves between two scans faster than a robot can (the same test
//! SLAM makes: an odometry reset it did not follow), the base track jumped there: between
//! those two scans the optimised poses are interpolated instead, as across a gap of the
//! track.
//! This is the `map → odom` transform a ROS localiser publishes (REP 105), here estimated
//! offline for every scan. At a scan stamp the track is exactly the optimised pose.

use crate::geometry::Pose2;
use crate::time::{MotionLimits, NoPose, PoseTrack, Stamp, SyncMode};

/// `base` corrected by SLAM.
pub struct CorrectedTrack {
    base: Box<dyn PoseTrack>,
    /// At each scan where `base` has a pose: the correction, the optimised pose and the
    /// base pose.
    corrections: Vec<(Stamp, Pose2, Pose2, Pose2)>,
    slam: Vec<(Stamp, Pose2)>,
    limits: MotionLimits,
}

impl CorrectedTrack {
    /// `slam_poses`: the optimised `map_from_base` of scans (any order) whose stamps lie in
    /// `base`'s span; scans where `base` has no pose are left out. `limits`: the fastest
    /// the base track may move between two scans and still be followed
    /// (`log.max_speed_m_s`, …).
    pub fn new(base: Box<dyn PoseTrack>, slam_poses: &[(Stamp, Pose2)], limits: MotionLimits) -> Self {
        let mut corrections: Vec<(Stamp, Pose2, Pose2, Pose2)> = slam_poses
            .iter()
            .filter_map(|&(t, p)| {
                let b = base.pose_at(t, SyncMode::Interpolate).ok()?;
                Some((t, p.compose(b.inverse()), p, b))
            })
            .collect();
        corrections.sort_by_key(|c| c.0);
        corrections.dedup_by_key(|c| c.0);
        let mut slam = slam_poses.to_vec();
        slam.sort_by_key(|c| c.0);
        slam.dedup_by_key(|c| c.0);
        Self { base, corrections, slam, limits }
    }

    /// The correction at `t`: interpolated between scans, the nearest one outside them.
    pub fn correction_at(&self, t: Stamp) -> Pose2 {
        let c = &self.corrections;
        match c.binary_search_by_key(&t, |x| x.0) {
            Ok(i) => c[i].1,
            Err(0) => c.first().map_or(Pose2::IDENTITY, |x| x.1),
            Err(i) if i == c.len() => c[i - 1].1,
            Err(i) => {
                let ((t0, a, _, _), (t1, b, _, _)) = (c[i - 1], c[i]);
                a.interpolate(b, fraction(t0, t1, t))
            }
        }
    }

    /// Between two scans across which the base track moves faster than a robot can (it
    /// jumped between them), the optimised poses interpolated: the base track holds the
    /// jump, the scans were placed by the lidar. Equal stamps say nothing of speed.
    /// Under [`SyncMode::Nearest`] the nearer scan's pose instead ([`between`]).
    fn across_jump(&self, t: Stamp, mode: SyncMode) -> Option<Result<Pose2, NoPose>> {
        let c = &self.corrections;
        let i = c.partition_point(|x| x.0 < t);
        let ((t0, _, p0, b0), (t1, _, p1, b1)) = (*c.get(i.checked_sub(1)?)?, *c.get(i)?);
        (t1 != t && t1 != t0 && !self.limits.plausible((t0, b0), (t1, b1)))
            .then(|| between((t0, p0), (t1, p1), t, mode))
    }
}

/// Where `t` lies from `t0` to `t1`, as a fraction (in `i128`: two stamps of a hostile log
/// can lie further apart than `i64` holds).
fn fraction(t0: Stamp, t1: Stamp, t: Stamp) -> f64 {
    (i128::from(t.0) - i128::from(t0.0)) as f64 / (i128::from(t1.0) - i128::from(t0.0)) as f64
}

/// The pose at `t` between two optimised scan poses under `mode`: interpolated, or under
/// [`SyncMode::Nearest`] the nearer one (the earlier on a tie) when within the tolerance,
/// as [`crate::time::PoseBuffer::nearest`] picks a sample.
fn between(a: (Stamp, Pose2), b: (Stamp, Pose2), t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
    match mode {
        SyncMode::Interpolate => Ok(a.1.interpolate(b.1, fraction(a.0, b.0, t))),
        SyncMode::Nearest { tolerance_s } => {
            let away = |s: Stamp| (i128::from(s.0) - i128::from(t.0)).unsigned_abs() as f64 * 1e-9;
            let (d, p) = if away(a.0) <= away(b.0) { (away(a.0), a.1) } else { (away(b.0), b.1) };
            if d <= tolerance_s {
                Ok(p)
            } else {
                Err(NoPose::TooFar { distance_s: d, tolerance_s })
            }
        }
    }
}

impl PoseTrack for CorrectedTrack {
    /// Inside a gap of the base track, or across a jump of it, between two scans SLAM
    /// matched, the optimised poses themselves are interpolated: the scans were placed by
    /// the lidar. Under [`SyncMode::Nearest`] those are the nearer scan's pose, within the
    /// tolerance, as the base track's samples are.
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
        if let Some(p) = self.across_jump(t, mode) {
            return p;
        }
        match self.base.pose_at(t, mode) {
            Ok(p) => Ok(self.correction_at(t).compose(p)),
            Err(e) => {
                let i = self.slam.partition_point(|s| s.0 < t);
                match (i.checked_sub(1).and_then(|j| self.slam.get(j)), self.slam.get(i)) {
                    (_, Some(b)) if b.0 == t => Ok(b.1),
                    (Some(&a), Some(&b)) => between(a, b, t, mode),
                    _ => Err(e),
                }
            }
        }
    }

    fn span(&self) -> Option<(Stamp, Stamp)> {
        self.base.span()
    }

    fn frame_correction_at(&self, t: Stamp) -> Option<Pose2> {
        Some(self.correction_at(t))
    }

    /// The base track's samples, corrected (across a jump: the optimised poses
    /// interpolated, as [`pose_at`](Self::pose_at) gives them).
    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        (self.base.samples().into_iter())
            .map(|(t, p)| {
                let jumped = self.across_jump(t, SyncMode::Interpolate).and_then(Result::ok);
                (t, jumped.unwrap_or_else(|| self.correction_at(t).compose(p)))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::PoseBuffer;

    #[test]
    fn the_track_is_the_slam_pose_at_scans_and_follows_the_odometry_between() {
        let mut odo = PoseBuffer::new(10.0);
        for k in 0..=10 {
            odo.push(Stamp(k * 100), Pose2::new(k as f64 * 0.1, 0.0, 0.0));
        }
        // SLAM says the robot was rotated by 0.1 rad and shifted: a constant correction.
        let c = Pose2::new(1.0, 2.0, 0.1);
        let slam: Vec<(Stamp, Pose2)> =
            [0, 400, 1000].iter().map(|&t| (Stamp(t), c.compose(Pose2::new(t as f64 * 1e-3, 0.0, 0.0)))).collect();
        let track = CorrectedTrack::new(Box::new(odo), &slam, limits());
        for &(t, p) in &slam {
            let q = track.pose_at(t, SyncMode::Interpolate).unwrap();
            assert!((q.x - p.x).abs() < 1e-12 && (q.y - p.y).abs() < 1e-12 && (q.theta - p.theta).abs() < 1e-12);
        }
        // The correction is `map → odom`, the same at every stamp here.
        let m = track.frame_correction_at(Stamp(250)).unwrap();
        assert!((m.x - c.x).abs() < 1e-12 && (m.y - c.y).abs() < 1e-12 && (m.theta - c.theta).abs() < 1e-12);
        let mid = track.pose_at(Stamp(250), SyncMode::Interpolate).unwrap();
        let want = c.compose(Pose2::new(0.25, 0.0, 0.0));
        assert!((mid.x - want.x).abs() < 1e-12 && (mid.y - want.y).abs() < 1e-12);
        assert!(track.pose_at(Stamp(2000), SyncMode::Interpolate).is_err());
    }

    fn limits() -> MotionLimits {
        MotionLimits { max_speed_m_s: 20.0, max_turn_rate_rad_s: 10.0 }
    }

    #[test]
    fn across_a_jump_of_the_track_the_optimised_poses_are_interpolated() {
        // The odometry reset by 10⁶ m between 0.4 s and 0.5 s; SLAM kept the scans in place,
        // so the correction jumps by −10⁶ m there.
        let mut odo = PoseBuffer::new(10.0);
        let reset = |k: i64| if k >= 5 { 1e6 } else { 0.0 };
        for k in 0..=10 {
            odo.push(Stamp(k * 100_000_000), Pose2::new(k as f64 * 0.1 + reset(k), 0.0, 0.0));
        }
        let slam: Vec<(Stamp, Pose2)> =
            (0..=10).map(|k| (Stamp(k * 100_000_000), Pose2::new(k as f64 * 0.1, 0.0, 0.0))).collect();
        let track = CorrectedTrack::new(Box::new(odo), &slam, limits());
        // Between the two scans around the reset every pose stays near the scans, never
        // half a million metres away.
        for t in (400..=500).step_by(10) {
            let p = track.pose_at(Stamp(t * 1_000_000), SyncMode::Interpolate).unwrap();
            assert!((0.3..=0.6).contains(&p.x), "{t} ms: {p:?}");
        }
        // Nearest-neighbour sync takes the nearer scan's pose there, within its tolerance.
        let nearest =
            |ms: i64, tolerance_s: f64| track.pose_at(Stamp(ms * 1_000_000), SyncMode::Nearest { tolerance_s });
        assert_eq!(nearest(430, 0.05).unwrap(), slam[4].1);
        assert_eq!(nearest(470, 0.05).unwrap(), slam[5].1);
        assert!(matches!(nearest(450, 0.04), Err(NoPose::TooFar { .. })));
    }

    /// Inside a gap of the base track the optimised poses stand in for it: interpolated,
    /// or the nearer one under nearest-neighbour sync (refused beyond its tolerance).
    #[test]
    fn inside_a_gap_of_the_track_the_sync_mode_is_kept() {
        let mut odo = PoseBuffer::new(0.15);
        for k in [0, 1, 2, 3, 4, 9, 10] {
            odo.push(Stamp(k * 100_000_000), Pose2::new(k as f64 * 0.1, 0.0, 0.0));
        }
        let slam: Vec<(Stamp, Pose2)> =
            [0, 4, 9, 10].iter().map(|&k| (Stamp(k * 100_000_000), Pose2::new(k as f64 * 0.1, 1.0, 0.0))).collect();
        let track = CorrectedTrack::new(Box::new(odo), &slam, limits());
        let at = |ms: i64, mode| track.pose_at(Stamp(ms * 1_000_000), mode);
        let p = at(650, SyncMode::Interpolate).unwrap();
        assert!((p.x - 0.65).abs() < 1e-12 && (p.y - 1.0).abs() < 1e-12, "{p:?}");
        assert_eq!(at(450, SyncMode::Nearest { tolerance_s: 0.1 }).unwrap(), slam[1].1);
        assert_eq!(at(850, SyncMode::Nearest { tolerance_s: 0.1 }).unwrap(), slam[2].1);
        assert!(matches!(at(650, SyncMode::Nearest { tolerance_s: 0.1 }), Err(NoPose::TooFar { .. })));
    }
}
