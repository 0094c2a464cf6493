//! The pinhole camera of `sensor_msgs/CameraInfo`, without distortion.
//!
//! A pixel `(u, v)` (column, row) sees the ray of the optical frame (REP 103: x right, y
//! down, z forward) through its centre, which sits at the integer coordinates `(u, v)`:
//! the convention of OpenCV's calibration, which writes `CameraInfo`'s `K`, and of ROS's
//! depth-image consumers (depth_image_proc's point clouds), so an ideal camera of width
//! `w` has `cx = (w − 1) / 2`. (Taking centres at `u + 0.5`, the corner convention, turns
//! every ray by half a pixel: 0.13° in yaw and pitch at 70° across 320 pixels, which put
//! a pitched camera's wall points millimetres to centimetres nearer the robot than the
//! lidar's walls.)
//!
//! ```text
//! x = (u - cx) / fx · z,   y = (v - cy) / fy · z
//! ```
//!
//! (Hartley & Zisserman, *Multiple View Geometry*, §6.1, with zero skew.)
//!
//! **fusemap does not undistort.** Label and depth images must be rectified before they
//! reach the camera model; a `CameraInfo` that declares a distortion with any non-zero
//! coefficient is refused rather than silently treated as a pinhole, because a radial
//! distortion of a few pixels at the image border becomes decimetres on the floor a few
//! metres away. For a rectified stream (image_proc's `image_rect`), ROS keeps the raw
//! camera's `K` and `D` in the `CameraInfo` and puts the rectified intrinsics in the
//! projection matrix `P`: build the pinhole with [`Pinhole::from_projection`] then.

use super::CameraError;

/// The largest image, in pixels, a camera may declare (50 megapixels). Width and height
/// come from the recording: the bound stops a corrupt `CameraInfo` from asking for a
/// gigantic allocation.
pub const MAX_CAMERA_PIXELS: u64 = 50_000_000;

/// Pinhole intrinsics from `sensor_msgs/CameraInfo` `K` (`fx = K[0]`, `cx = K[2]`,
/// `fy = K[4]`, `cy = K[5]`), pixels. Built only through the checked constructors, so
/// `fx`, `fy` are positive and finite and the size is non-empty and bounded.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Pinhole {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (from the left edge of the image).
    pub cx: f64,
    /// Principal point y, pixels (from the top edge of the image).
    pub cy: f64,
}

/// Distortion models named by `CameraInfo.distortion_model` that are accepted when every
/// coefficient is zero (then the camera is a plain pinhole whatever the model).
const ZERO_DISTORTION_MODELS: [&str; 5] = ["", "none", "plumb_bob", "rational_polynomial", "equidistant"];

impl Pinhole {
    /// A pinhole from its values, checked: width and height non-zero with at most
    /// [`MAX_CAMERA_PIXELS`] pixels, `fx`, `fy` finite and positive, `cx`, `cy` finite.
    pub fn new(width: u32, height: u32, fx: f64, fy: f64, cx: f64, cy: f64) -> Result<Pinhole, CameraError> {
        if width == 0 || height == 0 {
            return Err(CameraError::EmptyImage { width, height });
        }
        if width as u64 * height as u64 > MAX_CAMERA_PIXELS {
            return Err(CameraError::TooManyPixels { width, height });
        }
        for (name, v) in [("fx", fx), ("fy", fy)] {
            if !v.is_finite() || v <= 0.0 {
                return Err(CameraError::Intrinsics {
                    what: format!(
                        "{name} must be a positive finite focal length in pixels, got {v} (an uncalibrated \
                         camera's CameraInfo has K = 0)"
                    ),
                });
            }
        }
        for (name, v) in [("cx", cx), ("cy", cy)] {
            if !v.is_finite() {
                return Err(CameraError::Intrinsics { what: format!("{name} must be finite, got {v}") });
            }
        }
        Ok(Pinhole { width, height, fx, fy, cx, cy })
    }

    /// A pinhole from a `sensor_msgs/CameraInfo`: its size, its row-major camera matrix
    /// `K = [fx s cx; 0 fy cy; 0 0 1]`, its distortion model and coefficients `D`.
    ///
    /// The distortion model may be `""`, `"none"`, `"plumb_bob"`, `"rational_polynomial"`
    /// or `"equidistant"`, and only with every coefficient zero: fusemap does not undistort
    /// (see the module documentation). The skew `K[1]` must be 0 and the last row
    /// `[0 0 1]`.
    pub fn from_camera_info(
        width: u32,
        height: u32,
        k: [f64; 9],
        distortion_model: &str,
        d: &[f64],
    ) -> Result<Pinhole, CameraError> {
        if !ZERO_DISTORTION_MODELS.contains(&distortion_model) {
            return Err(CameraError::UnsupportedDistortion { model: distortion_model.to_string() });
        }
        // `!= 0.0` is also true for NaN: a NaN coefficient is refused too.
        if d.iter().any(|c| *c != 0.0) {
            return Err(CameraError::Distorted { model: distortion_model.to_string(), coefficients: d.to_vec() });
        }
        if k[1] != 0.0 {
            return Err(CameraError::Skew { skew: k[1] });
        }
        if k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
            return Err(CameraError::Intrinsics {
                what: format!(
                    "K must read [fx 0 cx; 0 fy cy; 0 0 1], its entries 3, 6, 7, 8 are {}, {}, {}, {}",
                    k[3], k[6], k[7], k[8]
                ),
            });
        }
        Pinhole::new(width, height, k[0], k[4], k[2], k[5])
    }

    /// A pinhole from the projection matrix `P` of a `CameraInfo` (row-major 3×4,
    /// `[fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0]`): the intrinsics of the *rectified* image
    /// (ROS `image_rect`). `Tx` and `Ty` must be 0 (they place the second camera of a
    /// stereo pair; a depth image aligned with it is not the first camera's).
    pub fn from_projection(width: u32, height: u32, p: [f64; 12]) -> Result<Pinhole, CameraError> {
        if p[3] != 0.0 || p[7] != 0.0 {
            return Err(CameraError::Intrinsics {
                what: format!("projection matrix P has Tx = {}, Ty = {}: only a first (monocular) camera", p[3], p[7]),
            });
        }
        let k = [p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]];
        if p[11] != 0.0 {
            return Err(CameraError::Intrinsics { what: format!("projection matrix P[11] is {}, not 0", p[11]) });
        }
        Pinhole::from_camera_info(width, height, k, "", &[])
    }

    /// Number of pixels, `width × height`.
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// The ray of image point `(u, v)` (pixel coordinates, continuous) in the optical
    /// frame, scaled to `z = 1`: multiplied by a depth along the optical axis it gives the
    /// 3D point.
    #[inline]
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        [(u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0]
    }

    /// The image point `(u, v)` where an optical-frame point projects; `None` for a point
    /// not in front of the camera (`z ≤ 0` or not finite).
    pub fn project(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        if !p.iter().all(|c| c.is_finite()) || p[2] <= 0.0 {
            return None;
        }
        Some((self.fx * p[0] / p[2] + self.cx, self.fy * p[1] / p[2] + self.cy))
    }
}
