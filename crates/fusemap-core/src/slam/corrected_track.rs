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
                a.interpolate(b, (t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64)
            }
        }
    }

    /// Between two scans across which the base track moves faster than a robot can (it
    /// jumped between them), the optimised poses interpolated: the base track holds the
    /// jump, the scans were placed by the lidar. Equal stamps say nothing of speed.
    fn across_jump(&self, t: Stamp) -> Option<Pose2> {
        let c = &self.corrections;
        let i = c.partition_point(|x| x.0 < t);
        let ((t0, _, p0, b0), (t1, _, p1, b1)) = (*c.get(i.checked_sub(1)?)?, *c.get(i)?);
        (t1 != t && t1 != t0 && !self.limits.plausible((t0, b0), (t1, b1)))
            .then(|| p0.interpolate(p1, (t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64))
    }
}

impl PoseTrack for CorrectedTrack {
    /// Inside a gap of the base track, or across a jump of it, between two scans SLAM
    /// matched, the optimised poses themselves are interpolated: the scans were placed by
    /// the lidar.
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
        if let Some(p) = self.across_jump(t) {
            return Ok(p);
        }
        match self.base.pose_at(t, mode) {
            Ok(p) => Ok(self.correction_at(t).compose(p)),
            Err(e) => {
                let i = self.slam.partition_point(|s| s.0 < t);
                match (i.checked_sub(1).and_then(|j| self.slam.get(j)), self.slam.get(i)) {
                    (_, Some(b)) if b.0 == t => Ok(b.1),
                    (Some(a), Some(b)) => Ok(a.1.interpolate(b.1, (t.0 - a.0 .0) as f64 / (b.0 .0 - a.0 .0) as f64)),
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
            .map(|(t, p)| (t, self.across_jump(t).unwrap_or_else(|| self.correction_at(t).compose(p))))
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
    }
}
