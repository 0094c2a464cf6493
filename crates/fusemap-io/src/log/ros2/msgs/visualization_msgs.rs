//! `visualization_msgs`: markers, which fusemap writes beside its maps to draw SLAM's loop
//! closures in Foxglove and RViz. Written only.
//!
//! The definitions are those of ROS 2 Humble and later (`texture`, `uv_coordinates` and
//! `mesh_file` included): `ros2 bag play` publishes with the local type, so the fields
//! must be the ones a current installation has.

use super::builtin_interfaces::DURATION;
use super::geometry_msgs::{Point, Pose, Vector3, POINT, POSE, VECTOR3};
use super::sensor_msgs::{CompressedImage, COMPRESSED_IMAGE};
use super::std_msgs::{ColorRgba, Header, COLOR_RGBA, HEADER};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

/// `visualization_msgs/UVCoordinate`.
pub static UV_COORDINATE: MsgDef =
    MsgDef { name: "visualization_msgs/UVCoordinate", text: "float32 u\nfloat32 v\n", deps: &[] };
/// `visualization_msgs/MeshFile`.
pub static MESH_FILE: MsgDef =
    MsgDef { name: "visualization_msgs/MeshFile", text: "string filename\nuint8[] data\n", deps: &[] };
/// `visualization_msgs/Marker`.
pub static MARKER: MsgDef = MsgDef {
    name: "visualization_msgs/Marker",
    text: "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n\
           int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\n\
           int32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
           std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n\
           geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\n\
           bool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\n\
           string texture_resource\nsensor_msgs/CompressedImage texture\n\
           visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
           visualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n",
    deps: &[&HEADER, &POSE, &VECTOR3, &COLOR_RGBA, &DURATION, &POINT, &COMPRESSED_IMAGE, &UV_COORDINATE, &MESH_FILE],
};
/// `visualization_msgs/MarkerArray`.
pub static MARKER_ARRAY: MsgDef =
    MsgDef { name: "visualization_msgs/MarkerArray", text: "visualization_msgs/Marker[] markers\n", deps: &[&MARKER] };

/// `visualization_msgs/msg/Marker`, the fields fusemap sets; the texture, UV and mesh
/// fields are written empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace; with `id`, names the marker.
    pub ns: String,
    /// Identifier within the namespace.
    pub id: i32,
    /// Shape ([`Marker::LINE_LIST`], …).
    pub kind: i32,
    /// Add (0), delete (2), delete all (3).
    pub action: i32,
    /// Pose of the marker's frame.
    pub pose: Pose,
    /// Size; for lines, `x` is the line width.
    pub scale: Vector3,
    /// Colour of the whole marker.
    pub color: ColorRgba,
    /// The points (two per segment for a line list).
    pub points: Vec<Point>,
}

impl Marker {
    /// Each pair of points is a segment.
    pub const LINE_LIST: i32 = 5;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

impl CdrEncode for Marker {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("ns", &self.ns)?;
        w.i32(self.id);
        w.i32(self.kind);
        w.i32(self.action);
        self.pose.encode(w)?;
        self.scale.encode(w)?;
        self.color.encode(w)?;
        // lifetime: 0 = forever.
        w.i32(0);
        w.u32(0);
        w.bool(false);
        w.seq("points", &self.points)?;
        w.u32(0); // colors
        w.string("texture_resource", "")?;
        CompressedImage::default().encode(w)?;
        w.u32(0); // uv_coordinates
        w.string("text", "")?;
        w.string("mesh_resource", "")?;
        w.string("mesh_file.filename", "")?;
        w.u32(0); // mesh_file.data
        w.bool(false);
        Ok(())
    }
}

impl CdrEncode for MarkerArray {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.seq("markers", &self.markers)
    }
}
