//! `nav_msgs`: odometry (read and written), and the map messages fusemap writes beside
//! its maps: occupancy grids and paths.

use super::builtin_interfaces::{write_time, TIME};
use super::geometry_msgs::{
    Pose, PoseStamped, PoseWithCovariance, TwistWithCovariance, POSE, POSE_STAMPED, POSE_WITH_COVARIANCE,
    TWIST_WITH_COVARIANCE,
};
use super::std_msgs::{Header, HEADER};
use super::wire::{FieldReader, RosMsg};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;
use fusemap_core::time::Stamp;

/// `nav_msgs/Odometry`.
pub static ODOMETRY: MsgDef = MsgDef {
    name: "nav_msgs/Odometry",
    text: "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
           geometry_msgs/TwistWithCovariance twist\n",
    deps: &[&HEADER, &POSE_WITH_COVARIANCE, &TWIST_WITH_COVARIANCE],
};

/// `nav_msgs/msg/Odometry`: an estimate of where the robot is and how fast it moves
/// (REP 105: `odom_from_base`, the twist in the child frame).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Odometry {
    /// Stamp, and the frame the pose is given in (usually `odom`).
    pub header: Header,
    /// The frame the twist is given in (usually `base_link`).
    pub child_frame_id: String,
    /// Pose of `child_frame_id` in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// Velocity, expressed in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

impl RosMsg for Odometry {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self {
            header: r.message("header")?,
            child_frame_id: r.string("child_frame_id")?,
            pose: r.message("pose")?,
            twist: r.message("twist")?,
        })
    }
}

impl CdrEncode for Odometry {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.string("child_frame_id", &self.child_frame_id)?;
        self.pose.encode(w)?;
        self.twist.encode(w)
    }
}

/// `nav_msgs/MapMetaData`.
pub static MAP_META_DATA: MsgDef = MsgDef {
    name: "nav_msgs/MapMetaData",
    text: "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n\
           geometry_msgs/Pose origin\n",
    deps: &[&TIME, &POSE],
};
/// `nav_msgs/OccupancyGrid`.
pub static OCCUPANCY_GRID: MsgDef = MsgDef {
    name: "nav_msgs/OccupancyGrid",
    text: "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n",
    deps: &[&HEADER, &MAP_META_DATA],
};
/// `nav_msgs/Path`.
pub static PATH: MsgDef = MsgDef {
    name: "nav_msgs/Path",
    text: "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n",
    deps: &[&HEADER, &POSE_STAMPED],
};

/// `nav_msgs/msg/MapMetaData`: where an occupancy grid lies and how fine it is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapMetaData {
    /// When the map was made (loaded, for `map_server`).
    pub map_load_time: Stamp,
    /// Cell side, metres.
    pub resolution: f32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// The pose of cell (0, 0)'s lower-left corner in the grid's frame.
    pub origin: Pose,
}

/// `nav_msgs/msg/OccupancyGrid`: row-major cells from the lowest y, each −1 (unknown) or
/// an occupancy probability in percent. Written only.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccupancyGrid {
    /// Stamp and frame (`map`).
    pub header: Header,
    /// Placement.
    pub info: MapMetaData,
    /// The cells.
    pub data: Vec<i8>,
}

/// `nav_msgs/msg/Path`: poses in order, a robot's track. Written only.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path {
    /// Stamp and frame (`map`).
    pub header: Header,
    /// The poses.
    pub poses: Vec<PoseStamped>,
}

impl CdrEncode for OccupancyGrid {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        write_time(w, "info.map_load_time", self.info.map_load_time)?;
        w.f32(self.info.resolution);
        w.u32(self.info.width);
        w.u32(self.info.height);
        self.info.origin.encode(w)?;
        w.i8_seq("data", &self.data)
    }
}

impl CdrEncode for Path {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        self.header.encode(w)?;
        w.seq("poses", &self.poses)
    }
}
