//! `nav_msgs`: odometry.

use super::geometry_msgs::{PoseWithCovariance, TwistWithCovariance, POSE_WITH_COVARIANCE, TWIST_WITH_COVARIANCE};
use super::std_msgs::{Header, HEADER};
use super::wire::{FieldReader, RosMsg};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

/// `nav_msgs/Odometry`.
pub static ODOMETRY: MsgDef = MsgDef {
    name: "nav_msgs/Odometry",
    text: "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
           geometry_msgs/TwistWithCovariance twist\n",
    deps: &[&HEADER, &POSE_WITH_COVARIANCE, &TWIST_WITH_COVARIANCE],
};

/// `nav_msgs/msg/Odometry`: an estimate of where the robot is and how fast it moves
/// (REP 105: `odom_from_base`, the twist in the child frame).
#[derive(Clone, Debug, Default, PartialEq)]
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

impl RosMsg for Odometry {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            child_frame_id: r.string("child_frame_id")?,
            pose: r.message("pose")?,
            twist: r.message("twist")?,
        })
    }
}

impl CdrEncode for Odometry {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("child_frame_id", &self.child_frame_id)?;
        self.pose.encode(w)?;
        self.twist.encode(w)
    }
}
