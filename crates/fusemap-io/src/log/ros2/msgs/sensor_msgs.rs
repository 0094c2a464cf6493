//! `sensor_msgs`: planar laser scans, inertial measurements, satellite navigation fixes,
//! camera images and calibrations.

use super::geometry_msgs::{Quaternion, Vector3};
use super::std_msgs::Header;
use crate::log::check_image_layout;
use crate::log::ros2::cdr::{check_encapsulation, CdrDecode, CdrError, CdrReader};

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

/// `sensor_msgs/msg/Image`: an uncompressed image, pixel (0, 0) at the top left, with its
/// pixels borrowed from the payload (so that reading the header costs no copy).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image<'a> {
    /// Acquisition time; `frame_id` is the camera's optical frame (z forward, x right,
    /// y down).
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`sensor_msgs/image_encodings.h` names: `mono8`, `16UC1`, …).
    pub encoding: String,
    /// Non-zero when multi-byte pixels are big-endian.
    pub is_bigendian: u8,
    /// Full row length, bytes.
    pub step: u32,
    /// The pixels, `step × height` bytes.
    pub data: &'a [u8],
}

impl<'a> Image<'a> {
    /// Reads the fields in declaration order and checks the layout
    /// ([`check_image_layout`]): an image whose sizes do not fit its data is an error at
    /// its `data` field.
    pub fn decode(r: &mut CdrReader<'a>) -> Result<Self, CdrError> {
        let header = r.decode_field("header")?;
        let height = r.u32("height")?;
        let width = r.u32("width")?;
        let encoding = r.string("encoding")?;
        let is_bigendian = r.u8("is_bigendian")?;
        let step = r.u32("step")?;
        let at = r.position();
        let data = r.u8_seq("data")?;
        check_image_layout(width, height, &encoding, step, data.len() as u64)
            .map_err(|e| r.invalid_at("data", at, e))?;
        Ok(Self { header, height, width, encoding, is_bigendian, step, data })
    }

    /// Decodes a whole payload (encapsulation header included).
    pub fn from_payload(payload: &'a [u8]) -> Result<Self, CdrError> {
        let body = check_encapsulation(payload)?;
        Self::decode(&mut CdrReader::new(body))
    }
}

/// `sensor_msgs/msg/RegionOfInterest`: a rectangle of the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RegionOfInterest {
    /// Leftmost column.
    pub x_offset: u32,
    /// Topmost row.
    pub y_offset: u32,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// True when the region is to be rectified.
    pub do_rectify: bool,
}

impl CdrDecode for RegionOfInterest {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            x_offset: r.u32("x_offset")?,
            y_offset: r.u32("y_offset")?,
            height: r.u32("height")?,
            width: r.u32("width")?,
            do_rectify: r.u8("do_rectify")? != 0,
        })
    }
}

/// `sensor_msgs/msg/CameraInfo`: the calibration of a camera (pinhole intrinsics `k`,
/// distortion `d` of `distortion_model`, rectification `r`, projection `p`).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfo {
    /// Stamp and the optical frame.
    pub header: Header,
    /// Image rows the calibration is for.
    pub height: u32,
    /// Image columns the calibration is for.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`, …
    pub distortion_model: String,
    /// Distortion parameters, as many as the model has.
    pub d: Vec<f64>,
    /// Row-major 3 × 3 intrinsics `fx 0 cx; 0 fy cy; 0 0 1`.
    pub k: [f64; 9],
    /// Row-major 3 × 3 rectification rotation (stereo).
    pub r: [f64; 9],
    /// Row-major 3 × 4 projection of the rectified image.
    pub p: [f64; 12],
    /// Horizontal binning, 0 or 1 for none.
    pub binning_x: u32,
    /// Vertical binning.
    pub binning_y: u32,
    /// The region of the full image this calibration covers.
    pub roi: RegionOfInterest,
}

impl CdrDecode for CameraInfo {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            height: r.u32("height")?,
            width: r.u32("width")?,
            distortion_model: r.string("distortion_model")?,
            d: r.f64_seq("d")?,
            k: r.f64_array("k")?,
            r: r.f64_array("r")?,
            p: r.f64_array("p")?,
            binning_x: r.u32("binning_x")?,
            binning_y: r.u32("binning_y")?,
            roi: r.decode_field("roi")?,
        })
    }
}
