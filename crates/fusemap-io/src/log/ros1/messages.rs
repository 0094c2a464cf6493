//! ROS 1 message payloads fusemap uses, decoded straight into its own types.
//!
//! ROS 1 serialisation is the fields in order, little-endian, with no padding; strings
//! and variable-length arrays start with a `u32` length; `time` is `u32` seconds and
//! `u32` nanoseconds; `std_msgs/Header` is `u32 seq`, `time stamp`, `string frame_id`.
//! A layout is only valid for the definition it was written with, so each type carries
//! the MD5 sum ROS computes from its standard definition and connections whose sum
//! differs are refused.

use super::cursor::{Cursor, Malformed};
use crate::log::{
    check_image_layout, planar_pose, CameraInfoMessage, GnssMessage, ImageHeader, ImageMessage, ImuMessage, LogMessage,
    OdomMessage, PoseMessage, ScanMessage, TfMessage, Transform,
};
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;

/// A message type this reader decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// `sensor_msgs/LaserScan`.
    LaserScan,
    /// `nav_msgs/Odometry`.
    Odometry,
    /// `tf2_msgs/TFMessage` or `tf/tfMessage` (the same definition).
    Tf,
    /// `sensor_msgs/Imu`.
    Imu,
    /// `sensor_msgs/NavSatFix`.
    NavSatFix,
    /// `geometry_msgs/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped,
    /// `sensor_msgs/Image`.
    Image,
    /// `sensor_msgs/CameraInfo`.
    CameraInfo,
}

impl Kind {
    /// The kind for a connection's `type`, with the MD5 sum of the standard definition
    /// (ROS's sum over the definition text with nested types replaced by their sums;
    /// the values `rosmsg md5` prints).
    pub(super) fn from_type(ty: &[u8]) -> Option<(Kind, &'static str)> {
        Some(match ty {
            b"sensor_msgs/LaserScan" => (Kind::LaserScan, "90c7ef2dc6895d81024acba2ac42f369"),
            b"nav_msgs/Odometry" => (Kind::Odometry, "cd5e73d190d741a2f92e81eda573aca7"),
            b"tf2_msgs/TFMessage" | b"tf/tfMessage" => (Kind::Tf, "94810edda583a504dfda3829e70d7eec"),
            b"sensor_msgs/Imu" => (Kind::Imu, "6a62c6daae103f4ff57a132d6f95cec2"),
            b"sensor_msgs/NavSatFix" => (Kind::NavSatFix, "2d3a8cd499b9b4a0249fb98fd05cfa48"),
            b"geometry_msgs/PoseWithCovarianceStamped" => {
                (Kind::PoseWithCovarianceStamped, "953b798c0f514ff060a53a3498ce6246")
            }
            b"sensor_msgs/Image" => (Kind::Image, "060021388200f6f0f447d0fcd9c64743"),
            b"sensor_msgs/CameraInfo" => (Kind::CameraInfo, "c9a58c1b0b154e0e6da7578cb991d214"),
            _ => return None,
        })
    }

    /// Short name for error messages.
    fn name(self) -> &'static str {
        match self {
            Kind::LaserScan => "LaserScan",
            Kind::Odometry => "Odometry",
            Kind::Tf => "TFMessage",
            Kind::Imu => "Imu",
            Kind::NavSatFix => "NavSatFix",
            Kind::PoseWithCovarianceStamped => "PoseWithCovarianceStamped",
            Kind::Image => "Image",
            Kind::CameraInfo => "CameraInfo",
        }
    }
}

/// Bytes of one `geometry_msgs/TransformStamped` with empty frame names: the least an
/// element of a TF array can take.
const MIN_TRANSFORM_SIZE: usize = 4 + 8 + 4 + 4 + 7 * 8;

