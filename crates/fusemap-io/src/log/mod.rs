//! Robot logs in: CARMEN, ROS 1 bags, ROS 2 MCAP and rosbag2 directories, each read as a
//! stream of [`LogMessage`]s in fusemap's own types.
//!
//! Readers decode; they do not decide. Stamps are passed on as written (header stamp and,
//! where the container has one, the receive/log time) so that time synchronisation and
//! the log doctor can judge them. A record that cannot be decoded is an error naming file
//! and record; a record of a type fusemap does not use is counted in
//! [`ReadStats::skipped_by_type`] and skipped.

pub mod carmen;
mod open;
pub mod ros1;
pub mod ros2;

pub use open::{detect, open_log, LogFormat, OpenedLog};

use fusemap_core::geometry::Pose2;
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;
use std::collections::BTreeMap;

/// A 2D laser scan with the fields of `sensor_msgs/LaserScan` fusemap uses.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanMessage {
    /// Topic (ROS) or message type (`FLASER`, `ROBOTLASER1`, …) for CARMEN.
    pub topic: String,
    /// The sensor frame (`header.frame_id`); empty when the format has none.
    pub frame_id: String,
    /// When the log recorded the message (ROS bag/MCAP log time, CARMEN `logger_ts`),
    /// if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// The scan; `scan.stamp` is the header stamp (acquisition of the first beam).
    pub scan: LaserScan,
    /// Seconds between beams (0 when unknown).
    pub time_increment: f32,
    /// Seconds between scans (0 when unknown).
    pub scan_time: f32,
    /// The sensor's minimum range as the message states it.
    pub range_min: f32,
    /// The sensor's maximum range as the message states it.
    pub range_max: f32,
    /// A pose written on the scan line itself (CARMEN `FLASER` / `ROBOTLASER1`
    /// corrected logs): `world_from_base`. `None` for ROS messages.
    pub pose: Option<Pose2>,
    /// The raw odometry pose written on the scan line (CARMEN `odom_x odom_y odom_theta`),
    /// `odom_from_base`.
    pub odom_pose: Option<Pose2>,
    /// For CARMEN `ROBOTLASER1`: the laser pose on the line (`world_from_laser`), from
    /// which the mount follows.
    pub laser_pose: Option<Pose2>,
}

/// Robot odometry (`nav_msgs/Odometry`, CARMEN `ODOM`): `odom_from_base` at a stamp.
#[derive(Clone, Debug, PartialEq)]
pub struct OdomMessage {
    /// Topic, or `ODOM` for CARMEN.
    pub topic: String,
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id` (usually `odom`).
    pub frame_id: String,
    /// `child_frame_id` (usually `base_link`).
    pub child_frame_id: String,
    /// The planar pose (yaw from the quaternion).
    pub pose: Pose2,
}

/// One transform of a `tf2_msgs/TFMessage`.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Parent frame (`header.frame_id`).
    pub parent: String,
    /// Child frame (`child_frame_id`).
    pub child: String,
    /// Translation x, y, z (metres).
    pub translation: [f64; 3],
    /// Rotation quaternion x, y, z, w.
    pub rotation: [f64; 4],
}

/// A `tf2_msgs/TFMessage` from `/tf` or `/tf_static`.
#[derive(Clone, Debug, PartialEq)]
pub struct TfMessage {
    /// Topic.
    pub topic: String,
    /// True for `/tf_static` (latched, valid at all times).
    pub is_static: bool,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// The transforms.
    pub transforms: Vec<Transform>,
}

/// `sensor_msgs/Imu`, the fields fusemap uses.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuMessage {
    /// Topic.
    pub topic: String,
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`.
    pub frame_id: String,
    /// Orientation quaternion x, y, z, w.
    pub orientation: [f64; 4],
    /// Angular velocity, rad/s.
    pub angular_velocity: [f64; 3],
    /// Linear acceleration, m/s².
    pub linear_acceleration: [f64; 3],
}

/// One decoded message of a log.
#[derive(Clone, Debug, PartialEq)]
pub enum LogMessage {
    /// A laser scan.
    Scan(ScanMessage),
    /// Odometry.
    Odometry(OdomMessage),
    /// Transforms.
    Tf(TfMessage),
    /// An IMU reading.
    Imu(ImuMessage),
}

/// What a reader saw besides the messages it returned.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadStats {
    /// Messages or lines skipped because fusemap does not use their type, by type name.
    pub skipped_by_type: BTreeMap<String, u64>,
    /// Records skipped because they were malformed, when the reader chose to skip rather
    /// than fail (a user wants the rest of the log), with the first few reasons.
    pub malformed: u64,
    /// Up to 10 messages describing malformed records (file, line/record, reason).
    pub malformed_examples: Vec<String>,
}

impl ReadStats {
    /// Counts a skipped record of type `t`.
    pub fn skip_type(&mut self, t: &str) {
        *self.skipped_by_type.entry(t.to_string()).or_default() += 1;
    }

    /// Counts a malformed record and keeps its description if fewer than 10 are kept.
    pub fn malformed(&mut self, description: String) {
        self.malformed += 1;
        if self.malformed_examples.len() < 10 {
            self.malformed_examples.push(description);
        }
    }
}

/// A log opened for reading: messages in file order.
///
/// After an `Err` the reader may not be able to go on (a truncated file); callers stop
/// at the first error unless they know the reader resynchronises.
pub trait LogReader {
    /// The next message, `None` at the end of the log.
    fn next_message(&mut self) -> Option<crate::Result<LogMessage>>;

    /// What was skipped so far.
    fn stats(&self) -> &ReadStats;
}
