//! Plain-Rust mirrors of the ROS messages a recording holds. Field names and meanings
//! follow the `.msg` definitions so a writer fills `sensor_msgs/LaserScan`,
//! `nav_msgs/Odometry`, `sensor_msgs/Imu`, `sensor_msgs/NavSatFix`, `sensor_msgs/Image`,
//! `sensor_msgs/CameraInfo` and `tf2_msgs/TFMessage` one field at a time. Quaternions are `(x, y, z, w)`,
//! covariances row-major.

use fusemap_core::geometry::{quaternion_yaw, Mount3, Pose2};
use fusemap_core::time::Stamp;

/// `sensor_msgs/NavSatStatus.STATUS_NO_FIX`.
pub const STATUS_NO_FIX: i8 = -1;
/// `sensor_msgs/NavSatStatus.STATUS_FIX`: unaugmented (here: a float RTK solution).
pub const STATUS_FIX: i8 = 0;
/// `sensor_msgs/NavSatStatus.STATUS_SBAS_FIX`.
pub const STATUS_SBAS_FIX: i8 = 1;
/// `sensor_msgs/NavSatStatus.STATUS_GBAS_FIX`: ground-based augmentation (RTK fixed).
pub const STATUS_GBAS_FIX: i8 = 2;
/// `sensor_msgs/NavSatStatus.SERVICE_GPS`.
pub const SERVICE_GPS: u16 = 1;
/// `sensor_msgs/NavSatStatus.SERVICE_GALILEO`.
pub const SERVICE_GALILEO: u16 = 8;
/// `sensor_msgs/NavSatFix.COVARIANCE_TYPE_UNKNOWN`.
pub const COVARIANCE_TYPE_UNKNOWN: u8 = 0;
/// `sensor_msgs/NavSatFix.COVARIANCE_TYPE_DIAGONAL_KNOWN`.
pub const COVARIANCE_TYPE_DIAGONAL_KNOWN: u8 = 2;

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

/// `sensor_msgs/LaserScan`. Ranges follow REP 117: `+inf` no return, NaN or 0 an
/// invalid reading.
#[derive(Clone, Debug, PartialEq)]
pub struct SimScan {
    /// Header stamp: the sensor clock at the first beam.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (the laser).
    pub frame_id: String,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Time between beams, seconds: beam `i` was measured at `stamp + i·time_increment`.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres.
    pub ranges: Vec<f32>,
    /// Return intensities (arbitrary units: glass 10, machine 40, wall 50, steel 90).
    pub intensities: Vec<f32>,
}

/// `nav_msgs/Odometry`: `odom_from_base` and the body-frame twist.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOdometry {
    /// Header stamp.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (`odom`).
    pub frame_id: String,
    /// Child frame (`base_link`).
    pub child_frame_id: String,
    /// Position, metres.
    pub position: [f64; 3],
    /// Orientation quaternion `(x, y, z, w)`.
    pub orientation: [f64; 4],
    /// Pose covariance (x, y, z, roll, pitch, yaw), row-major 6×6.
    pub pose_covariance: [f64; 36],
    /// Linear velocity in the child frame, m/s.
    pub linear: [f64; 3],
    /// Angular velocity in the child frame, rad/s.
    pub angular: [f64; 3],
    /// Twist covariance, row-major 6×6.
    pub twist_covariance: [f64; 36],
}

impl SimOdometry {
    /// The planar pose `odom_from_base`.
    pub fn pose2(&self) -> Pose2 {
        Pose2::new(self.position[0], self.position[1], quaternion_yaw(self.orientation))
    }
}

/// `sensor_msgs/Imu` without orientation (REP 145: `orientation_covariance[0] = -1`).
#[derive(Clone, Debug, PartialEq)]
pub struct SimImu {
    /// Header stamp.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (`imu_link`).
    pub frame_id: String,
    /// Orientation: identity, and unused (see `orientation_covariance`).
    pub orientation: [f64; 4],
    /// `[-1, 0, …]`: no orientation estimate.
    pub orientation_covariance: [f64; 9],
    /// Angular velocity in the IMU frame, rad/s.
    pub angular_velocity: [f64; 3],
    /// Its covariance, row-major 3×3.
    pub angular_velocity_covariance: [f64; 9],
    /// Specific force in the IMU frame (gravity included: +9.81 on z at rest), m/s².
    pub linear_acceleration: [f64; 3],
    /// Its covariance, row-major 3×3.
    pub linear_acceleration_covariance: [f64; 9],
}