/// Decodes one message payload of `kind` published on `topic` and logged at `receive`;
/// an image's pixels are copied only with `pixels` (else it is an [`ImageHeader`]).
pub(super) fn decode(
    kind: Kind,
    topic: &str,
    receive: Stamp,
    payload: &[u8],
    pixels: bool,
) -> Result<LogMessage, Malformed> {
    let mut c = Cursor::new(payload);
    let receive_stamp = Some(receive);
    let message = match kind {
        Kind::LaserScan => scan(&mut c, topic, receive_stamp).map(LogMessage::Scan),
        Kind::Odometry => odometry(&mut c, topic, receive_stamp).map(LogMessage::Odometry),
        Kind::Tf => tf(&mut c, topic, receive_stamp).map(LogMessage::Tf),
        Kind::Imu => imu(&mut c, topic, receive_stamp).map(LogMessage::Imu),
        Kind::NavSatFix => nav_sat_fix(&mut c, topic, receive_stamp).map(LogMessage::Gnss),
        Kind::PoseWithCovarianceStamped => pose_with_covariance(&mut c, topic, receive_stamp).map(LogMessage::Pose),
        Kind::Image => image(&mut c, topic, receive_stamp, pixels),
        Kind::CameraInfo => camera_info(&mut c, topic, receive_stamp).map(LogMessage::CameraInfo),
    }
    .map_err(|e| e.context(kind.name()))?;
    if !c.is_empty() {
        return Err(Malformed(format!(
            "{}: {} bytes left over after the message's last field (the layout differs \
             from the standard definition)",
            kind.name(),
            c.remaining()
        )));
    }
    Ok(message)
}

/// `std_msgs/Header`: the stamp and frame; `seq` is skipped.
fn header(c: &mut Cursor<'_>) -> Result<(Stamp, String), Malformed> {
    c.u32("header.seq")?;
    let stamp = c.time("header.stamp")?;
    let frame = c.string("header.frame_id")?;
    Ok((stamp, frame))
}

fn scan(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<ScanMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let angle_min = c.f32("angle_min")?;
    let angle_max = c.f32("angle_max")?;
    let angle_increment = c.f32("angle_increment")?;
    let time_increment = c.f32("time_increment")?;
    let scan_time = c.f32("scan_time")?;
    let range_min = c.f32("range_min")?;
    let range_max = c.f32("range_max")?;
    let ranges = c.f32_vec("ranges")?;
    c.skip_f32_array("intensities")?;
    Ok(ScanMessage {
        topic: topic.to_string(),
        frame_id,
        receive_stamp,
        scan: LaserScan { stamp, angle_min: f64::from(angle_min), angle_increment: f64::from(angle_increment), ranges },
        angle_max,
        time_increment,
        scan_time,
        range_min,
        range_max,
        pose: None,
        odom_pose: None,
        laser_pose: None,
    })
}

fn odometry(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<OdomMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let child_frame_id = c.string("child_frame_id")?;
    let position = c.f64s::<3>("pose.pose.position")?;
    let orientation = c.f64s::<4>("pose.pose.orientation")?;
    let pose_covariance = c.f64s::<36>("pose.covariance")?;
    let twist = c.f64s::<6>("twist.twist")?;
    let twist_covariance = c.f64s::<36>("twist.covariance")?;
    Ok(OdomMessage {
        topic: topic.to_string(),
        stamp,
        receive_stamp,
        frame_id,
        child_frame_id,
        pose: planar_pose(position, orientation),
        pose_covariance,
        twist,
        twist_covariance,
    })
}

