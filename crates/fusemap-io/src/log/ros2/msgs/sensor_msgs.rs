//! `sensor_msgs`: planar laser scans, inertial measurements, satellite navigation fixes,
//! camera images and calibrations (read and written), and the point clouds and compressed
//! images fusemap writes beside its maps.

use super::geometry_msgs::{Quaternion, Vector3, QUATERNION, VECTOR3};
use super::std_msgs::{Header, HEADER};
use super::wire::{FieldReader, RosMsg};
use crate::log::check_image_layout;
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;
use std::borrow::Cow;

/// `sensor_msgs/LaserScan`.
pub static LASER_SCAN: MsgDef = MsgDef {
    name: "sensor_msgs/LaserScan",
    text: "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
           float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n\
           float32[] ranges\nfloat32[] intensities\n",
    deps: &[&HEADER],
};
/// `sensor_msgs/Imu`.
pub static IMU: MsgDef = MsgDef {
    name: "sensor_msgs/Imu",
    text: "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n\
           geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n\
           geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
    deps: &[&HEADER, &QUATERNION, &VECTOR3],
};
/// `sensor_msgs/NavSatStatus`.
pub static NAV_SAT_STATUS: MsgDef = MsgDef {
    name: "sensor_msgs/NavSatStatus",
    text: "int8 STATUS_NO_FIX=-1\nint8 STATUS_FIX=0\nint8 STATUS_SBAS_FIX=1\nint8 STATUS_GBAS_FIX=2\n\
           uint16 SERVICE_GPS=1\nuint16 SERVICE_GLONASS=2\nuint16 SERVICE_COMPASS=4\nuint16 SERVICE_GALILEO=8\n\
           int8 status\nuint16 service\n",
    deps: &[],
};
/// `sensor_msgs/NavSatFix`.
pub static NAV_SAT_FIX: MsgDef = MsgDef {
    name: "sensor_msgs/NavSatFix",
    text: "uint8 COVARIANCE_TYPE_UNKNOWN=0\nuint8 COVARIANCE_TYPE_APPROXIMATED=1\n\
           uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN=2\nuint8 COVARIANCE_TYPE_KNOWN=3\nstd_msgs/Header header\n\
           sensor_msgs/NavSatStatus status\nfloat64 latitude\nfloat64 longitude\nfloat64 altitude\n\
           float64[9] position_covariance\nuint8 position_covariance_type\n",
    deps: &[&HEADER, &NAV_SAT_STATUS],
};
/// `sensor_msgs/Image`.
pub static IMAGE: MsgDef = MsgDef {
    name: "sensor_msgs/Image",
    text: "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n\
           uint32 step\nuint8[] data\n",
    deps: &[&HEADER],
};
/// `sensor_msgs/RegionOfInterest`.
pub static REGION_OF_INTEREST: MsgDef = MsgDef {
    name: "sensor_msgs/RegionOfInterest",
    text: "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
    deps: &[],
};
/// `sensor_msgs/CameraInfo`.
pub static CAMERA_INFO: MsgDef = MsgDef {
    name: "sensor_msgs/CameraInfo",
    text: "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n\
           float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n\
           sensor_msgs/RegionOfInterest roi\n",
    deps: &[&HEADER, &REGION_OF_INTEREST],
};

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

