//! `sensor_msgs`: planar laser scans, inertial measurements and satellite navigation fixes.

use super::geometry_msgs::{Quaternion, Vector3};
use super::std_msgs::Header;
use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};

/// `sensor_msgs/msg/LaserScan`: one sweep of a planar range finder.
///
/// Beam `i` points at `angle_min + i * angle_increment` in the sensor frame (counter-
/// clockwise about z, 0 along x) and was measured `i * time_increment` after
/// `header.stamp`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LaserScan {
    /// `stamp` is the time of the first beam; `frame_id` the sensor frame.
    pub header: Header,
    /// Angle of the first beam, rad.
    pub angle_min: f32,
    /// Angle of the last beam, rad.
    pub angle_max: f32,
    /// Angle between neighbouring beams, rad.
    pub angle_increment: f32,
    /// Time between neighbouring beams, s (for de-skewing while the sensor moves).
    pub time_increment: f32,
    /// Time between two scans, s.
    pub scan_time: f32,
    /// Shortest range the sensor reports, m.
    pub range_min: f32,
    /// Longest range the sensor reports, m; values outside `[range_min, range_max]`
    /// are not valid returns.
    pub range_max: f32,
    /// Measured distances, m, one per beam.
    pub ranges: Vec<f32>,
    /// Return strengths in a sensor-specific unit, one per beam, or empty.
    pub intensities: Vec<f32>,
}

impl CdrDecode for LaserScan {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            angle_min: r.f32("angle_min")?,
            angle_max: r.f32("angle_max")?,
            angle_increment: r.f32("angle_increment")?,
            time_increment: r.f32("time_increment")?,
            scan_time: r.f32("scan_time")?,
            range_min: r.f32("range_min")?,
            range_max: r.f32("range_max")?,
            ranges: r.f32_seq("ranges")?,
            intensities: r.f32_seq("intensities")?,
        })
    }
}

/// `sensor_msgs/msg/Imu`: orientation, angular velocity and linear acceleration from an
/// inertial unit, each with a covariance.
///
/// A covariance whose first element is -1 marks the quantity as not measured; all zeros
/// means the covariance is unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct Imu {
    /// Stamp and the IMU's frame.
    pub header: Header,
    /// Orientation of the IMU frame in a fixed frame.
    pub orientation: Quaternion,
    /// Row-major 3×3 covariance about x, y, z, rad².
    pub orientation_covariance: [f64; 9],
    /// Angular velocity, rad/s.
    pub angular_velocity: Vector3,
    /// Row-major 3×3 covariance of `angular_velocity`.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration, m/s² (gravity included).
    pub linear_acceleration: Vector3,
    /// Row-major 3×3 covariance of `linear_acceleration`.
    pub linear_acceleration_covariance: [f64; 9],
}

impl CdrDecode for Imu {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            orientation: r.decode_field("orientation")?,
            orientation_covariance: r.f64_array("orientation_covariance")?,
            angular_velocity: r.decode_field("angular_velocity")?,
            angular_velocity_covariance: r.f64_array("angular_velocity_covariance")?,
            linear_acceleration: r.decode_field("linear_acceleration")?,
            linear_acceleration_covariance: r.f64_array("linear_acceleration_covariance")?,
        })
    }
}

/// `sensor_msgs/msg/NavSatStatus`: whether the receiver has a fix, and from which
/// satellite systems.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavSatStatus {
    /// -1 no fix, 0 fix, 1 SBAS-augmented fix, 2 GBAS-augmented fix.
    pub status: i8,
    /// Bit set: 1 GPS, 2 GLONASS, 4 COMPASS, 8 Galileo.
    pub service: u16,
}

/// `sensor_msgs/msg/NavSatFix`: a WGS 84 position from a satellite navigation receiver.
#[derive(Clone, Debug, PartialEq)]
pub struct NavSatFix {
    /// Stamp and the antenna's frame.
    pub header: Header,
    /// Fix status and services.
    pub status: NavSatStatus,
    /// Latitude, degrees (north positive).
    pub latitude: f64,
    /// Longitude, degrees (east positive).
    pub longitude: f64,
    /// Altitude above the WGS 84 ellipsoid, m.
    pub altitude: f64,
    /// Row-major 3×3 covariance in the East-North-Up tangent plane, m².
    pub position_covariance: [f64; 9],
    /// 0 unknown, 1 approximated, 2 diagonal known, 3 known.
    pub position_covariance_type: u8,
}

impl CdrDecode for NavSatStatus {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { status: r.i8("status")?, service: r.u16("service")? })
    }
}

impl CdrDecode for NavSatFix {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            status: r.decode_field("status")?,
            latitude: r.f64("latitude")?,
            longitude: r.f64("longitude")?,
            altitude: r.f64("altitude")?,
            position_covariance: r.f64_array("position_covariance")?,
            position_covariance_type: r.u8("position_covariance_type")?,
        })
    }
}
