//! The camera's table of the scenario (`[camera]`, `[camera.backlight]`).

use crate::checks::{finite, non_negative, positive, probability};
use fusemap_core::field_error::FieldError;
use fusemap_core::geometry::{Mount3, Pose3};
use serde::{Deserialize, Serialize};

/// How label images are encoded (`sensor_msgs/image_encodings`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum LabelEncoding {
    /// One byte per pixel.
    #[default]
    #[serde(rename = "mono8")]
    Mono8,
    /// Two bytes per pixel, little-endian.
    #[serde(rename = "mono16")]
    Mono16,
}

impl LabelEncoding {
    /// The `encoding` string of `sensor_msgs/Image`.
    pub fn as_str(self) -> &'static str {
        match self {
            LabelEncoding::Mono8 => "mono8",
            LabelEncoding::Mono16 => "mono16",
        }
    }
}

/// How depth images are encoded (REP 118).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DepthEncoding {
    /// `32FC1`: metres as 32-bit floats, NaN for no depth.
    #[default]
    #[serde(rename = "32FC1")]
    Float32Metres,
    /// `16UC1`: millimetres as unsigned 16-bit integers, 0 for no depth.
    #[serde(rename = "16UC1")]
    U16Millimetres,
}

impl DepthEncoding {
    /// The `encoding` string of `sensor_msgs/Image`.
    pub fn as_str(self) -> &'static str {
        match self {
            DepthEncoding::Float32Metres => "32FC1",
            DepthEncoding::U16Millimetres => "16UC1",
        }
    }
}

/// Backlight through the windows (the design document's opening picture): when the
/// camera faces the window, a segmentation network labels part of the bright floor as an
/// obstacle, in smooth blobs that drift from frame to frame. The depth is unaffected: the
/// floor is still the floor, which is why geometry must decide occupancy (§2.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BacklightConfig {
    /// Whether the effect happens at all.
    pub enabled: bool,
    /// Heading the camera looks along when it faces the windows, degrees (ENU: 0 east).
    pub window_yaw_deg: f64,
    /// The effect happens while the optical axis heading is within this angle of
    /// `window_yaw_deg`, degrees.
    pub half_angle_deg: f64,
    /// Share of the floor pixels mislabelled in a backlit frame.
    pub floor_share: f64,
    /// Class name the blobs get (one of the class table's).
    pub class: String,
    /// Size of the blobs: lattice spacing of the noise field, pixels.
    pub blob_scale_px: f64,
    /// Time over which the field changes completely, seconds (the blobs drift smoothly).
    pub blob_period_s: f64,
}

impl Default for BacklightConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            window_yaw_deg: 0.0,
            half_angle_deg: 30.0,
            floor_share: 0.25,
            class: "wall".into(),
            blob_scale_px: 48.0,
            blob_period_s: 4.0,
        }
    }
}

/// The semantic RGB-D camera: a per-pixel class-label image, an aligned depth image and
/// `sensor_msgs/CameraInfo` (pinhole, `plumb_bob` with zero distortion).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Whether the camera records at all.
    pub enabled: bool,
    /// Topic of the label images.
    pub label_topic: String,
    /// Topic of the depth images.
    pub depth_topic: String,
    /// Topic of the calibration, one message per frame.
    pub info_topic: String,
    /// Frames per second.
    pub rate_hz: f64,
    /// Image columns.
    pub width: u32,
    /// Image rows.
    pub height: u32,
    /// Horizontal field of view, degrees. Pixels are square (`fy = fx`) and the principal
    /// point is the image centre, `((width − 1) / 2, (height − 1) / 2)` in the ROS pixel
    /// convention (integer coordinates at pixel centres).
    pub hfov_deg: f64,
    /// `base_link → camera` body mount (x forward, y left, z up, REP 103 RPY; a positive
    /// pitch looks down). The published optical frame adds the fixed REP 103 rotation
    /// (z forward, x right, y down).
    pub mount: Mount3,
    /// Label image encoding.
    pub label_encoding: LabelEncoding,
    /// Depth image encoding.
    pub depth_encoding: DepthEncoding,
    /// The sensor clock minus true time, seconds: header stamps are `true time + offset`.
    pub time_offset_s: f64,
    /// Longest depth reported, metres; beyond it depth is "none" (the label is still given).
    pub max_depth_m: f64,
    /// Depth noise σ = `depth_sigma_k · d²` (stereo and structured-light depth error grows
    /// with the square of the depth: Khoshelham & Elberink 2012).
    pub depth_sigma_k: f64,
    /// Probability that a pixel's label is replaced by a uniformly random class id in
    /// 1..=6 (salt noise of a segmentation network).
    pub label_noise_probability: f64,
    /// Probability that a pixel looking at glass gets the glass's depth; otherwise it gets
    /// the depth of what lies behind (transmission). The label stays `glass` either way.
    pub glass_depth_probability: f64,
    /// The backlight effect.
    pub backlight: BacklightConfig,
}