fn tf(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<TfMessage, Malformed> {
    let n = c.array_len(MIN_TRANSFORM_SIZE, "transforms")?;
    let mut transforms =
        crate::bounded::vec_with_capacity(n).map_err(|e| Malformed(format!("no memory for {n} transforms ({e})")))?;
    for i in 0..n {
        let t = transform(c).map_err(|e| e.context(format_args!("transforms[{i}]")))?;
        transforms.push(t);
    }
    Ok(TfMessage { topic: topic.to_string(), is_static: topic == "/tf_static", receive_stamp, transforms })
}

/// `geometry_msgs/TransformStamped`.
fn transform(c: &mut Cursor<'_>) -> Result<Transform, Malformed> {
    let (stamp, parent) = header(c)?;
    let child = c.string("child_frame_id")?;
    let translation = c.f64s::<3>("transform.translation")?;
    let rotation = c.f64s::<4>("transform.rotation")?;
    Ok(Transform { stamp, parent, child, translation, rotation })
}

fn imu(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<ImuMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let orientation = c.f64s::<4>("orientation")?;
    let orientation_covariance = c.f64s::<9>("orientation_covariance")?;
    let angular_velocity = c.f64s::<3>("angular_velocity")?;
    let angular_velocity_covariance = c.f64s::<9>("angular_velocity_covariance")?;
    let linear_acceleration = c.f64s::<3>("linear_acceleration")?;
    let linear_acceleration_covariance = c.f64s::<9>("linear_acceleration_covariance")?;
    Ok(ImuMessage {
        topic: topic.to_string(),
        stamp,
        receive_stamp,
        frame_id,
        orientation,
        angular_velocity,
        linear_acceleration,
        orientation_covariance,
        angular_velocity_covariance,
        linear_acceleration_covariance,
    })
}

/// `sensor_msgs/NavSatFix`: header; `NavSatStatus status` (`int8 status`, `uint16
/// service`); latitude, longitude, altitude; `float64[9] position_covariance`; `uint8
/// position_covariance_type`. Values are passed on as written, NaN included.
fn nav_sat_fix(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<GnssMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let status = i8::from_le_bytes(c.array::<1>("status.status")?);
    let service = u16::from_le_bytes(c.array::<2>("status.service")?);
    let [latitude, longitude, altitude] = c.f64s::<3>("latitude, longitude and altitude")?;
    let position_covariance = c.f64s::<9>("position_covariance")?;
    let [position_covariance_type] = c.array::<1>("position_covariance_type")?;
    Ok(GnssMessage {
        topic: topic.to_string(),
        stamp,
        receive_stamp,
        frame_id,
        status,
        service,
        latitude,
        longitude,
        altitude,
        position_covariance,
        position_covariance_type,
    })
}

/// `geometry_msgs/PoseWithCovarianceStamped`: header; `PoseWithCovariance pose`
/// (`Pose pose` = position, orientation; `float64[36] covariance`).
fn pose_with_covariance(
    c: &mut Cursor<'_>,
    topic: &str,
    receive_stamp: Option<Stamp>,
) -> Result<PoseMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let position = c.f64s::<3>("pose.pose.position")?;
    let orientation = c.f64s::<4>("pose.pose.orientation")?;
    let covariance = c.f64s::<36>("pose.covariance")?;
    Ok(PoseMessage { topic: topic.to_string(), stamp, receive_stamp, frame_id, position, orientation, covariance })
}

/// `sensor_msgs/Image`: header; `uint32 height`, `uint32 width`; `string encoding`;
/// `uint8 is_bigendian`; `uint32 step`; `uint8[] data`. The layout is checked
/// ([`check_image_layout`]) before the pixels are copied, and they are copied only with
/// `pixels`.
fn image(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>, pixels: bool) -> Result<LogMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let height = c.u32("height")?;
    let width = c.u32("width")?;
    let encoding = c.string("encoding")?;
    let [is_bigendian] = c.array::<1>("is_bigendian")?;
    let step = c.u32("step")?;
    let data = c.prefixed("data")?;
    check_image_layout(width, height, &encoding, step, data.len() as u64).map_err(Malformed)?;
    let topic = topic.to_string();
    let is_bigendian = is_bigendian != 0;
    Ok(if pixels {
        LogMessage::Image(ImageMessage {
            topic,
            stamp,
            receive_stamp,
            frame_id,
            width,
            height,
            encoding,
            is_bigendian,
            step,
            data: data.to_vec(),
        })
    } else {
        LogMessage::ImageHeader(ImageHeader {
            topic,
            stamp,
            receive_stamp,
            frame_id,
            width,
            height,
            encoding,
            is_bigendian,
            step,
            data_len: data.len() as u64,
        })
    })
}

/// `sensor_msgs/CameraInfo`: header; `uint32 height`, `uint32 width`; `string
/// distortion_model`; `float64[] D`; `float64[9] K`, `float64[9] R`, `float64[12] P`;
/// `uint32 binning_x`, `uint32 binning_y`; `RegionOfInterest roi` (four `uint32`, a
/// `bool`). R, P, binning and roi are read past.
fn camera_info(c: &mut Cursor<'_>, topic: &str, receive_stamp: Option<Stamp>) -> Result<CameraInfoMessage, Malformed> {
    let (stamp, frame_id) = header(c)?;
    let height = c.u32("height")?;
    let width = c.u32("width")?;
    let distortion_model = c.string("distortion_model")?;
    let d = c.f64_vec("D")?;
    let k = c.f64s::<9>("K")?;
    c.f64s::<9>("R")?;
    c.f64s::<12>("P")?;
    c.u32("binning_x")?;
    c.u32("binning_y")?;
    c.take(4 * 4 + 1, "roi")?;
    Ok(CameraInfoMessage {
        topic: topic.to_string(),
        stamp,
        receive_stamp,
        frame_id,
        width,
        height,
        distortion_model,
        d,
        k,
    })
}
