//! Why a camera model cannot be built or a frame cannot be projected.

use super::pinhole::MAX_CAMERA_PIXELS;

/// A camera error: bad intrinsics, an unsupported distortion, a parameter out of range,
/// images that do not fit the camera. Every message names the value at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A distortion model other than none, `plumb_bob`, `rational_polynomial` and
    /// `equidistant`.
    #[error(
        "distortion model `{model}` is not supported: fusemap does not undistort, so the images must be \
         rectified and their CameraInfo must name no model, \"none\", \"plumb_bob\", \
         \"rational_polynomial\" or \"equidistant\", with all coefficients zero"
    )]
    UnsupportedDistortion {
        /// The model named by the CameraInfo.
        model: String,
    },
    /// A known distortion model with non-zero (or non-finite) coefficients.
    #[error(
        "distortion model `{model}` has non-zero coefficients D = {coefficients:?}: fusemap does not \
         undistort, so the images must be rectified (e.g. image_proc's image_rect, whose intrinsics are \
         the projection matrix P, with D = 0)"
    )]
    Distorted {
        /// The model named by the CameraInfo.
        model: String,
        /// Its coefficients, as given.
        coefficients: Vec<f64>,
    },
    /// A camera matrix entry out of range (zero focal length of an uncalibrated camera,
    /// NaN, a non-canonical last row).
    #[error("camera matrix: {what}")]
    Intrinsics {
        /// What is wrong, naming the entry.
        what: String,
    },
    /// A camera matrix with skew (`K[1] ≠ 0`), which the pinhole model here leaves out.
    #[error(
        "camera matrix K[1] (skew) is {skew}, not 0: fusemap's pinhole model has no skew term (every \
         ROS calibration writes 0 there)"
    )]
    Skew {
        /// `K[1]`.
        skew: f64,
    },
    /// A zero width or height.
    #[error("the camera's image size {width}×{height} is empty")]
    EmptyImage {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// More pixels than `MAX_CAMERA_PIXELS`.
    #[error("the camera's image size {width}×{height} exceeds MAX_CAMERA_PIXELS = {max} pixels", max = MAX_CAMERA_PIXELS)]
    TooManyPixels {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// Label image, depth image and camera disagree in size.
    #[error(
        "image sizes differ: labels {}×{}, depth {}×{}, camera (CameraInfo) {}×{}",
        labels.0, labels.1, depth.0, depth.1, camera.0, camera.1
    )]
    ImageSize {
        /// Label image width, height.
        labels: (u32, u32),
        /// Depth image width, height.
        depth: (u32, u32),
        /// The pinhole's width, height.
        camera: (u32, u32),
    },
    /// A model parameter out of range.
    #[error("camera parameter {name}: {message}")]
    Parameter {
        /// The parameter (the `CameraParams` field).
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// The mount `base_from_optical` has a NaN or infinite component.
    #[error("the camera mount base_from_optical is not finite: {translation:?}, quaternion {rotation:?}")]
    Mount {
        /// Its translation.
        translation: [f64; 3],
        /// Its rotation quaternion.
        rotation: [f64; 4],
    },
    /// The robot pose of a frame is not finite.
    #[error("the robot pose of the camera frame is not finite: ({x}, {y}, {theta})")]
    Pose {
        /// x, metres.
        x: f64,
        /// y, metres.
        y: f64,
        /// Heading, radians.
        theta: f64,
    },
}
