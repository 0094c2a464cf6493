//! `geometry_msgs`: points, rotations, poses, velocities and frame transforms.

use super::std_msgs::Header;
use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};

/// `geometry_msgs/msg/Point`: a position in space, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Vector3`: a free vector (a translation, a velocity, an
/// acceleration); unlike [`Point`] it has no position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`: a rotation as a unit quaternion, vector part first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w, the scalar part (1 for no rotation).
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }
    }
}

impl Quaternion {
    /// `[x, y, z, w]`, the order fusemap's geometry uses.
    pub fn to_array(self) -> [f64; 4] {
        [self.x, self.y, self.z, self.w]
    }
}

impl Vector3 {
    /// `[x, y, z]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

/// `geometry_msgs/msg/Pose`: a position and an orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseWithCovariance`: a pose estimate with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseWithCovariance {
    /// The estimate.
    pub pose: Pose,
    /// Row-major 6×6 covariance over (x, y, z, rotation about x, about y, about z).
    pub covariance: [f64; 36],
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`: a stamped pose estimate (AMCL's
/// `/amcl_pose`, an external localiser) in `header.frame_id`.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseWithCovarianceStamped {
    /// Stamp and the frame the pose is given in.
    pub header: Header,
    /// The estimate and its covariance.
    pub pose: PoseWithCovariance,
}

/// `geometry_msgs/msg/Twist`: a velocity split into linear and angular parts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`: a velocity estimate with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwistWithCovariance {
    /// The estimate.
    pub twist: Twist,
    /// Row-major 6×6 covariance over (x, y, z, rotation about x, about y, about z).
    pub covariance: [f64; 36],
}

/// `geometry_msgs/msg/Transform`: a rigid transform between two frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Transform {
    /// Translation, metres.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in
/// `header.frame_id` at `header.stamp` (maps points in the child frame to the parent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The frame the transform describes.
    pub child_frame_id: String,
    /// The transform `parent_from_child`.
    pub transform: Transform,
}

impl CdrDecode for Point {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")? })
    }
}

impl CdrDecode for Vector3 {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")? })
    }
}

impl CdrDecode for Quaternion {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")?, w: r.f64("w")? })
    }
}

impl CdrDecode for Pose {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { position: r.decode_field("position")?, orientation: r.decode_field("orientation")? })
    }
}

impl CdrDecode for PoseWithCovariance {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { pose: r.decode_field("pose")?, covariance: r.f64_array("covariance")? })
    }
}

impl CdrDecode for PoseWithCovarianceStamped {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { header: r.decode_field("header")?, pose: r.decode_field("pose")? })
    }
}

impl CdrDecode for Twist {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { linear: r.decode_field("linear")?, angular: r.decode_field("angular")? })
    }
}

impl CdrDecode for TwistWithCovariance {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { twist: r.decode_field("twist")?, covariance: r.f64_array("covariance")? })
    }
}

impl CdrDecode for Transform {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { translation: r.decode_field("translation")?, rotation: r.decode_field("rotation")? })
    }
}

impl CdrDecode for TransformStamped {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: r.decode_field("header")?,
            child_frame_id: r.string("child_frame_id")?,
            transform: r.decode_field("transform")?,
        })
    }
}
