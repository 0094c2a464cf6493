//! The pose track SLAM hands back: the prediction track corrected by the optimised scan
//! poses, as a `map ← odom` correction that varies slowly along the log.
//!
//! At each scan the correction is `C = slam_pose ∘ track_pose⁻¹`; between scans it is
//! interpolated (linear in translation, shortest arc in rotation) and applied on the left
//! of the track, so the track's own fine motion (odometry, gyro) still places every
//! measurement between two scans — the de-skewed beams, a camera frame — at its stamp.
//! This is the `map → odom` transform a ROS localiser publishes (REP 105), here estimated
//! offline for every scan. At a scan stamp the track is exactly the optimised pose.

use crate::geometry::Pose2;
use crate::time::{NoPose, PoseTrack, Stamp, SyncMode};

/// `base` corrected by SLAM.
pub struct CorrectedTrack {
    base: Box<dyn PoseTrack>,
    corrections: Vec<(Stamp, Pose2)>,
    slam: Vec<(Stamp, Pose2)>,
}

impl CorrectedTrack {
    /// `slam_poses`: the optimised `map_from_base` of scans (any order) whose stamps lie in
    /// `base`'s span; scans where `base` has no pose are left out.
    pub fn new(base: Box<dyn PoseTrack>, slam_poses: &[(Stamp, Pose2)]) -> Self {
        let mut corrections: Vec<(Stamp, Pose2)> = slam_poses
            .iter()
            .filter_map(|&(t, p)| {
                let b = base.pose_at(t, SyncMode::Interpolate).ok()?;
                Some((t, p.compose(b.inverse())))
            })
            .collect();
        corrections.sort_by_key(|c| c.0);
        corrections.dedup_by_key(|c| c.0);
        let mut slam = slam_poses.to_vec();
        slam.sort_by_key(|c| c.0);
        slam.dedup_by_key(|c| c.0);
        Self { base, corrections, slam }
    }

    /// The correction at `t`: interpolated between scans, the nearest one outside them.
    pub fn correction_at(&self, t: Stamp) -> Pose2 {
        let c = &self.corrections;
        match c.binary_search_by_key(&t, |x| x.0) {
            Ok(i) => c[i].1,
            Err(0) => c.first().map_or(Pose2::IDENTITY, |x| x.1),
            Err(i) if i == c.len() => c[i - 1].1,
            Err(i) => {
                let ((t0, a), (t1, b)) = (c[i - 1], c[i]);
                a.interpolate(b, (t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64)
            }
        }
    }
}

impl PoseTrack for CorrectedTrack {
    /// Inside a gap of the base track, between two scans SLAM matched, the optimised
    /// poses themselves are interpolated: the scans were placed by the lidar.
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
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

    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        self.base.samples().into_iter().map(|(t, p)| (t, self.correction_at(t).compose(p))).collect()
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
        let track = CorrectedTrack::new(Box::new(odo), &slam);
        for &(t, p) in &slam {
            let q = track.pose_at(t, SyncMode::Interpolate).unwrap();
            assert!((q.x - p.x).abs() < 1e-12 && (q.y - p.y).abs() < 1e-12 && (q.theta - p.theta).abs() < 1e-12);
        }
        let mid = track.pose_at(Stamp(250), SyncMode::Interpolate).unwrap();
        let want = c.compose(Pose2::new(0.25, 0.0, 0.0));
        assert!((mid.x - want.x).abs() < 1e-12 && (mid.y - want.y).abs() < 1e-12);
        assert!(track.pose_at(Stamp(2000), SyncMode::Interpolate).is_err());
    }
}