impl Default for CameraConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            label_topic: "/camera/labels".into(),
            depth_topic: "/camera/depth".into(),
            info_topic: "/camera/camera_info".into(),
            rate_hz: 10.0,
            width: 320,
            height: 240,
            hfov_deg: 70.0,
            mount: Mount3 { x: 0.25, y: 0.0, z: 1.0, roll: 0.0, pitch: 25f64.to_radians(), yaw: 0.0 },
            label_encoding: LabelEncoding::Mono8,
            depth_encoding: DepthEncoding::Float32Metres,
            time_offset_s: 0.0,
            max_depth_m: 8.0,
            depth_sigma_k: 0.005,
            label_noise_probability: 0.01,
            glass_depth_probability: 0.5,
            backlight: BacklightConfig::default(),
        }
    }
}

/// Most image bytes (labels and depth together) a run may hold in memory.
pub const MAX_CAMERA_BYTES: f64 = 8e9;

/// The fixed rotation `camera_from_camera_optical` of REP 103: optical z is the body's x
/// (forward), optical x the body's −y (right), optical y the body's −z (down); as RPY
/// `(−π/2, 0, −π/2)`.
pub fn optical_rotation() -> [f64; 4] {
    use std::f64::consts::FRAC_PI_2;
    Mount3 { roll: -FRAC_PI_2, yaw: -FRAC_PI_2, ..Mount3::default() }.quaternion()
}

impl CameraConfig {
    /// The intrinsic matrix `K` (row-major): `fx = (width / 2) / tan(hfov / 2)`, `fy = fx`.
    pub fn k_matrix(&self) -> [f64; 9] {
        let fx = f64::from(self.width) / 2.0 / (self.hfov_deg.to_radians() / 2.0).tan();
        let (cx, cy) = ((f64::from(self.width) - 1.0) / 2.0, (f64::from(self.height) - 1.0) / 2.0);
        [fx, 0.0, cx, 0.0, fx, cy, 0.0, 0.0, 1.0]
    }

    /// `base_from_camera_optical`: the body mount composed with [`optical_rotation`].
    pub fn base_from_optical(&self) -> Pose3 {
        let m = &self.mount;
        Pose3::new([m.x, m.y, m.z], m.quaternion()).compose(&Pose3::new([0.0; 3], optical_rotation()))
    }

    pub(crate) fn validate(&self, duration_s: f64) -> Result<(), FieldError> {
        for (field, v) in [
            ("camera.label_topic", &self.label_topic),
            ("camera.depth_topic", &self.depth_topic),
            ("camera.info_topic", &self.info_topic),
        ] {
            if v.is_empty() {
                return Err(FieldError::new(field, "must not be empty"));
            }
        }
        positive("camera.rate_hz", self.rate_hz)?;
        if self.rate_hz > 100.0 {
            return Err(FieldError::new("camera.rate_hz", format!("must be at most 100, got {}", self.rate_hz)));
        }
        for (field, v) in [("camera.width", self.width), ("camera.height", self.height)] {
            if !(1..=4096).contains(&v) {
                return Err(FieldError::new(field, format!("must lie in 1..=4096, got {v}")));
            }
        }
        if !(self.hfov_deg.is_finite() && self.hfov_deg > 0.0 && self.hfov_deg < 170.0) {
            return Err(FieldError::new("camera.hfov_deg", format!("must lie in (0, 170), got {}", self.hfov_deg)));
        }
        let m = &self.mount;
        for (k, v) in [("x", m.x), ("y", m.y), ("z", m.z), ("roll", m.roll), ("pitch", m.pitch), ("yaw", m.yaw)] {
            finite(&format!("camera.mount.{k}"), v)?;
        }
        if m.z <= 0.0 {
            return Err(FieldError::new("camera.mount.z", format!("must be above the floor (> 0), got {}", m.z)));
        }
        if !(self.time_offset_s.is_finite() && self.time_offset_s.abs() <= 10.0) {
            return Err(FieldError::new(
                "camera.time_offset_s",
                format!("must be finite and within ±10 s, got {}", self.time_offset_s),
            ));
        }
        positive("camera.max_depth_m", self.max_depth_m)?;
        non_negative("camera.depth_sigma_k", self.depth_sigma_k)?;
        probability("camera.label_noise_probability", self.label_noise_probability)?;
        probability("camera.glass_depth_probability", self.glass_depth_probability)?;
        let b = &self.backlight;
        finite("camera.backlight.window_yaw_deg", b.window_yaw_deg)?;
        non_negative("camera.backlight.half_angle_deg", b.half_angle_deg)?;
        probability("camera.backlight.floor_share", b.floor_share)?;
        if super::class_id(&b.class).is_none() {
            return Err(FieldError::new(
                "camera.backlight.class",
                format!("`{}` is not a class of the table", b.class),
            ));
        }
        positive("camera.backlight.blob_scale_px", b.blob_scale_px)?;
        positive("camera.backlight.blob_period_s", b.blob_period_s)?;
        let bytes = f64::from(self.width) * f64::from(self.height) * 6.0 * self.rate_hz * duration_s;
        if self.enabled && bytes > MAX_CAMERA_BYTES {
            return Err(FieldError::new(
                "camera.width",
                format!(
                "needs {bytes:.3e} bytes of images with camera.height × camera.rate_hz × robot.duration_s, more than \
                 the {MAX_CAMERA_BYTES:.0e} a run may hold in memory"
            ),
            ));
        }
        Ok(())
    }
}
