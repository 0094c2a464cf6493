//! `map.mcap`: a run's map as ROS 2 messages in one MCAP file (profile `ros2`, schemas
//! `ros2msg` with their full definitions, messages CDR), so that Foxglove opens it, `ros2
//! bag play` can replay it, and `rosbags` or `mcap-ros2-support` read it in Python — the
//! design document's §4.4 advice to hand long-term maps over in the standard message
//! types.
//!
//! | topic | type | what |
//! |---|---|---|
//! | `/map` | `nav_msgs/msg/OccupancyGrid` | the occupancy map ([`Raster::occupancy_percent`]) |
//! | `/trajectory` | `nav_msgs/msg/Path` | the track the scans were placed with |
//! | `/map_points` | `sensor_msgs/msg/PointCloud2` | the occupied cells' centres ([`MapCloud`]) |
//! | `/map/semantic` | `sensor_msgs/msg/Image` | with a camera: the class map, `mono8` class indices |
//! | `/map/dynamic` | `nav_msgs/msg/OccupancyGrid` | with a camera: the dynamic layer |
//! | `/slam/loop_closures` | `visualization_msgs/msg/MarkerArray` | SLAM's loop closures as lines |
//! | `/tf_static` | `tf2_msgs/msg/TFMessage` | where known: `map → odom` at the last pose |
//!
//! Everything is in the `map` frame, stamped at the run's last pose, and offered latched
//! (transient local, depth 1), as `map_server` offers `/map`: a subscriber that starts
//! after the message was played still gets it while the player runs. `/map` holds
//! probabilities (0–100), not `map_server`'s 0/100: a Nav2 static layer takes only 100 as
//! lethal by default, so navigation should load `map.yaml` with `map_server` (or set the
//! layer's `lethal_cost_threshold`). `/map`'s cells agree with `map.pgm`'s:
//! row-major from the lowest y, `info.origin` the lower-left corner of cell (0, 0) as in
//! `map.yaml`. `/map/semantic`'s rows run from the highest y down, as in `semantic.png`
//! (an image's row 0 is its top); its palette (`semantic.yaml`'s text) is the metadata
//! record `semantic`, key `yaml`. The file is written atomically.
//!
//! `/tf_static` joins the map to a bag's own TF tree (REP 105: `map → odom → base_link`), so
//! that Foxglove or RViz2 draws `/map` under the robot of the recording played beside it.
//! It is written where the track was odometry (identity: the map frame is `odom`) or SLAM's
//! correction of odometry; SLAM's correction moves along the log, and a static transform
//! holds its value at the last pose, so early in a long log the overlay is off by the drift
//! corrected since.

use crate::atomic::{check_raster, write_atomic};
use crate::log::ros2::msgs::builtin_interfaces::split_stamp;
use crate::log::ros2::msgs::geometry_msgs::{
    Point, Pose, PoseStamped, Quaternion, Transform, TransformStamped, Vector3,
};
use crate::log::ros2::msgs::nav_msgs::{MapMetaData, OccupancyGrid, Path as PathMsg, OCCUPANCY_GRID, PATH};
use crate::log::ros2::msgs::sensor_msgs::{Image, PointCloud2, PointField, IMAGE, POINT_CLOUD2};
use crate::log::ros2::msgs::std_msgs::{ColorRgba, Header};
use crate::log::ros2::msgs::tf2_msgs::{TfMessageRef, TF_MESSAGE};
use crate::log::ros2::msgs::visualization_msgs::{Marker, MarkerArray, MARKER_ARRAY};
use crate::log::ros2::writer::cdr_write::{encode_cdr, CdrEncode};
use crate::log::ros2::writer::definition::MsgDef;
use crate::log::ros2::writer::QosProfile;
use crate::point_cloud::MapCloud;
use crate::semantic::{semantic_yaml, SemanticRaster};
use crate::Result;
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::grid::{CellRaster, Raster};
use fusemap_core::time::Stamp;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io;
use std::path::Path;

/// The frame every message is in.
pub const MAP_FRAME: &str = "map";

/// What goes into `map.mcap`.
pub struct MapMessages<'a> {
    /// The occupancy map.
    pub raster: &'a Raster,
    /// The stamp of every message (the run's last pose).
    pub stamp: Stamp,
    /// The base's track.
    pub trajectory: &'a [(Stamp, Pose2)],
    /// The occupied cells, as `map.pcd` holds them.
    pub cloud: &'a MapCloud,
    /// The semantic layer as `semantic.png` shows it, with a camera.
    pub semantic: Option<&'a SemanticRaster>,
    /// The dynamic layer, with a camera.
    pub dynamic: Option<&'a CellRaster<f32>>,
    /// SLAM's loop closures, as segments between the two poses they join.
    pub closures: &'a [(Point2, Point2)],
    /// `map → odom` and the odometry frame's name, where known.
    pub map_from_odom: Option<(&'a str, Pose2)>,
}