impl RosMsg for LaserScan {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
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
#[derive(Clone, Debug, Default, PartialEq)]
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

impl RosMsg for Imu {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            orientation: r.message("orientation")?,
            orientation_covariance: r.f64_array("orientation_covariance")?,
            angular_velocity: r.message("angular_velocity")?,
            angular_velocity_covariance: r.f64_array("angular_velocity_covariance")?,
            linear_acceleration: r.message("linear_acceleration")?,
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

impl NavSatStatus {
    /// No fix.
    pub const STATUS_NO_FIX: i8 = -1;
    /// Unaugmented fix.
    pub const STATUS_FIX: i8 = 0;
    /// Fix with satellite-based augmentation.
    pub const STATUS_SBAS_FIX: i8 = 1;
    /// Fix with ground-based augmentation (RTK, DGPS).
    pub const STATUS_GBAS_FIX: i8 = 2;
    /// GPS.
    pub const SERVICE_GPS: u16 = 1;
    /// GLONASS.
    pub const SERVICE_GLONASS: u16 = 2;
    /// BeiDou (COMPASS).
    pub const SERVICE_COMPASS: u16 = 4;
    /// Galileo.
    pub const SERVICE_GALILEO: u16 = 8;
}

/// `sensor_msgs/msg/NavSatFix`: a WGS 84 position from a satellite navigation receiver.
#[derive(Clone, Debug, Default, PartialEq)]
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

impl NavSatFix {
    /// Covariance unknown.
    pub const COVARIANCE_TYPE_UNKNOWN: u8 = 0;
    /// Covariance approximated.
    pub const COVARIANCE_TYPE_APPROXIMATED: u8 = 1;
    /// Only the diagonal is known.
    pub const COVARIANCE_TYPE_DIAGONAL_KNOWN: u8 = 2;
    /// The full covariance is known.
    pub const COVARIANCE_TYPE_KNOWN: u8 = 3;
}

impl RosMsg for NavSatStatus {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { status: r.i8("status")?, service: r.u16("service")? })
    }
}

impl RosMsg for NavSatFix {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            status: r.message("status")?,
            latitude: r.f64("latitude")?,
            longitude: r.f64("longitude")?,
            altitude: r.f64("altitude")?,
            position_covariance: r.f64_array("position_covariance")?,
            position_covariance_type: r.u8("position_covariance_type")?,
        })
    }
}

/// `sensor_msgs/msg/Image`: an uncompressed image, row after row, pixel (0, 0) at the top
/// left. Read, its pixels are borrowed from the payload (so reading the header costs no
/// copy); to be written, they may be owned.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
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
    pub data: Cow<'a, [u8]>,
}

impl<'a> Image<'a> {
    /// Reads the fields in declaration order and checks the layout
    /// ([`check_image_layout`]): an image whose sizes do not fit its data is an error at
    /// its `data` field.
    pub fn read<R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        let header = r.message("header")?;
        let height = r.u32("height")?;
        let width = r.u32("width")?;
        let encoding = r.string("encoding")?;
        let is_bigendian = r.u8("is_bigendian")?;
        let step = r.u32("step")?;
        let at = r.position();
        let data = r.u8_seq("data")?;
        check_image_layout(width, height, &encoding, step, data.len() as u64)
            .map_err(|e| r.invalid_at("data", at, e))?;
        Ok(Self { header, height, width, encoding, is_bigendian, step, data: Cow::Borrowed(data) })
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

impl RosMsg for RegionOfInterest {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
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
/// distortion `d` of `distortion_model`, rectification `r`, projection `p`; Hartley &
/// Zisserman's `K`, `R`, `P`).
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

impl Default for CameraInfo {
    fn default() -> Self {
        Self {
            header: Header::default(),
            height: 0,
            width: 0,
            distortion_model: String::new(),
            d: Vec::new(),
            k: [0.0; 9],
            r: [0.0; 9],
            p: [0.0; 12],
            binning_x: 0,
            binning_y: 0,
            roi: RegionOfInterest::default(),
        }
    }
}

impl RosMsg for CameraInfo {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            height: r.u32("height")?,
            width: r.u32("width")?,
            distortion_model: r.string("distortion_model")?,
            d: r.f64_seq("d")?,
            k: r.f64_array("k")?,
            r: r.f64_array("r")?,
            p: r.f64_array("p")?,
            binning_x: r.u32("binning_x")?,
            binning_y: r.u32("binning_y")?,
            roi: r.message("roi")?,
        })
    }
}

impl CdrEncode for LaserScan {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        w.f32_seq("ranges", &self.ranges)?;
        w.f32_seq("intensities", &self.intensities)
    }
}

