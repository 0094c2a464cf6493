//! Robot logs in: CARMEN, ROS 1 bags, ROS 2 MCAP and rosbag2 directories, each read as a
//! stream of [`LogMessage`]s in fusemap's own types.
//!
//! Readers decode; they do not decide. Stamps are passed on as written (header stamp and,
//! where the container has one, the receive/log time) so that time synchronisation and
//! the log doctor can judge them; so are NaN fields and covariances (all zeros: unknown,
//! as in ROS). A record that cannot be decoded is an error naming file and record (one
//! message's payload: [`crate::Error::is_skippable`], the reader goes on); a record of a
//! type fusemap does not use is counted in [`ReadStats::skipped_by_type`] and skipped.
//!
//! Camera images are the exception to "decode everything": they are large, and most
//! passes over a log do not want them. [`open_log`] gives every `sensor_msgs/Image` as an
//! [`ImageHeader`] (stamps, frame, size, encoding; pixels neither decoded nor copied);
//! [`open_log_with`] and [`ReadOptions`] name the image topics whose pixels a pass wants,
//! which then come as [`ImageMessage`]s. Either way an image's declared sizes are checked
//! against its data first ([`check_image_layout`]): one that does not fit is a malformed
//! message like any other.
//!
//! [`ReadOptions`] also carry the `[limits]` a reader holds each piece to: bytes of a
//! decompressed chunk, message or line, beams of a scan, pixels of a decoded image
//! ([`ReadOptions::over_limit`]). A broken limit ends the read with
//! [`crate::Error::Limit`] where it is met.

pub mod carmen;
mod image;
mod open;
pub mod ros1;
pub mod ros2;

pub use image::{
    bytes_per_pixel, check_image_layout, image_over_limit, CameraInfoMessage, ImageHeader, ImageMessage, ImagePayloads,
    ReadOptions, DEFAULT_MAX_DECOMPRESSED_BYTES,
};
pub use open::{detect, open_log, open_log_with, LogFormat, OpenedLog};

use fusemap_core::geometry::{quaternion_yaw, Pose2};
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;
use ros2::msgs::sensor_msgs::NavSatStatus;
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
    /// The angle of the last beam as the message states it (ROS `angle_max`), radians;
    /// NaN when the format states none (CARMEN, whose angles follow from the count).
    pub angle_max: f32,
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

impl ScanMessage {
    /// Why the scan's beams cannot be placed, if they cannot: an `angle_increment` that is
    /// zero or not finite puts every beam on one bearing, a non-finite `angle_min` puts
    /// them nowhere, and a `ranges` count that disagrees with the stated
    /// `angle_min … angle_max` (by more than one beam and 1 %) would spread them over
    /// another field of view — a driver bug, or a message cut or padded. Such a scan is
    /// refused and counted, never drawn.
    pub fn angle_fault(&self) -> Option<String> {
        // At LaserScan's f32 precision, as the map pass places the beams: a CARMEN
        // resolution of 1e-50 is 0 there, and 1e39 infinite.
        let (a0, inc) = (self.scan.angle_min as f32 as f64, self.scan.angle_increment as f32 as f64);
        let n = self.scan.ranges.len();
        if !a0.is_finite() {
            return Some(format!("angle_min is {a0}"));
        }
        if !(inc.is_finite() && inc != 0.0) {
            return Some(format!("angle_increment is {inc}: every beam would lie on one bearing"));
        }
        let a1 = f64::from(self.angle_max);
        if a1.is_nan() || n == 0 {
            return None;
        }
        let expected = (a1 - a0) / inc + 1.0;
        let tolerance = 1.0 + 0.01 * expected.abs();
        if !(expected.is_finite() && (n as f64 - expected).abs() <= tolerance) {
            return Some(format!(
                "{n} ranges, but angle_min {a0:.4} to angle_max {a1:.4} rad by {inc:.6} rad is {expected:.1} beams"
            ));
        }
        None
    }
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
    /// The planar pose (yaw from the quaternion, see [`planar_pose`]): NaN heading for a
    /// zero or non-finite quaternion, never a silent identity.
    pub pose: Pose2,
    /// Row-major 6×6 covariance of the pose over (x, y, z, roll, pitch, yaw), as ROS
    /// writes it (`pose.covariance`). All zeros means unknown (REP 103 leaves it to the
    /// publisher; CARMEN has none).
    pub pose_covariance: [f64; 36],
    /// Velocity of the child frame, expressed in the child frame (`twist.twist`): linear
    /// x, y, z (m/s) then angular x, y, z (rad/s). For CARMEN `ODOM`, `tv` and `rv`
    /// (translational and rotational velocity) as `[tv, 0, 0, 0, 0, rv]`.
    pub twist: [f64; 6],
    /// Row-major 6×6 covariance of `twist`; all zeros means unknown.
    pub twist_covariance: [f64; 36],
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
    /// Linear acceleration, m/s² (gravity included).
    pub linear_acceleration: [f64; 3],
    /// Row-major 3×3 covariance of the orientation about x, y, z (rad²). REP 145: element
    /// 0 equal to -1 means the IMU gives no orientation (see
    /// [`ImuMessage::has_orientation`]); all zeros means the covariance is unknown.
    pub orientation_covariance: [f64; 9],
    /// Row-major 3×3 covariance of `angular_velocity`; -1 at element 0: not measured.
    pub angular_velocity_covariance: [f64; 9],
    /// Row-major 3×3 covariance of `linear_acceleration`; -1 at element 0: not measured.
    pub linear_acceleration_covariance: [f64; 9],
}

