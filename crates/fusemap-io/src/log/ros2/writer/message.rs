//! [`OutMessage`]: one message to write, of any type the writer knows.

use super::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use super::definition::MsgDef;
use crate::log::ros2::msgs::geometry_msgs::{
    PoseWithCovarianceStamped, TransformStamped, POSE_WITH_COVARIANCE_STAMPED,
};
use crate::log::ros2::msgs::nav_msgs::{Odometry, ODOMETRY};
use crate::log::ros2::msgs::sensor_msgs::{
    CameraInfo, Image, Imu, LaserScan, NavSatFix, CAMERA_INFO, IMAGE, IMU, LASER_SCAN, NAV_SAT_FIX,
};
use crate::log::ros2::msgs::tf2_msgs::{TfMessageRef, TF_MESSAGE};
use fusemap_core::time::Stamp;

/// A message for [`Rosbag2Writer::write`](super::Rosbag2Writer::write).
///
/// Odometry and pose variants hold their 6×6 covariances inline (about 600 bytes); a
/// message is built, written by reference and dropped, so boxing would only add an
/// allocation per message.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // built, written by reference, dropped: never stored in bulk
pub enum OutMessage {
    /// `sensor_msgs/msg/LaserScan`.
    LaserScan(LaserScan),
    /// `nav_msgs/msg/Odometry`.
    Odometry(Odometry),
    /// `sensor_msgs/msg/Imu`.
    Imu(Imu),
    /// `sensor_msgs/msg/NavSatFix`.
    NavSatFix(NavSatFix),
    /// `geometry_msgs/msg/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped(PoseWithCovarianceStamped),
    /// `tf2_msgs/msg/TFMessage`. Topics with `is_static` transforms, and `/tf_static`
    /// always, are offered latched ([`QosProfile::LATCHED`](super::QosProfile::LATCHED));
    /// static transforms belong on `/tf_static`, which fusemap's reader treats as static.
    Tf {
        /// True for static transforms (valid at all times).
        is_static: bool,
        /// The transforms.
        transforms: Vec<TransformStamped>,
    },
    /// `sensor_msgs/msg/Image`.
    Image(Image<'static>),
    /// `sensor_msgs/msg/CameraInfo`.
    CameraInfo(CameraInfo),
}

impl OutMessage {
    /// The message's `.msg` definition.
    pub fn definition(&self) -> &'static MsgDef {
        match self {
            OutMessage::LaserScan(_) => &LASER_SCAN,
            OutMessage::Odometry(_) => &ODOMETRY,
            OutMessage::Imu(_) => &IMU,
            OutMessage::NavSatFix(_) => &NAV_SAT_FIX,
            OutMessage::PoseWithCovarianceStamped(_) => &POSE_WITH_COVARIANCE_STAMPED,
            OutMessage::Tf { .. } => &TF_MESSAGE,
            OutMessage::Image(_) => &IMAGE,
            OutMessage::CameraInfo(_) => &CAMERA_INFO,
        }
    }

    /// The ROS 2 type name (`sensor_msgs/msg/LaserScan`).
    pub fn type_name(&self) -> String {
        self.definition().ros2_name()
    }

    /// The header stamp; for a TF message, that of its first transform (`None` when empty).
    pub fn header_stamp(&self) -> Option<Stamp> {
        Some(match self {
            OutMessage::LaserScan(m) => m.header.stamp,
            OutMessage::Odometry(m) => m.header.stamp,
            OutMessage::Imu(m) => m.header.stamp,
            OutMessage::NavSatFix(m) => m.header.stamp,
            OutMessage::PoseWithCovarianceStamped(m) => m.header.stamp,
            OutMessage::Tf { transforms, .. } => transforms.first()?.header.stamp,
            OutMessage::Image(m) => m.header.stamp,
            OutMessage::CameraInfo(m) => m.header.stamp,
        })
    }

    /// True for static transforms, which are offered latched.
    pub fn is_static_tf(&self) -> bool {
        matches!(self, OutMessage::Tf { is_static: true, .. })
    }
}

impl CdrEncode for OutMessage {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        match self {
            OutMessage::LaserScan(m) => m.encode(w),
            OutMessage::Odometry(m) => m.encode(w),
            OutMessage::Imu(m) => m.encode(w),
            OutMessage::NavSatFix(m) => m.encode(w),
            OutMessage::PoseWithCovarianceStamped(m) => m.encode(w),
            OutMessage::Tf { transforms, .. } => TfMessageRef(transforms).encode(w),
            OutMessage::Image(m) => m.encode(w),
            OutMessage::CameraInfo(m) => m.encode(w),
        }
    }
}
