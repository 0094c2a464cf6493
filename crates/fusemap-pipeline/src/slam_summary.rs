//! What the SLAM pass reports (`summary.json`'s `log.slam`): a leaf of the pipeline, so
//! the pose track and the run report can carry it without importing the pass itself.

use fusemap_core::geometry::Pose2;
use fusemap_core::slam::SlamReport;
use fusemap_core::time::Stamp;
use serde::Serialize;

/// A pose-graph node as the run report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct GraphNode {
    /// `scan` or `submap`.
    pub kind: &'static str,
    /// The scan's stamp, ns (scans only).
    pub stamp_ns: Option<i64>,
    /// Optimised pose `[x, y, θ]`.
    pub pose: [f64; 3],
}

/// A pose-graph edge as the run report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct GraphEdge {
    /// Index into the nodes.
    pub from: usize,
    /// Index into the nodes.
    pub to: usize,
    /// `odometry`, `match` (a scan in a submap it went into) or `loop_closure`.
    pub kind: &'static str,
}

/// A GNSS fix's position prior on a node, as the run report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct GraphPrior {
    /// Index into the nodes.
    pub node: usize,
    /// The antenna's measured position `[x, y]` in the map frame.
    pub position: [f64; 2],
}

/// What the SLAM pass did, for `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct SlamSummary {
    /// Why SLAM ran.
    pub reason: String,
    /// The lidar topic SLAM used.
    pub topic: String,
    /// Scans without a track pose (matched from the previous scan's pose).
    pub scans_without_pose: u64,
    /// Scans that arrived more than `log.reorder_window_s` behind a later one (not used).
    pub scans_late: u64,
    /// The core's counts and timings.
    pub counts: SlamReport,
    /// Wall time of the whole pass, reading included, seconds.
    pub seconds: f64,
    /// How the track was made from the optimised poses.
    pub track: String,
    /// The optimised pose graph.
    pub nodes: Vec<GraphNode>,
    /// Its edges.
    pub edges: Vec<GraphEdge>,
    /// Its GNSS position priors.
    pub priors: Vec<GraphPrior>,
    /// The loop-closure searches that closed no loop: node and submap (indices into
    /// `nodes`), the best score (or an upper bound of it when
    /// nothing reached the threshold), the reason, and whether the best pose lay on the
    /// window's edge.
    pub open_loops: Vec<fusemap_core::slam::OpenSearch>,
    /// The lidar's pose in the base frame, `[x, y, yaw]` (metres, radians). The
    /// trajectory is the base frame's; the SLAM benchmark's relations are between laser
    /// poses, so `fusemap relations --sensor-in-base` composes the two.
    pub sensor_in_base: [f64; 3],
    /// Every scan's optimised pose (in `trajectory.tum` through the track, not here).
    #[serde(skip)]
    pub scan_poses: Vec<(Stamp, Pose2)>,
    /// With poses on the scan lines: each scan's stamp and line pose, in the order of
    /// `scan_poses` (`None` for a line without a usable pose).
    #[serde(skip)]
    pub lines: Vec<Option<(Stamp, Pose2)>>,
}