impl ImuMessage {
    /// False when the IMU says it gives no orientation (REP 145 and the
    /// `sensor_msgs/Imu` definition: `orientation_covariance[0] == -1`), so that
    /// `orientation` must not be used.
    pub fn has_orientation(&self) -> bool {
        self.orientation_covariance[0] != -1.0
    }
}

/// A satellite navigation fix (`sensor_msgs/NavSatFix`): WGS 84 latitude, longitude and
/// altitude of the antenna with the receiver's covariance.
///
/// Passed on as written: a NaN field or a `STATUS_NO_FIX` status is for the estimator to
/// judge, not the reader.
#[derive(Clone, Debug, PartialEq)]
pub struct GnssMessage {
    /// Topic.
    pub topic: String,
    /// `header.stamp`: when the fix was valid.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`: the antenna's frame (its mount on the robot).
    pub frame_id: String,
    /// `status.status`: one of [`NavSatStatus`]'s `STATUS_*` constants (other values as
    /// written).
    pub status: i8,
    /// `status.service`: a bit set of [`NavSatStatus`]'s `SERVICE_*` constants.
    pub service: u16,
    /// Latitude, degrees, positive north of the equator.
    pub latitude: f64,
    /// Longitude, degrees, positive east of the prime meridian.
    pub longitude: f64,
    /// Altitude above the WGS 84 ellipsoid, metres (NaN when the receiver has none).
    pub altitude: f64,
    /// Row-major 3×3 covariance of the position in the local East-North-Up tangent
    /// plane at the fix, m².
    pub position_covariance: [f64; 9],
    /// How much of `position_covariance` is known: one of
    /// [`NavSatFix`](ros2::msgs::sensor_msgs::NavSatFix)'s `COVARIANCE_TYPE_*` constants.
    pub position_covariance_type: u8,
}

impl GnssMessage {
    /// True when the receiver reports a fix (`status >= STATUS_FIX`).
    pub fn has_fix(&self) -> bool {
        self.status >= NavSatStatus::STATUS_FIX
    }
}