/// Writes `content` to `path` as one MCAP file.
pub fn write_map_mcap(path: &Path, content: &MapMessages<'_>) -> Result<()> {
    check_raster(path, content.raster, true)?;
    let stamp = representable(content.stamp);
    let mut messages: Vec<(&str, &'static MsgDef, Vec<u8>)> = Vec::new();
    let mut add = |topic, def, msg: &dyn CdrEncode| -> std::result::Result<(), String> {
        let payload = encode_cdr(msg).map_err(|e| format!("{topic}: {e}"))?;
        messages.push((topic, def, payload));
        Ok(())
    };
    let packed = (|| -> std::result::Result<(), String> {
        add("/map", &OCCUPANCY_GRID, &grid_message(content.raster, stamp, content.raster.occupancy_percent()))?;
        add("/trajectory", &PATH, &path_message(content.trajectory, stamp))?;
        add("/map_points", &POINT_CLOUD2, &cloud_message(content.cloud, stamp))?;
        if let Some(s) = content.semantic {
            add("/map/semantic", &IMAGE, &semantic_image(s, stamp))?;
        }
        if let Some(d) = content.dynamic {
            add("/map/dynamic", &OCCUPANCY_GRID, &dynamic_grid(d, stamp))?;
        }
        if !content.closures.is_empty() {
            add("/slam/loop_closures", &MARKER_ARRAY, &closure_markers(content.closures, stamp))?;
        }
        if let Some((odom, m)) = content.map_from_odom {
            add("/tf_static", &TF_MESSAGE, &TfMessageRef(&[map_to_odom(odom, m, stamp)]))?;
        }
        Ok(())
    })();
    packed.map_err(|e| crate::Error::format(path, crate::Location::File, e))?;
    let semantic = content.semantic.map(|s| semantic_yaml(s, "/map/semantic"));
    write_atomic(path, |w| {
        let mut mcap = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("fusemap ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .create(w)
            .map_err(mcap_io)?;
        let qos = BTreeMap::from([("offered_qos_profiles".to_string(), QosProfile::LATCHED.to_yaml())]);
        let log_time = u64::try_from(stamp.0).unwrap_or(0);
        for (sequence, (topic, def, payload)) in messages.iter().enumerate() {
            let schema = mcap.add_schema(&def.ros2_name(), "ros2msg", def.full_text().as_bytes()).map_err(mcap_io)?;
            let channel_id = mcap.add_channel(schema, topic, "cdr", &qos).map_err(mcap_io)?;
            let header = mcap::records::MessageHeader {
                channel_id,
                sequence: sequence as u32,
                log_time,
                publish_time: log_time,
            };
            mcap.write_to_known_channel(&header, payload).map_err(mcap_io)?;
        }
        if let Some(yaml) = semantic {
            let record = mcap::records::Metadata {
                name: "semantic".into(),
                metadata: BTreeMap::from([("yaml".to_string(), yaml)]),
            };
            mcap.write_metadata(&record).map_err(mcap_io)?;
        }
        mcap.finish().map_err(mcap_io)?;
        Ok(())
    })
}

fn mcap_io(e: mcap::McapError) -> io::Error {
    match e {
        mcap::McapError::Io(e) => e,
        other => io::Error::other(other.to_string()),
    }
}

/// `stamp` if a `builtin_interfaces/Time` and an MCAP log time can hold it, else 0 (a log
/// stamped before 1970 or after 2038 still gets its map written).
fn representable(stamp: Stamp) -> Stamp {
    if stamp.0 >= 0 && split_stamp("stamp", stamp).is_ok() {
        stamp
    } else {
        Stamp(0)
    }
}

fn header(stamp: Stamp) -> Header {
    Header::new(stamp, MAP_FRAME)
}

/// A planar pose as a ROS pose: z = 0, the yaw as a quaternion about z.
fn pose(x: f64, y: f64, yaw: f64) -> Pose {
    let (s, c) = (0.5 * yaw).sin_cos();
    Pose { position: Point { x, y, z: 0.0 }, orientation: Quaternion { x: 0.0, y: 0.0, z: s, w: c } }
}

/// `map → odom` as a TF edge: the pose of the odometry frame in the map.
fn map_to_odom(odom: &str, m: Pose2, stamp: Stamp) -> TransformStamped {
    let p = pose(m.x, m.y, m.theta);
    TransformStamped {
        header: header(stamp),
        child_frame_id: odom.to_string(),
        transform: Transform { translation: Vector3 { x: m.x, y: m.y, z: 0.0 }, rotation: p.orientation },
    }
}

fn meta(width: usize, height: usize, resolution: f64, origin: Point2, stamp: Stamp) -> MapMetaData {
    MapMetaData {
        map_load_time: stamp,
        resolution: resolution as f32,
        width: width as u32,
        height: height as u32,
        origin: pose(origin.x, origin.y, 0.0),
    }
}

fn grid_message(r: &Raster, stamp: Stamp, data: Vec<i8>) -> OccupancyGrid {
    OccupancyGrid { header: header(stamp), info: meta(r.width, r.height, r.resolution, r.origin, stamp), data }
}

fn path_message(track: &[(Stamp, Pose2)], stamp: Stamp) -> PathMsg {
    let poses = track
        .iter()
        .map(|(t, p)| PoseStamped { header: header(representable(*t)), pose: pose(p.x, p.y, p.theta) })
        .collect();
    PathMsg { header: header(stamp), poses }
}

fn cloud_message(cloud: &MapCloud, stamp: Stamp) -> PointCloud2 {
    let field = |name: &str, offset: u32, datatype: u8| PointField { name: name.into(), offset, datatype, count: 1 };
    let mut fields = vec![
        field("x", 0, PointField::FLOAT32),
        field("y", 4, PointField::FLOAT32),
        field("z", 8, PointField::FLOAT32),
        field("probability", 12, PointField::FLOAT32),
    ];
    if cloud.classes {
        fields.push(field("class", 16, PointField::UINT16));
        fields.push(field("rgb", 20, PointField::FLOAT32));
    }
    let step = cloud.point_step() as u32;
    let n = cloud.points.len() as u32;
    PointCloud2 {
        header: header(stamp),
        height: 1,
        width: n,
        fields,
        is_bigendian: false,
        point_step: step,
        row_step: step * n,
        data: cloud.records(),
        is_dense: true,
    }
}

/// The class map as a `mono8` image, top row = highest y; `K` (the class count) where a
/// cell has no class, as in `semantic.png`.
fn semantic_image(s: &SemanticRaster, stamp: Stamp) -> Image<'static> {
    let unknown = s.classes.len().min(255) as u8;
    let data: Vec<u8> = s
        .best
        .chunks_exact(s.width.max(1))
        .rev()
        .flat_map(|row| row.iter().map(|&b| u8::try_from(b).unwrap_or(unknown)))
        .collect();
    Image {
        header: header(stamp),
        height: s.height as u32,
        width: s.width as u32,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: s.width as u32,
        data: Cow::Owned(data),
    }
}

/// The dynamic layer as an occupancy grid over the map's cells: −1 where never observed,
/// else the probability of a moving object in percent.
fn dynamic_grid(d: &CellRaster<f32>, stamp: Stamp) -> OccupancyGrid {
    let data = d
        .cells
        .iter()
        .zip(&d.known)
        .map(|(&p, &k)| if k && p.is_finite() { (100.0 * p.clamp(0.0, 1.0)).round() as i8 } else { -1 })
        .collect();
    OccupancyGrid { header: header(stamp), info: meta(d.width, d.height, d.resolution, d.origin, stamp), data }
}

/// One line-list marker, a segment per loop closure, 5 cm wide, orange.
fn closure_markers(closures: &[(Point2, Point2)], stamp: Stamp) -> MarkerArray {
    let points = closures
        .iter()
        .flat_map(|(a, b)| [Point { x: a.x, y: a.y, z: 0.0 }, Point { x: b.x, y: b.y, z: 0.0 }])
        .collect();
    let marker = Marker {
        header: header(stamp),
        ns: "loop_closures".into(),
        id: 0,
        kind: Marker::LINE_LIST,
        action: 0,
        pose: pose(0.0, 0.0, 0.0),
        scale: [0.05, 0.0, 0.0].into(),
        color: ColorRgba { r: 1.0, g: 0.45, b: 0.0, a: 1.0 },
        points,
    };
    MarkerArray { markers: vec![marker] }
}

#[cfg(test)]
mod tests;
