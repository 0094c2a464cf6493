//! `geometry_msgs`: points, rotations, poses, velocities and frame transforms.

use super::std_msgs::{Header, HEADER};
use super::wire::{FieldReader, RosMsg};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

/// `geometry_msgs/Point`.
pub static POINT: MsgDef = MsgDef { name: "geometry_msgs/Point", text: "float64 x\nfloat64 y\nfloat64 z\n", deps: &[] };
/// `geometry_msgs/Vector3`.
pub static VECTOR3: MsgDef =
    MsgDef { name: "geometry_msgs/Vector3", text: "float64 x\nfloat64 y\nfloat64 z\n", deps: &[] };
/// `geometry_msgs/Quaternion`.
pub static QUATERNION: MsgDef =
    MsgDef { name: "geometry_msgs/Quaternion", text: "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n", deps: &[] };
/// `geometry_msgs/Pose`.
pub static POSE: MsgDef = MsgDef {
    name: "geometry_msgs/Pose",
    text: "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    deps: &[&POINT, &QUATERNION],
};
/// `geometry_msgs/PoseStamped`.
pub static POSE_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/PoseStamped",
    text: "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    deps: &[&HEADER, &POSE],
};
/// `geometry_msgs/PoseWithCovariance`.
pub static POSE_WITH_COVARIANCE: MsgDef = MsgDef {
    name: "geometry_msgs/PoseWithCovariance",
    text: "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
    deps: &[&POSE],
};
/// `geometry_msgs/PoseWithCovarianceStamped`.
pub static POSE_WITH_COVARIANCE_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/PoseWithCovarianceStamped",
    text: "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n",
    deps: &[&HEADER, &POSE_WITH_COVARIANCE],
};
/// `geometry_msgs/Twist`.
pub static TWIST: MsgDef = MsgDef {
    name: "geometry_msgs/Twist",
    text: "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    deps: &[&VECTOR3],
};
/// `geometry_msgs/TwistWithCovariance`.
pub static TWIST_WITH_COVARIANCE: MsgDef = MsgDef {
    name: "geometry_msgs/TwistWithCovariance",
    text: "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    deps: &[&TWIST],
};
/// `geometry_msgs/Transform`.
pub static TRANSFORM: MsgDef = MsgDef {
    name: "geometry_msgs/Transform",
    text: "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    deps: &[&VECTOR3, &QUATERNION],
};
/// `geometry_msgs/TransformStamped`.
pub static TRANSFORM_STAMPED: MsgDef = MsgDef {
    name: "geometry_msgs/TransformStamped",
    text: "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    deps: &[&HEADER, &TRANSFORM],
};

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

impl Point {
    /// `[x, y, z]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl Vector3 {
    /// `[x, y, z]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl From<[f64; 3]> for Vector3 {
    fn from([x, y, z]: [f64; 3]) -> Self {
        Self { x, y, z }
    }
}

impl From<[f64; 3]> for Point {
    fn from([x, y, z]: [f64; 3]) -> Self {
        Self { x, y, z }
    }
}

impl From<[f64; 4]> for Quaternion {
    /// From `[x, y, z, w]`.
    fn from([x, y, z, w]: [f64; 4]) -> Self {
        Self { x, y, z, w }
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

/// `geometry_msgs/msg/PoseStamped`: a pose at a time in a frame. Written only (paths).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/msg/PoseWithCovariance`: a pose estimate with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseWithCovariance {
    /// The estimate.
    pub pose: Pose,
    /// Row-major 6×6 covariance over (x, y, z, rotation about x, about y, about z).
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self { pose: Pose::default(), covariance: [0.0; 36] }
    }
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`: a stamped pose estimate (AMCL's
/// `/amcl_pose`, an external localiser, RViz's "2D Pose Estimate") in `header.frame_id`.
#[derive(Clone, Debug, Default, PartialEq)]
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

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self { twist: Twist::default(), covariance: [0.0; 36] }
    }
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

impl RosMsg for Point {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")? })
    }
}

impl RosMsg for Vector3 {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")? })
    }
}

impl RosMsg for Quaternion {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { x: r.f64("x")?, y: r.f64("y")?, z: r.f64("z")?, w: r.f64("w")? })
    }
}

impl RosMsg for Pose {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { position: r.message("position")?, orientation: r.message("orientation")? })
    }
}

impl RosMsg for PoseWithCovariance {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { pose: r.message("pose")?, covariance: r.f64_array("covariance")? })
    }
}

impl RosMsg for PoseWithCovarianceStamped {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { header: r.message("header")?, pose: r.message("pose")? })
    }
}

impl RosMsg for Twist {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { linear: r.message("linear")?, angular: r.message("angular")? })
    }
}

impl RosMsg for TwistWithCovariance {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { twist: r.message("twist")?, covariance: r.f64_array("covariance")? })
    }
}

impl RosMsg for Transform {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { translation: r.message("translation")?, rotation: r.message("rotation")? })
    }
}

impl RosMsg for TransformStamped {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            child_frame_id: r.string("child_frame_id")?,
            transform: r.message("transform")?,
        })
    }
}

impl CdrEncode for Point {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.f64_array(&self.to_array());
        Ok(())
    }
}

impl CdrEncode for Vector3 {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.f64_array(&self.to_array());
        Ok(())
    }
}

impl CdrEncode for Quaternion {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.f64_array(&self.to_array());
        Ok(())
    }
}

impl CdrEncode for Pose {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.position.encode(w)?;
        self.orientation.encode(w)
    }
}

impl CdrEncode for PoseWithCovariance {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.pose.encode(w)?;
        w.f64_array(&self.covariance);
        Ok(())
    }
}

impl CdrEncode for PoseWithCovarianceStamped {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        self.pose.encode(w)
    }
}

impl CdrEncode for Twist {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.linear.encode(w)?;
        self.angular.encode(w)
    }
}

impl CdrEncode for TwistWithCovariance {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.twist.encode(w)?;
        w.f64_array(&self.covariance);
        Ok(())
    }
}

impl CdrEncode for Transform {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.translation.encode(w)?;
        self.rotation.encode(w)
    }
}

impl CdrEncode for TransformStamped {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("child_frame_id", &self.child_frame_id)?;
        self.transform.encode(w)
    }
}

impl CdrEncode for PoseStamped {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        self.pose.encode(w)
    }
}