/// A pose estimate with its uncertainty (`geometry_msgs/PoseWithCovarianceStamped`, as
/// published by AMCL on `/amcl_pose`, by a motion-capture system or by another
/// localiser): the pose of the robot in `frame_id`.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseMessage {
    /// Topic.
    pub topic: String,
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`: the frame the pose is given in (`map`, `world`).
    pub frame_id: String,
    /// Position x, y, z, metres.
    pub position: [f64; 3],
    /// Orientation quaternion x, y, z, w, as written (not normalised).
    pub orientation: [f64; 4],
    /// Row-major 6×6 covariance over (x, y, z, roll, pitch, yaw); all zeros: unknown.
    pub covariance: [f64; 36],
}

impl PoseMessage {
    /// The planar pose ([`planar_pose`]): NaN heading for a zero or non-finite quaternion.
    pub fn pose2(&self) -> Pose2 {
        planar_pose(self.position, self.orientation)
    }
}

/// The planar pose of a 3D position and quaternion `(x, y, z, w)`: `(x, y)` and the yaw
/// of the quaternion's x axis projected on the x-y plane (REP 103: z up).
///
/// A zero or non-finite quaternion has no rotation to take the yaw of: the heading is NaN
/// (so that [`Pose2::is_finite`] is false and the consumer rejects it), never the
/// identity a naive `atan2(0, 0)` would give.
///
/// A scaled quaternion (float32-rounded, or written scaled: the same rotation) is
/// normalised by [`quaternion_yaw`] itself; a unit one is used as written.
pub fn planar_pose(position: [f64; 3], orientation: [f64; 4]) -> Pose2 {
    Pose2::new(position[0], position[1], quaternion_yaw(orientation))
}

/// One decoded message of a log.
///
/// The covariances make the odometry variant some 750 bytes, and so every message; they
/// are kept inline rather than boxed because a message is moved once, from the reader
/// to the consumer's own per-type collection, which costs a copy of that size against a
/// heap allocation per message, and because the field types stay those of ROS.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum LogMessage {
    /// A laser scan.
    Scan(ScanMessage),
    /// Odometry.
    Odometry(OdomMessage),
    /// Transforms.
    Tf(TfMessage),
    /// An IMU reading.
    Imu(ImuMessage),
    /// A satellite navigation fix.
    Gnss(GnssMessage),
    /// A pose estimate with covariance.
    Pose(PoseMessage),
    /// A camera image with its pixels (a topic [`ReadOptions::images`] asked for).
    Image(ImageMessage),
    /// A camera image read without its pixels (every other image topic).
    ImageHeader(ImageHeader),
    /// A camera calibration.
    CameraInfo(CameraInfoMessage),
}

impl LogMessage {
    /// The topic (ROS) or message type (CARMEN) the message came on.
    pub fn topic(&self) -> &str {
        match self {
            LogMessage::Scan(m) => &m.topic,
            LogMessage::Odometry(m) => &m.topic,
            LogMessage::Tf(m) => &m.topic,
            LogMessage::Imu(m) => &m.topic,
            LogMessage::Gnss(m) => &m.topic,
            LogMessage::Pose(m) => &m.topic,
            LogMessage::Image(m) => &m.topic,
            LogMessage::ImageHeader(m) => &m.topic,
            LogMessage::CameraInfo(m) => &m.topic,
        }
    }

    /// The header stamp: when the data was taken. For a TF message the first
    /// transform's (each transform has its own); `None` for one with no transforms.
    pub fn stamp(&self) -> Option<Stamp> {
        match self {
            LogMessage::Scan(m) => Some(m.scan.stamp),
            LogMessage::Odometry(m) => Some(m.stamp),
            LogMessage::Tf(m) => m.transforms.first().map(|t| t.stamp),
            LogMessage::Imu(m) => Some(m.stamp),
            LogMessage::Gnss(m) => Some(m.stamp),
            LogMessage::Pose(m) => Some(m.stamp),
            LogMessage::Image(m) => Some(m.stamp),
            LogMessage::ImageHeader(m) => Some(m.stamp),
            LogMessage::CameraInfo(m) => Some(m.stamp),
        }
    }

    /// When the log recorded the message, if its format has such a time.
    pub fn receive_stamp(&self) -> Option<Stamp> {
        match self {
            LogMessage::Scan(m) => m.receive_stamp,
            LogMessage::Odometry(m) => m.receive_stamp,
            LogMessage::Tf(m) => m.receive_stamp,
            LogMessage::Imu(m) => m.receive_stamp,
            LogMessage::Gnss(m) => m.receive_stamp,
            LogMessage::Pose(m) => m.receive_stamp,
            LogMessage::Image(m) => m.receive_stamp,
            LogMessage::ImageHeader(m) => m.receive_stamp,
            LogMessage::CameraInfo(m) => m.receive_stamp,
        }
    }
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
    /// Malformed messages by topic, with the first one's description: a topic whose
    /// every message was malformed is then refused for that reason, not as missing.
    pub malformed_by_topic: BTreeMap<String, (u64, String)>,
}

impl ReadStats {
    /// Counts a skipped record of type `t`.
    pub fn skip_type(&mut self, t: &str) {
        *self.skipped_by_type.entry(t.to_string()).or_default() += 1;
    }

    /// Counts a malformed message of `topic`, keeping the topic's first description.
    pub fn malformed_on(&mut self, topic: &str, description: &str) {
        let (n, _) = self.malformed_by_topic.entry(topic.to_owned()).or_insert_with(|| (0, description.to_owned()));
        *n += 1;
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use ros2::msgs::sensor_msgs::NavSatFix;
    use std::f64::consts::PI;

    fn transform(stamp: i64) -> Transform {
        Transform {
            stamp: Stamp(stamp),
            parent: "odom".into(),
            child: "base_link".into(),
            translation: [0.0; 3],
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn beam_angles_that_cannot_be_placed_are_named() {
        let scan = |angle_min: f64, angle_increment: f64, angle_max: f32, n: usize| {
            crate::testdata::scan_message(Stamp(1), angle_min, angle_increment, angle_max, vec![1.0; n])
        };
        let inc = std::f64::consts::PI / 720.0;
        let half = std::f32::consts::FRAC_PI_2;
        let a0 = std::f64::consts::FRAC_PI_2;
        // ±90° at 0.25° is 721 beams; a driver's rounding of one beam either way is kept.
        for n in [720, 721, 722] {
            assert_eq!(scan(-a0, inc, half, n).angle_fault(), None, "{n}");
        }
        // CARMEN states no angle_max: the count decides the angles.
        assert_eq!(scan(-a0, inc, f32::NAN, 181).angle_fault(), None);
        // A negative increment sweeping clockwise is a real layout.
        assert_eq!(scan(a0, -inc, -half, 721).angle_fault(), None);
        for (bad, what) in [
            (scan(-1.57, 0.0, half, 721), "angle_increment is 0"),
            (scan(-1.57, f64::NAN, half, 721), "angle_increment is NaN"),
            (scan(-1.57, 1e-50, f32::NAN, 721), "angle_increment is 0"),
            (scan(-1.57, 1e39, f32::NAN, 721), "angle_increment is inf"),
            (scan(f64::INFINITY, inc, half, 721), "angle_min is inf"),
            (scan(-a0, inc, half, 1442), "1442 ranges"),
            (scan(-a0, inc, half, 360), "is 721.0 beams"),
        ] {
            let why = bad.angle_fault().expect(what);
            assert!(why.contains(what), "{what}: {why}");
        }
    }

    #[test]
    fn topic_and_stamps_of_every_kind() {
        let receive = Some(Stamp(99));
        let messages = [
            LogMessage::Scan(ScanMessage {
                receive_stamp: receive,
                ..crate::testdata::scan_message(Stamp(1), 0.0, 0.1, f32::NAN, vec![])
            }),
            LogMessage::Odometry(OdomMessage {
                topic: "/odom".into(),
                stamp: Stamp(2),
                receive_stamp: receive,
                frame_id: "odom".into(),
                child_frame_id: "base_link".into(),
                pose: Pose2::IDENTITY,
                pose_covariance: [0.0; 36],
                twist: [0.0; 6],
                twist_covariance: [0.0; 36],
            }),
            LogMessage::Tf(TfMessage {
                topic: "/tf".into(),
                is_static: false,
                receive_stamp: receive,
                transforms: vec![transform(3), transform(30)],
            }),
            LogMessage::Imu(ImuMessage {
                topic: "/imu".into(),
                stamp: Stamp(4),
                receive_stamp: receive,
                frame_id: "imu".into(),
                orientation: [0.0, 0.0, 0.0, 1.0],
                angular_velocity: [0.0; 3],
                linear_acceleration: [0.0; 3],
                orientation_covariance: [-1.0; 9],
                angular_velocity_covariance: [0.0; 9],
                linear_acceleration_covariance: [0.0; 9],
            }),
            LogMessage::Gnss(GnssMessage {
                topic: "/fix".into(),
                stamp: Stamp(5),
                receive_stamp: receive,
                frame_id: "gps".into(),
                status: NavSatStatus::STATUS_FIX,
                service: NavSatStatus::SERVICE_GPS,
                latitude: 0.0,
                longitude: 0.0,
                altitude: 0.0,
                position_covariance: [0.0; 9],
                position_covariance_type: NavSatFix::COVARIANCE_TYPE_UNKNOWN,
            }),
            LogMessage::Pose(PoseMessage {
                topic: "/amcl_pose".into(),
                stamp: Stamp(6),
                receive_stamp: receive,
                frame_id: "map".into(),
                position: [0.0; 3],
                orientation: [0.0, 0.0, 0.0, 1.0],
                covariance: [0.0; 36],
            }),
        ];
        let topics: Vec<&str> = messages.iter().map(LogMessage::topic).collect();
        assert_eq!(topics, ["/scan", "/odom", "/tf", "/imu", "/fix", "/amcl_pose"]);
        let stamps: Vec<Option<Stamp>> = messages.iter().map(LogMessage::stamp).collect();
        assert_eq!(stamps, [1, 2, 3, 4, 5, 6].map(|s| Some(Stamp(s))));
        assert!(messages.iter().all(|m| m.receive_stamp() == receive));

        let empty =
            LogMessage::Tf(TfMessage { topic: "/tf".into(), is_static: true, receive_stamp: None, transforms: vec![] });
        assert_eq!((empty.stamp(), empty.receive_stamp()), (None, None));
    }

    #[test]
    fn a_degenerate_quaternion_gives_a_nan_heading_not_the_identity() {
        for q in [[0.0; 4], [f64::NAN, 0.0, 0.0, 1.0], [0.0, 0.0, f64::INFINITY, 1.0], [0.0, 0.0, 0.0, f64::NAN]] {
            let p = planar_pose([1.0, 2.0, 3.0], q);
            assert!(p.theta.is_nan(), "{q:?}: {p:?}");
            assert_eq!((p.x, p.y), (1.0, 2.0));
            assert!(!p.is_finite());
        }
    }

    proptest! {
        /// A rotation about z by `yaw`, at any positive scale, gives back `yaw` (the ROS
        /// quaternion of a planar heading, as `tf2::Quaternion::setRPY(0, 0, yaw)` makes it).
        #[test]
        fn planar_pose_recovers_the_yaw_of_any_scaled_z_rotation(
            yaw in -(PI - 1e-6)..(PI - 1e-6),
            scale in 1e-3f64..1e3,
            x in -1e6f64..1e6,
            y in -1e6f64..1e6,
        ) {
            let q = [0.0, 0.0, scale * (yaw / 2.0).sin(), scale * (yaw / 2.0).cos()];
            let p = planar_pose([x, y, 0.0], q);
            prop_assert_eq!((p.x, p.y), (x, y));
            prop_assert!((p.theta - yaw).abs() < 1e-9, "{} vs {}", p.theta, yaw);
        }

        /// A quaternion that is unit up to rounding gives exactly what
        /// `quaternion_yaw` gives (what every reader gave before it normalised).
        #[test]
        fn a_unit_quaternion_is_used_as_written(yaw in -(PI - 1e-6)..(PI - 1e-6)) {
            let q = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
            prop_assert_eq!(planar_pose([0.0; 3], q).theta.to_bits(), quaternion_yaw(q).to_bits());
        }
    }
}
