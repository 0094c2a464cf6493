//! `nav_msgs`: odometry.

use super::geometry_msgs::{PoseWithCovariance, TwistWithCovariance};
use super::std_msgs::Header;
use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};

/// `nav_msgs/msg/Odometry`: an estimate of where the robot is and how fast it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Odometry {
    /// Stamp, and the frame the pose is given in (usually `odom`).
    pub header: Header,
    /// The frame the twist is given in (usually `base_link`).
    pub child_frame_id: String,
    /// Pose of `child_frame_id` in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// Velocity, expressed in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

impl CdrDecode for Odometry {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            child_frame_id: r.string("child_frame_id")?,
            pose: r.decode_field("pose")?,
            twist: r.decode_field("twist")?,
        })
    }
}
