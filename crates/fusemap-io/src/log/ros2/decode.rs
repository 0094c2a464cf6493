//! Decoding the messages fusemap uses into [`LogMessage`]s: CDR payloads of ROS 2 by
//! their type name here, and ROS 1 payloads through the same [`On::read`].

use super::cdr::{check_encapsulation, CdrError, CdrReader};
use super::msgs;
use super::msgs::wire::{FieldReader, RosMsg};
use crate::log::{
    planar_pose, CameraInfoMessage, GnssMessage, ImageHeader, ImageMessage, ImuMessage, LogMessage, OdomMessage,
    PoseMessage, ScanMessage, TfMessage, Transform,
};
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;

/// The kinds of ROS 2 message fusemap decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KnownType {
    /// `sensor_msgs/msg/LaserScan`.
    LaserScan,
    /// `nav_msgs/msg/Odometry`.
    Odometry,
    /// `tf2_msgs/msg/TFMessage`.
    TfMessage,
    /// `sensor_msgs/msg/Imu`.
    Imu,
    /// `sensor_msgs/msg/NavSatFix`.
    NavSatFix,
    /// `geometry_msgs/msg/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped,
    /// `sensor_msgs/msg/Image`.
    Image,
    /// `sensor_msgs/msg/CameraInfo`.
    CameraInfo,
}

impl KnownType {
    /// All of them, for tests and fuzzing.
    pub const ALL: [KnownType; 8] = [
        KnownType::LaserScan,
        KnownType::Odometry,
        KnownType::TfMessage,
        KnownType::Imu,
        KnownType::NavSatFix,
        KnownType::PoseWithCovarianceStamped,
        KnownType::Image,
        KnownType::CameraInfo,
    ];

    /// The type from its ROS 2 name (`sensor_msgs/msg/LaserScan`); the ROS 1 spelling
    /// without `/msg/` is accepted too. `None` for types fusemap does not use.
    pub fn from_name(type_name: &str) -> Option<Self> {
        match type_name {
            "sensor_msgs/msg/LaserScan" | "sensor_msgs/LaserScan" => Some(KnownType::LaserScan),
            "nav_msgs/msg/Odometry" | "nav_msgs/Odometry" => Some(KnownType::Odometry),
            "tf2_msgs/msg/TFMessage" | "tf2_msgs/TFMessage" => Some(KnownType::TfMessage),
            "sensor_msgs/msg/Imu" | "sensor_msgs/Imu" => Some(KnownType::Imu),
            "sensor_msgs/msg/NavSatFix" | "sensor_msgs/NavSatFix" => Some(KnownType::NavSatFix),
            "geometry_msgs/msg/PoseWithCovarianceStamped" | "geometry_msgs/PoseWithCovarianceStamped" => {
                Some(KnownType::PoseWithCovarianceStamped)
            }
            "sensor_msgs/msg/Image" | "sensor_msgs/Image" => Some(KnownType::Image),
            "sensor_msgs/msg/CameraInfo" | "sensor_msgs/CameraInfo" => Some(KnownType::CameraInfo),
            _ => None,
        }
    }

    /// The ROS 2 type name.
    pub fn name(self) -> &'static str {
        match self {
            KnownType::LaserScan => "sensor_msgs/msg/LaserScan",
            KnownType::Odometry => "nav_msgs/msg/Odometry",
            KnownType::TfMessage => "tf2_msgs/msg/TFMessage",
            KnownType::Imu => "sensor_msgs/msg/Imu",
            KnownType::NavSatFix => "sensor_msgs/msg/NavSatFix",
            KnownType::PoseWithCovarianceStamped => "geometry_msgs/msg/PoseWithCovarianceStamped",
            KnownType::Image => "sensor_msgs/msg/Image",
            KnownType::CameraInfo => "sensor_msgs/msg/CameraInfo",
        }
    }
}

/// Decodes one CDR payload (encapsulation header included) of type `kind` received on
/// `topic` into fusemap's message type; an image with its pixels.
pub fn decode_known(
    kind: KnownType,
    topic: &str,
    receive_stamp: Option<Stamp>,
    payload: &[u8],
) -> std::result::Result<LogMessage, CdrError> {
    decode_known_with(kind, topic, receive_stamp, payload, true)
}

/// [`decode_known`], with an image's pixels copied only with `pixels` (else it becomes
/// an [`ImageHeader`]; its layout is checked either way).
pub fn decode_known_with(
    kind: KnownType,
    topic: &str,
    receive_stamp: Option<Stamp>,
    payload: &[u8],
    pixels: bool,
) -> std::result::Result<LogMessage, CdrError> {
    let body = check_encapsulation(payload)?;
    On { topic, receive_stamp }.read(kind, &mut CdrReader::new(body), pixels)
}

/// Where a decoded ROS message arrived: its topic and, when the container says, when it
/// was logged. Its methods turn each message struct into fusemap's message type; the ROS 1
/// and ROS 2 readers both use them.
pub(crate) struct On<'a> {
    /// The topic it was published on.
    pub(crate) topic: &'a str,
    /// When the log recorded it.
    pub(crate) receive_stamp: Option<Stamp>,
}