impl CdrEncode for Imu {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        self.orientation.encode(w)?;
        w.f64_array(&self.orientation_covariance);
        self.angular_velocity.encode(w)?;
        w.f64_array(&self.angular_velocity_covariance);
        self.linear_acceleration.encode(w)?;
        w.f64_array(&self.linear_acceleration_covariance);
        Ok(())
    }
}

impl CdrEncode for NavSatFix {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.i8(self.status.status);
        w.u16(self.status.service);
        w.f64(self.latitude);
        w.f64(self.longitude);
        w.f64(self.altitude);
        w.f64_array(&self.position_covariance);
        w.u8(self.position_covariance_type);
        Ok(())
    }
}

impl CdrEncode for Image<'_> {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.u32(self.height);
        w.u32(self.width);
        w.string("encoding", &self.encoding)?;
        w.u8(self.is_bigendian);
        w.u32(self.step);
        w.bytes("data", &self.data)
    }
}

impl CdrEncode for CameraInfo {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.u32(self.height);
        w.u32(self.width);
        w.string("distortion_model", &self.distortion_model)?;
        w.f64_seq("d", &self.d)?;
        w.f64_array(&self.k);
        w.f64_array(&self.r);
        w.f64_array(&self.p);
        w.u32(self.binning_x);
        w.u32(self.binning_y);
        w.u32(self.roi.x_offset);
        w.u32(self.roi.y_offset);
        w.u32(self.roi.height);
        w.u32(self.roi.width);
        w.bool(self.roi.do_rectify);
        Ok(())
    }
}

/// `sensor_msgs/PointField`.
pub static POINT_FIELD: MsgDef = MsgDef {
    name: "sensor_msgs/PointField",
    text: "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\n\
           uint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
    deps: &[],
};
/// `sensor_msgs/PointCloud2`.
pub static POINT_CLOUD2: MsgDef = MsgDef {
    name: "sensor_msgs/PointCloud2",
    text: "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n\
           bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
    deps: &[&HEADER, &POINT_FIELD],
};
/// `sensor_msgs/CompressedImage`.
pub static COMPRESSED_IMAGE: MsgDef = MsgDef {
    name: "sensor_msgs/CompressedImage",
    text: "std_msgs/Header header\nstring format\nuint8[] data\n",
    deps: &[&HEADER],
};

/// `sensor_msgs/msg/PointField`: one field of a [`PointCloud2`]'s points. Written only.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PointField {
    /// Its name (`x`, `intensity`, …).
    pub name: String,
    /// Byte offset in the point.
    pub offset: u32,
    /// Element type, one of the constants ([`PointField::FLOAT32`], …).
    pub datatype: u8,
    /// Elements.
    pub count: u32,
}

impl PointField {
    /// `uint16`.
    pub const UINT16: u8 = 4;
    /// `float32`.
    pub const FLOAT32: u8 = 7;
}

/// `sensor_msgs/msg/PointCloud2`: points as packed records described by their fields.
/// Written only.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud2 {
    /// Stamp and frame.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// The record layout.
    pub fields: Vec<PointField>,
    /// Multi-byte fields are big-endian.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The records.
    pub data: Vec<u8>,
    /// No invalid (NaN) points.
    pub is_dense: bool,
}

/// `sensor_msgs/msg/CompressedImage`: an encoded image (PNG, JPEG). Written only, empty,
/// inside markers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// `png`, `jpeg`.
    pub format: String,
    /// The encoded bytes.
    pub data: Vec<u8>,
}

impl CdrEncode for PointField {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.string("name", &self.name)?;
        w.u32(self.offset);
        w.u8(self.datatype);
        w.u32(self.count);
        Ok(())
    }
}

impl CdrEncode for PointCloud2 {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.u32(self.height);
        w.u32(self.width);
        w.seq("fields", &self.fields)?;
        w.bool(self.is_bigendian);
        w.u32(self.point_step);
        w.u32(self.row_step);
        w.bytes("data", &self.data)?;
        w.bool(self.is_dense);
        Ok(())
    }
}

impl CdrEncode for CompressedImage {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("format", &self.format)?;
        w.bytes("data", &self.data)
    }
}
