//! The messages of a recording: the ROS message structs fusemap's reader decodes and its
//! writer encodes ([`fusemap_io::log::ros2::msgs`], one struct per message type), each
//! with the topic it is published on. The simulator fills them field by field as a
//! robot's drivers would; writing the bag is then only a matter of encoding them.
//! Quaternions are `(x, y, z, w)`, covariances row-major.

use fusemap_core::geometry::{quaternion_yaw, Mount3, Pose2};
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::geometry_msgs::{Transform, TransformStamped};
use fusemap_io::log::ros2::msgs::nav_msgs::Odometry;
use fusemap_io::log::ros2::msgs::sensor_msgs::{CameraInfo, Image, Imu, LaserScan, NavSatFix};
use fusemap_io::log::ros2::msgs::std_msgs::Header;
use std::ops::{Deref, DerefMut};

/// The quaternion `(x, y, z, w)` of REP 103 roll, pitch, yaw (`Rz·Ry·Rx`).
pub fn rpy_to_quaternion(roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    let (sr, cr) = (roll / 2.0).sin_cos();
    let (sp, cp) = (pitch / 2.0).sin_cos();
    let (sy, cy) = (yaw / 2.0).sin_cos();
    [sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy]
}

/// A 6×6 row-major covariance with `diag` on its diagonal.
pub fn diagonal6(diag: [f64; 6]) -> [f64; 36] {
    let mut c = [0.0; 36];
    for (i, d) in diag.into_iter().enumerate() {
        c[i * 7] = d;
    }
    c
}

/// A 3×3 row-major covariance with `diag` on its diagonal.
pub fn diagonal3(diag: [f64; 3]) -> [f64; 9] {
    let mut c = [0.0; 9];
    for (i, d) in diag.into_iter().enumerate() {
        c[i * 4] = d;
    }
    c
}

/// A message and the topic it is published on. It dereferences to the message, so its
/// fields read as on the ROS type (`scan.ranges`, `fix.header.stamp`).
#[derive(Clone, Debug, PartialEq)]
pub struct OnTopic<T> {
    /// The topic.
    pub topic: String,
    /// The message.
    pub msg: T,
}

impl<T> OnTopic<T> {
    /// `msg` on `topic`.
    pub fn new(topic: impl Into<String>, msg: T) -> Self {
        Self { topic: topic.into(), msg }
    }
}

impl<T> Deref for OnTopic<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.msg
    }
}

impl<T> DerefMut for OnTopic<T> {
    fn deref_mut(&mut self) -> &mut T {
        &mut self.msg
    }
}

/// `sensor_msgs/LaserScan`; ranges follow REP 117: `+inf` no return, NaN or 0 an invalid
/// reading; intensities in arbitrary units (glass 10, machine 40, wall 50, steel 90).
pub type SimScan = OnTopic<LaserScan>;
/// `nav_msgs/Odometry`: `odom_from_base` and the body-frame twist.
pub type SimOdometry = OnTopic<Odometry>;
/// `sensor_msgs/Imu` without orientation (REP 145: `orientation_covariance[0] = -1`);
/// specific force with gravity (+9.81 on z at rest).
pub type SimImu = OnTopic<Imu>;
/// `sensor_msgs/NavSatFix`: GBAS_FIX good, FIX degraded, NO_FIX dropout; the covariance
/// is the zone's nominal σ, never the unreported outliers.
pub type SimFix = OnTopic<NavSatFix>;
/// One `geometry_msgs/TransformStamped` of `/tf_static`: `parent_from_child`.
pub type SimStaticTransform = OnTopic<TransformStamped>;
/// `sensor_msgs/Image`: labels (`mono8`, `mono16`) or depth (`32FC1`, `16UC1`).
pub type SimImage = OnTopic<Image<'static>>;
/// `sensor_msgs/CameraInfo` of a pinhole camera (`plumb_bob`, no distortion).
pub type SimCameraInfo = OnTopic<CameraInfo>;

impl SimOdometry {
    /// The planar pose `odom_from_base`.
    pub fn pose2(&self) -> Pose2 {
        let p = &self.msg.pose.pose;
        Pose2::new(p.position.x, p.position.y, quaternion_yaw(p.orientation.to_array()))
    }
}

impl SimStaticTransform {
    /// A mount as a static transform.
    pub fn from_mount(stamp: Stamp, topic: &str, parent: &str, child: &str, m: &Mount3) -> Self {
        let transform = Transform {
            translation: [m.x, m.y, m.z].into(),
            rotation: rpy_to_quaternion(m.roll, m.pitch, m.yaw).into(),
        };
        OnTopic::new(
            topic,
            TransformStamped { header: Header::new(stamp, parent), child_frame_id: child.into(), transform },
        )
    }
}

/// Any message of a recording.
#[derive(Clone, Debug, PartialEq)]
pub enum SimMessage {
    /// A lidar scan.
    Scan(SimScan),
    /// Wheel odometry (boxed: its two 6×6 covariances would make every message 760 bytes).
    Odometry(Box<SimOdometry>),
    /// IMU sample (boxed, as odometry).
    Imu(Box<SimImu>),
    /// GNSS fix.
    Fix(SimFix),
    /// A static mount.
    StaticTransform(SimStaticTransform),
    /// A camera image (labels or depth).
    Image(SimImage),
    /// A camera calibration (boxed: its matrices would make every message 300 bytes).
    CameraInfo(Box<SimCameraInfo>),
}

impl SimMessage {
    /// The message's header.
    pub fn header(&self) -> &Header {
        match self {
            SimMessage::Scan(m) => &m.header,
            SimMessage::Odometry(m) => &m.header,
            SimMessage::Imu(m) => &m.header,
            SimMessage::Fix(m) => &m.header,
            SimMessage::StaticTransform(m) => &m.header,
            SimMessage::Image(m) => &m.header,
            SimMessage::CameraInfo(m) => &m.header,
        }
    }

    /// Header stamp.
    pub fn stamp(&self) -> Stamp {
        self.header().stamp
    }

    /// Topic.
    pub fn topic(&self) -> &str {
        match self {
            SimMessage::Scan(m) => &m.topic,
            SimMessage::Odometry(m) => &m.topic,
            SimMessage::Imu(m) => &m.topic,
            SimMessage::Fix(m) => &m.topic,
            SimMessage::StaticTransform(m) => &m.topic,
            SimMessage::Image(m) => &m.topic,
            SimMessage::CameraInfo(m) => &m.topic,
        }
    }

    /// Header frame.
    pub fn frame_id(&self) -> &str {
        &self.header().frame_id
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::geometry::quaternion_to_rpy;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn quaternion_round_trips_rpy(r in -3.0..3.0f64, p in -1.5..1.5f64, y in -3.0..3.0f64) {
            let q = rpy_to_quaternion(r, p, y);
            let n: f64 = q.iter().map(|v| v * v).sum();
            prop_assert!((n - 1.0).abs() < 1e-12);
            let (r2, p2, y2) = quaternion_to_rpy(q);
            prop_assert!((r2 - r).abs() < 1e-9 && (p2 - p).abs() < 1e-9 && (y2 - y).abs() < 1e-9);
        }
    }

    #[test]
    fn diagonals() {
        let c = diagonal6([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!((c[0], c[7], c[35], c[1]), (1.0, 2.0, 6.0, 0.0));
        let c = diagonal3([1.0, 2.0, 3.0]);
        assert_eq!((c[0], c[4], c[8], c[3]), (1.0, 2.0, 3.0, 0.0));
    }
}