impl On<'_> {
    /// Reads one message of `kind` from `r` (whichever its wire format) into fusemap's
    /// message type; an image's pixels are copied only with `pixels`.
    pub(crate) fn read<'a, R: FieldReader<'a>>(
        &self,
        kind: KnownType,
        r: &mut R,
        pixels: bool,
    ) -> Result<LogMessage, R::Error> {
        use msgs::sensor_msgs::Image;
        Ok(match kind {
            KnownType::LaserScan => LogMessage::Scan(self.scan(RosMsg::read(r)?)),
            KnownType::Odometry => LogMessage::Odometry(self.odometry(RosMsg::read(r)?)),
            KnownType::TfMessage => LogMessage::Tf(self.tf(RosMsg::read(r)?)),
            KnownType::Imu => LogMessage::Imu(self.imu(RosMsg::read(r)?)),
            KnownType::NavSatFix => LogMessage::Gnss(self.fix(RosMsg::read(r)?)),
            KnownType::PoseWithCovarianceStamped => LogMessage::Pose(self.pose(RosMsg::read(r)?)),
            KnownType::Image => self.image(Image::read(r)?, pixels),
            KnownType::CameraInfo => LogMessage::CameraInfo(self.camera_info(RosMsg::read(r)?)),
        })
    }
}

impl On<'_> {
    fn scan(&self, m: msgs::sensor_msgs::LaserScan) -> ScanMessage {
        ScanMessage {
            topic: self.topic.to_owned(),
            frame_id: m.header.frame_id,
            receive_stamp: self.receive_stamp,
            scan: LaserScan {
                stamp: m.header.stamp,
                angle_min: f64::from(m.angle_min),
                angle_increment: f64::from(m.angle_increment),
                ranges: m.ranges,
            },
            angle_max: m.angle_max,
            time_increment: m.time_increment,
            scan_time: m.scan_time,
            range_min: m.range_min,
            range_max: m.range_max,
            pose: None,
            odom_pose: None,
            laser_pose: None,
        }
    }

    fn odometry(&self, m: msgs::nav_msgs::Odometry) -> OdomMessage {
        let p = m.pose.pose;
        let t = m.twist.twist;
        OdomMessage {
            topic: self.topic.to_owned(),
            stamp: m.header.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: m.header.frame_id,
            child_frame_id: m.child_frame_id,
            pose: planar_pose(p.position.to_array(), p.orientation.to_array()),
            pose_covariance: m.pose.covariance,
            twist: [t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z],
            twist_covariance: m.twist.covariance,
        }
    }

    fn tf(&self, m: msgs::tf2_msgs::TfMessage) -> TfMessage {
        TfMessage {
            topic: self.topic.to_owned(),
            is_static: self.topic == "/tf_static",
            receive_stamp: self.receive_stamp,
            transforms: m
                .transforms
                .into_iter()
                .map(|t| Transform {
                    stamp: t.header.stamp,
                    parent: t.header.frame_id,
                    child: t.child_frame_id,
                    translation: t.transform.translation.to_array(),
                    rotation: t.transform.rotation.to_array(),
                })
                .collect(),
        }
    }

    fn imu(&self, m: msgs::sensor_msgs::Imu) -> ImuMessage {
        ImuMessage {
            topic: self.topic.to_owned(),
            stamp: m.header.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: m.header.frame_id,
            orientation: m.orientation.to_array(),
            angular_velocity: m.angular_velocity.to_array(),
            linear_acceleration: m.linear_acceleration.to_array(),
            orientation_covariance: m.orientation_covariance,
            angular_velocity_covariance: m.angular_velocity_covariance,
            linear_acceleration_covariance: m.linear_acceleration_covariance,
        }
    }

    fn fix(&self, m: msgs::sensor_msgs::NavSatFix) -> GnssMessage {
        GnssMessage {
            topic: self.topic.to_owned(),
            stamp: m.header.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: m.header.frame_id,
            status: m.status.status,
            service: m.status.service,
            latitude: m.latitude,
            longitude: m.longitude,
            altitude: m.altitude,
            position_covariance: m.position_covariance,
            position_covariance_type: m.position_covariance_type,
        }
    }

    fn pose(&self, m: msgs::geometry_msgs::PoseWithCovarianceStamped) -> PoseMessage {
        let p = m.pose.pose;
        PoseMessage {
            topic: self.topic.to_owned(),
            stamp: m.header.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: m.header.frame_id,
            position: p.position.to_array(),
            orientation: p.orientation.to_array(),
            covariance: m.pose.covariance,
        }
    }

    /// An image with its pixels, or only its header without `pixels`.
    fn image(&self, m: msgs::sensor_msgs::Image<'_>, pixels: bool) -> LogMessage {
        let (topic, stamp, receive_stamp) = (self.topic.to_owned(), m.header.stamp, self.receive_stamp);
        let is_bigendian = m.is_bigendian != 0;
        let frame_id = m.header.frame_id;
        if pixels {
            LogMessage::Image(ImageMessage {
                topic,
                stamp,
                receive_stamp,
                frame_id,
                width: m.width,
                height: m.height,
                encoding: m.encoding,
                is_bigendian,
                step: m.step,
                data: m.data.into_owned(),
            })
        } else {
            LogMessage::ImageHeader(ImageHeader {
                topic,
                stamp,
                receive_stamp,
                frame_id,
                width: m.width,
                height: m.height,
                encoding: m.encoding,
                is_bigendian,
                step: m.step,
                data_len: m.data.len() as u64,
            })
        }
    }

    fn camera_info(&self, m: msgs::sensor_msgs::CameraInfo) -> CameraInfoMessage {
        CameraInfoMessage {
            topic: self.topic.to_owned(),
            stamp: m.header.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: m.header.frame_id,
            width: m.width,
            height: m.height,
            distortion_model: m.distortion_model,
            d: m.d,
            k: m.k,
        }
    }
}

/// Decodes a payload by its ROS type name: `Ok(None)` for a type fusemap does not use.
pub fn decode_message(
    type_name: &str,
    topic: &str,
    receive_stamp: Option<Stamp>,
    payload: &[u8],
) -> std::result::Result<Option<LogMessage>, CdrError> {
    match KnownType::from_name(type_name) {
        Some(kind) => decode_known(kind, topic, receive_stamp, payload).map(Some),
        None => Ok(None),
    }
}