/// `sensor_msgs/NavSatFix`.
#[derive(Clone, Debug, PartialEq)]
pub struct SimFix {
    /// Header stamp.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (the antenna, `gps`).
    pub frame_id: String,
    /// `NavSatStatus.status`: GBAS_FIX (2) good, FIX (0) degraded, NO_FIX (-1) dropout.
    pub status: i8,
    /// `NavSatStatus.service` bit mask.
    pub service: u16,
    /// WGS84 latitude, degrees (NaN without a fix).
    pub latitude: f64,
    /// WGS84 longitude, degrees (NaN without a fix).
    pub longitude: f64,
    /// Ellipsoidal height, metres (NaN without a fix).
    pub altitude: f64,
    /// ENU position covariance, m², row-major 3×3: the zone's nominal σ, never the
    /// unreported outliers.
    pub position_covariance: [f64; 9],
    /// `COVARIANCE_TYPE_*`.
    pub position_covariance_type: u8,
}

/// One `geometry_msgs/TransformStamped` of `/tf_static`: `parent_from_child`.
#[derive(Clone, Debug, PartialEq)]
pub struct SimStaticTransform {
    /// Header stamp.
    pub stamp: Stamp,
    /// Topic (`/tf_static`).
    pub topic: String,
    /// Parent frame (header frame).
    pub frame_id: String,
    /// Child frame.
    pub child_frame_id: String,
    /// Translation, metres.
    pub translation: [f64; 3],
    /// Rotation quaternion `(x, y, z, w)`.
    pub rotation: [f64; 4],
}

impl SimStaticTransform {
    /// A mount as a static transform.
    pub fn from_mount(stamp: Stamp, topic: &str, parent: &str, child: &str, m: &Mount3) -> Self {
        Self {
            stamp,
            topic: topic.into(),
            frame_id: parent.into(),
            child_frame_id: child.into(),
            translation: [m.x, m.y, m.z],
            rotation: rpy_to_quaternion(m.roll, m.pitch, m.yaw),
        }
    }
}

/// `sensor_msgs/Image`: an uncompressed image, row after row.
#[derive(Clone, Debug, PartialEq)]
pub struct SimImage {
    /// Header stamp: the camera clock at exposure.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (the camera's optical frame).
    pub frame_id: String,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// `mono8`, `mono16` (labels), `32FC1`, `16UC1` (depth).
    pub encoding: String,
    /// 1 when multi-byte pixels are big-endian (here always 0).
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step · height` bytes.
    pub data: Vec<u8>,
}

/// `sensor_msgs/CameraInfo` of a pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct SimCameraInfo {
    /// Header stamp: that of the images it describes.
    pub stamp: Stamp,
    /// Topic.
    pub topic: String,
    /// Header frame (the camera's optical frame).
    pub frame_id: String,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// `plumb_bob`.
    pub distortion_model: String,
    /// Distortion coefficients (k1, k2, t1, t2, k3): all zero.
    pub d: Vec<f64>,
    /// Intrinsic matrix, row-major 3×3.
    pub k: [f64; 9],
    /// Rectification rotation, row-major 3×3 (identity).
    pub r: [f64; 9],
    /// Projection matrix, row-major 3×4.
    pub p: [f64; 12],
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
    /// Header stamp.
    pub fn stamp(&self) -> Stamp {
        match self {
            SimMessage::Scan(m) => m.stamp,
            SimMessage::Odometry(m) => m.stamp,
            SimMessage::Imu(m) => m.stamp,
            SimMessage::Fix(m) => m.stamp,
            SimMessage::StaticTransform(m) => m.stamp,
            SimMessage::Image(m) => m.stamp,
            SimMessage::CameraInfo(m) => m.stamp,
        }
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
        match self {
            SimMessage::Scan(m) => &m.frame_id,
            SimMessage::Odometry(m) => &m.frame_id,
            SimMessage::Imu(m) => &m.frame_id,
            SimMessage::Fix(m) => &m.frame_id,
            SimMessage::StaticTransform(m) => &m.frame_id,
            SimMessage::Image(m) => &m.frame_id,
            SimMessage::CameraInfo(m) => &m.frame_id,
        }
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
