//! The optional hand-over formats of a dense map (`[output]`): `map.mcap` (ROS 2
//! messages for Foxglove, `ros2 bag play` and RViz2), `map.pcd` and `map.ply` (the
//! occupied cells as points for PCL, Open3D and CloudCompare).

use super::set::OutputFiles;
use super::OutputError;
use fusemap_core::config::{OutputConfig, PointsMode};
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::grid::{CellRaster, Raster};
use fusemap_core::time::Stamp;
use fusemap_io::map_mcap::{write_map_mcap, MapMessages};
use fusemap_io::point_cloud::{write_pcd, write_ply, MapCloud, MapPoint};
use fusemap_io::semantic::SemanticRaster;

/// Bytes one lidar return kept for `[output] points = "endpoints"` takes at the peak of
/// writing the clouds, beside the point as kept (8 bytes, counted by the kept vector's
/// capacity): its [`MapPoint`] (24), held while the three files are written one after
/// another, and the largest writer's buffer, `map.mcap`'s: the `PointCloud2` record (16
/// bytes without classes) in the message and the CDR encoding of it, whose buffer may
/// have grown to twice that (32); `map.pcd` reserves 22. The returns count against
/// `[limits] memory_mib` at this price beside the maps.
pub const ENDPOINT_WRITE_BYTES: u64 = (std::mem::size_of::<MapPoint>() + 16 + 32) as u64;

/// Bytes `kept` returns (in a vector of `capacity`) take by the time their clouds are
/// written ([`ENDPOINT_WRITE_BYTES`] each, and the kept vector itself).
pub fn endpoint_bytes(kept: usize, capacity: usize) -> u64 {
    let held = (capacity as u64).saturating_mul(std::mem::size_of::<[f32; 2]>() as u64);
    held.saturating_add((kept as u64).saturating_mul(ENDPOINT_WRITE_BYTES))
}

/// The formats a run writes, and the lidar returns for `[output] points = "endpoints"`
/// (a log run's; `None` for the other runs, whose clouds hold the occupied cells).
pub struct FormatRequest<'a> {
    /// `[output]`.
    pub formats: OutputConfig,
    /// The returns as placed.
    pub endpoints: Option<&'a [[f32; 2]]>,
    /// `map → odom` and the odometry frame's name, for `map.mcap`'s `/tf_static`.
    pub map_from_odom: Option<(&'a str, Pose2)>,
}

/// Writes the formats `request` turns on for the dense map `r`, with a camera's layers
/// (the semantic layer as `semantic.png` shows it, the dynamic layer): nothing for a map
/// with no observed cell.
pub(crate) fn write_map_formats(
    files: &OutputFiles,
    request: FormatRequest<'_>,
    r: &Raster,
    layers: Option<(&SemanticRaster, &CellRaster<f32>)>,
    trajectory: &[(Stamp, Pose2)],
    closures: &[(Point2, Point2)],
) -> Result<(), OutputError> {
    let formats = request.formats;
    if r.known_count() == 0 || !(formats.mcap || formats.pcd || formats.ply) {
        return Ok(());
    }
    let classes = layers.map(|(s, _)| (s.best.as_slice(), s.classes.as_slice()));
    let cloud = match request.endpoints {
        Some(points) if formats.points == PointsMode::Endpoints => MapCloud::endpoints(r, points),
        _ => MapCloud::occupied_cells(r, classes),
    };
    if formats.pcd {
        write_pcd(&files.pcd, &cloud)?;
    }
    if formats.ply {
        write_ply(&files.ply, &cloud)?;
    }
    if formats.mcap {
        let content = MapMessages {
            raster: r,
            stamp: trajectory.last().map_or(Stamp(0), |p| p.0),
            trajectory,
            cloud: &cloud,
            semantic: layers.map(|(s, _)| s),
            dynamic: layers.map(|(_, d)| d),
            closures,
            map_from_odom: request.map_from_odom,
        };
        write_map_mcap(&files.mcap, &content)?;
    }
    Ok(())
}
