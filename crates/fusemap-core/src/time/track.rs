//! The pose track: where the robot was at any stamp, or an explicit reason why that is not
//! known — never an extrapolated guess.
//!
//! Every source of poses a mapper can use is one of these: an odometry or TF buffer
//! (interpolated, [`PoseBuffer`]), the fused and smoothed estimate of several sensors, or a
//! localiser's output. The mapper asks for the pose at each measurement's own stamp (the
//! design document's §4.1), and either gets a pose with, where the source knows it, its
//! covariance, or a [`NoPose`] it counts.

use super::{NoPose, PoseBuffer, Stamp, SyncMode};
use crate::geometry::Pose2;

/// A 3 × 3 covariance of (x, y, θ), row-major.
pub type Covariance3 = [[f64; 3]; 3];

/// `map_from_base` at any stamp of a track's span.
pub trait PoseTrack: Send + Sync {
    /// The pose at `t` under `mode` (sources that are not sampled buffers may ignore the
    /// nearest-neighbour mode and always interpolate).
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose>;

    /// The pose's covariance at `t`, where the source estimates one.
    fn covariance_at(&self, _t: Stamp) -> Option<Covariance3> {
        None
    }

    /// The first and last stamp with a pose.
    fn span(&self) -> Option<(Stamp, Stamp)>;

    /// The track's samples in time order (for `trajectory.tum`).
    fn samples(&self) -> Vec<(Stamp, Pose2)>;

    /// For a track that is another track's poses moved into the map frame (SLAM's
    /// correction of an odometry track), the transform `map_from_source` at `t`: REP 105's
    /// `map → odom`. `None` for a track given in one frame.
    fn frame_correction_at(&self, _t: Stamp) -> Option<Pose2> {
        None
    }
}

impl PoseTrack for PoseBuffer {
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
        PoseBuffer::pose_at(self, t, mode)
    }

    fn span(&self) -> Option<(Stamp, Stamp)> {
        PoseBuffer::span(self)
    }

    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        PoseBuffer::samples(self).collect()
    }
}

/// A track composed with a fixed transform on the left: `map_from_base = map_from_odom ·
/// odom_from_base` with a constant `map_from_odom` (identity when only odometry is fused).
pub struct InFrame<T> {
    /// The constant `map_from_odom`.
    pub map_from_odom: Pose2,
    /// The `odom_from_base` track.
    pub track: T,
}

impl<T: PoseTrack> PoseTrack for InFrame<T> {
    fn pose_at(&self, t: Stamp, mode: SyncMode) -> Result<Pose2, NoPose> {
        Ok(self.map_from_odom * self.track.pose_at(t, mode)?)
    }

    fn covariance_at(&self, t: Stamp) -> Option<Covariance3> {
        self.track.covariance_at(t)
    }

    fn span(&self) -> Option<(Stamp, Stamp)> {
        self.track.span()
    }

    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        self.track.samples().into_iter().map(|(s, p)| (s, self.map_from_odom * p)).collect()
    }

    fn frame_correction_at(&self, t: Stamp) -> Option<Pose2> {
        Some(self.track.frame_correction_at(t).map_or(self.map_from_odom, |c| self.map_from_odom * c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_is_a_track_and_a_frame_moves_it() {
        let mut b = PoseBuffer::new(1.0);
        b.push(Stamp(0), Pose2::new(0.0, 0.0, 0.0));
        b.push(Stamp(1_000_000_000), Pose2::new(1.0, 0.0, 0.0));
        let t = InFrame { map_from_odom: Pose2::new(10.0, 0.0, std::f64::consts::FRAC_PI_2), track: b };
        let p = t.pose_at(Stamp(500_000_000), SyncMode::Interpolate).unwrap();
        assert!((p.x - 10.0).abs() < 1e-12 && (p.y - 0.5).abs() < 1e-12);
        assert!(matches!(t.pose_at(Stamp(2_000_000_000), SyncMode::Interpolate), Err(NoPose::AfterEnd(_))));
        assert_eq!(t.samples().len(), 2);
        assert!(t.covariance_at(Stamp(0)).is_none());
        assert_eq!(t.frame_correction_at(Stamp(0)), Some(t.map_from_odom));
    }
}
