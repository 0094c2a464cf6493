//! `sensor_msgs`: laser scans, inertial measurements, satellite fixes, camera images and
//! camera calibration.

use super::geometry_msgs::{QUATERNION, VECTOR3};
use super::std_msgs::{Header, HEADER};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

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

/// `sensor_msgs/msg/LaserScan`: one sweep of a planar range finder. Beam `i` points at
/// `angle_min + i * angle_increment` (counter-clockwise about z, REP 103) and was measured
/// `i * time_increment` after `header.stamp`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LaserScan {
    /// Stamp of the first beam; the sensor frame.
    pub header: Header,
    /// Angle of the first beam, rad.
    pub angle_min: f32,
    /// Angle of the last beam, rad.
    pub angle_max: f32,
    /// Angle between neighbouring beams, rad.
    pub angle_increment: f32,
    /// Time between neighbouring beams, s.
    pub time_increment: f32,
    /// Time between two scans, s.
    pub scan_time: f32,
    /// Shortest valid range, m.
    pub range_min: f32,
    /// Longest valid range, m.
    pub range_max: f32,
    /// Distances, m, one per beam (written bit for bit: NaN and ±inf keep their meaning).
    pub ranges: Vec<f32>,
    /// Return strengths, one per beam, or empty.
    pub intensities: Vec<f32>,
}

/// `sensor_msgs/msg/Imu`. A covariance whose first element is -1 marks the quantity as
/// not measured; all zeros means unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct Imu {
    /// Stamp and the IMU's frame.
    pub header: Header,
    /// Orientation quaternion `[x, y, z, w]` in a fixed frame.
    pub orientation: [f64; 4],
    /// Row-major 3×3 covariance about x, y, z, rad².
    pub orientation_covariance: [f64; 9],
    /// Angular velocity, rad/s.
    pub angular_velocity: [f64; 3],
    /// Row-major 3×3 covariance of `angular_velocity`.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration, m/s² (gravity included).
    pub linear_acceleration: [f64; 3],
    /// Row-major 3×3 covariance of `linear_acceleration`.
    pub linear_acceleration_covariance: [f64; 9],
}

impl Default for Imu {
    fn default() -> Self {
        Self {
            header: Header::default(),
            orientation: [0.0, 0.0, 0.0, 1.0],
            orientation_covariance: [0.0; 9],
            angular_velocity: [0.0; 3],
            angular_velocity_covariance: [0.0; 9],
            linear_acceleration: [0.0; 3],
            linear_acceleration_covariance: [0.0; 9],
        }
    }
}

/// `sensor_msgs/msg/NavSatStatus`: whether there is a fix, and from which systems.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavSatStatus {
    /// One of the `STATUS_*` constants.
    pub status: i8,
    /// A bit set of the `SERVICE_*` constants.
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

/// `sensor_msgs/msg/NavSatFix`: a WGS 84 position from a satellite receiver.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NavSatFix {
    /// Stamp and the antenna's frame.
    pub header: Header,
    /// Fix status.
    pub status: NavSatStatus,
    /// Latitude, degrees, positive north.
    pub latitude: f64,
    /// Longitude, degrees, positive east.
    pub longitude: f64,
    /// Altitude above the WGS 84 ellipsoid, m (NaN when unknown).
    pub altitude: f64,
    /// Row-major 3×3 covariance in the local ENU tangent plane, m².
    pub position_covariance: [f64; 9],
    /// One of the `COVARIANCE_TYPE_*` constants.
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

/// `sensor_msgs/msg/Image`: an uncompressed image, row after row.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Image {
    /// Stamp of acquisition; the camera's optical frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`rgb8`, `mono8`, `16UC1`, … from `sensor_msgs/image_encodings.hpp`).
    pub encoding: String,
    /// 1 when multi-byte pixels are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step * height` bytes.
    pub data: Vec<u8>,
}

/// `sensor_msgs/msg/RegionOfInterest`: a sub-window of the full image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RegionOfInterest {
    /// Leftmost column.
    pub x_offset: u32,
    /// Topmost row.
    pub y_offset: u32,
    /// Rows (0: the full image).
    pub height: u32,
    /// Columns (0: the full image).
    pub width: u32,
    /// True when the ROI is to be rectified.
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`: pinhole calibration (Hartley & Zisserman's `K`, `R`,
/// `P`) and lens distortion of a camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfo {
    /// Stamp of the image it describes; the camera's optical frame.
    pub header: Header,
    /// Image rows at calibration.
    pub height: u32,
    /// Image columns at calibration.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`, …
    pub distortion_model: String,
    /// Distortion parameters, as many as the model has.
    pub d: Vec<f64>,
    /// Row-major 3×3 intrinsic matrix.
    pub k: [f64; 9],
    /// Row-major 3×3 rectification rotation (stereo).
    pub r: [f64; 9],
    /// Row-major 3×4 projection matrix.
    pub p: [f64; 12],
    /// Horizontal binning (0 or 1: none).
    pub binning_x: u32,
    /// Vertical binning.
    pub binning_y: u32,
    /// The region of interest.
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
        w.f64_array(&self.orientation);
        w.f64_array(&self.orientation_covariance);
        w.f64_array(&self.angular_velocity);
        w.f64_array(&self.angular_velocity_covariance);
        w.f64_array(&self.linear_acceleration);
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

impl CdrEncode for Image {
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
