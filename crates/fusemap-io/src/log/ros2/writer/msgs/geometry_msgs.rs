//! `geometry_msgs`: poses with covariance, stamped transforms, and the definitions of the
//! small types inside them (points, vectors and quaternions are written as arrays).

use super::std_msgs::{Header, HEADER};
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

/// `geometry_msgs/msg/PoseWithCovariance`: a pose estimate with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseWithCovariance {
    /// `pose.position`, metres.
    pub position: [f64; 3],
    /// `pose.orientation`, quaternion `[x, y, z, w]`.
    pub orientation: [f64; 4],
    /// Row-major 6×6 covariance over (x, y, z, rotation about x, about y, about z).
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self { position: [0.0; 3], orientation: [0.0, 0.0, 0.0, 1.0], covariance: [0.0; 36] }
    }
}

/// `geometry_msgs/msg/TwistWithCovariance`: a velocity estimate with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwistWithCovariance {
    /// `twist.linear`, m/s.
    pub linear: [f64; 3],
    /// `twist.angular`, rad/s.
    pub angular: [f64; 3],
    /// Row-major 6×6 covariance over (x, y, z, rotation about x, about y, about z).
    pub covariance: [f64; 36],
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self { linear: [0.0; 3], angular: [0.0; 3], covariance: [0.0; 36] }
    }
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`: a pose estimate at a time, in a frame
/// (what AMCL publishes and RViz's "2D Pose Estimate" sends).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseWithCovarianceStamped {
    /// Stamp, and the frame the pose is given in.
    pub header: Header,
    /// The estimate.
    pub pose: PoseWithCovariance,
}

/// `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in
/// `header.frame_id` at `header.stamp` (REP 105 frames; maps child points to the parent).
#[derive(Clone, Debug, PartialEq)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The frame the transform describes.
    pub child_frame_id: String,
    /// `transform.translation`, metres.
    pub translation: [f64; 3],
    /// `transform.rotation`, quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

impl CdrEncode for PoseWithCovariance {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.f64_array(&self.position);
        w.f64_array(&self.orientation);
        w.f64_array(&self.covariance);
        Ok(())
    }
}

impl CdrEncode for TwistWithCovariance {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.f64_array(&self.linear);
        w.f64_array(&self.angular);
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

impl CdrEncode for TransformStamped {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("child_frame_id", &self.child_frame_id)?;
        w.f64_array(&self.translation);
        w.f64_array(&self.rotation);
        Ok(())
    }
}
