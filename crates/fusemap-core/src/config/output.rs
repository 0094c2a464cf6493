//! `[output]`: which of a run's optional map formats are written. The map itself
//! (`map.npz`, `map.pgm` + `map.yaml`, `map.png`), `trajectory.tum`, `summary.json` and
//! `report.html` are always written; these are the hand-overs to other tools (§4.4).

use serde::{Deserialize, Serialize};

/// The `[output]` table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputConfig {
    /// `map.mcap`: the map, the track and the occupied cells as ROS 2 messages
    /// (`nav_msgs/OccupancyGrid`, `nav_msgs/Path`, `sensor_msgs/PointCloud2`), for
    /// Foxglove, `ros2 bag play` and RViz.
    pub mcap: bool,
    /// `map.pcd`: the occupied cells as a PCL point cloud (v0.7, binary).
    pub pcd: bool,
    /// `map.ply`: the same points as a binary little-endian PLY.
    pub ply: bool,
    /// What the point clouds (`map.pcd`, `map.ply`, `/map_points`) hold.
    pub points: PointsMode,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self { mcap: true, pcd: true, ply: true, points: PointsMode::Cells }
    }
}

impl OutputConfig {
    /// Whether a run writes clouds of the lidar returns: `points = "endpoints"` with a
    /// cloud format on. Only then are the returns kept (they grow with the log).
    pub fn endpoint_clouds(&self) -> bool {
        self.points == PointsMode::Endpoints && (self.mcap || self.pcd || self.ply)
    }
}

/// What the map's point clouds hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PointsMode {
    /// The occupied cells' centres: the map itself.
    #[default]
    Cells,
    /// Every valid lidar return, placed with the final (SLAM-corrected) track, one point
    /// per cell per scan: a localisation map keeping the returns' sub-cell positions.
    Endpoints,
}
