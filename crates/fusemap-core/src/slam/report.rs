//! What a SLAM run did, for the run report.

use super::pose_graph::OptimizeReport;
use serde::Serialize;

/// Counts and timings of a SLAM run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SlamReport {
    /// Scans given.
    pub scans: u64,
    /// Scans matched against a submap.
    pub matched: u64,
    /// Scans whose match was degenerate (refined again from the prediction, pulled to it ten times harder).
    pub degenerate: u64,
    /// Scans not matched (too few returns, or no submap yet): predicted pose kept.
    pub predicted: u64,
    /// Scans inside a gap of the pose track (matched from the previous scan's pose).
    pub without_track: u64,
    /// Scans refused (non-finite track pose or sensor origin).
    pub refused: u64,
    /// Scans also matched from the constant-velocity prediction, because it lay outside
    /// half the search window of the track's prediction.
    pub moving_prediction_searched: u64,
    /// Scans matched from the constant-velocity prediction because it matched better than
    /// the track's (stalled or jumping odometry).
    pub moving_prediction_used: u64,
    /// Scans whose match scored far below the recent matches', searched again in the wide
    /// window (`[slam] rescue_*`).
    pub rescue_searched: u64,
    /// … and taken from that wider search, clearly better.
    pub rescued: u64,
    /// Scans whose track reading repeated the previous scan's bit for bit (a held reading:
    /// no motion information, not made a node).
    pub held_readings: u64,
    /// Matched scans the track's motion was judged by (`odometry.rs`).
    pub odometry_samples: u64,
    /// What they made of the odometry model's σ at the end: the factors of its
    /// translation and rotation (below 1: the track was better than the model).
    pub odometry_scale: [f64; 2],
    /// Odometry edges left out: the odometry disagreed with the matched motion by > 5 σ.
    pub odometry_edges_rejected: u64,
    /// GNSS fixes given.
    pub fixes: u64,
    /// Fixes made position priors on nodes.
    pub fix_priors: u64,
    /// Fixes left out: too far from the pose track for both covariances (χ², 99.9 %).
    pub fixes_gated: u64,
    /// Fixes left out: no node with a track pose within `fix_max_offset_s`, no track pose at
    /// the fix, a covariance that is not positive definite, or a graph not in the fixes'
    /// frame (its first node had no track pose).
    pub fixes_unplaced: u64,
    /// Pose-graph nodes (scans that moved far enough).
    pub nodes: u64,
    /// Submaps built.
    pub submaps: usize,
    /// Loop-closure searches run.
    pub loop_searches: u64,
    /// Loop closures accepted.
    pub loop_accepted: u64,
    /// Loop-closure searches that found nothing above the score threshold, or only a
    /// degenerate match.
    pub loop_rejected: u64,
    /// … of which degenerate: a match that fits anywhere along one direction (a corridor).
    pub loop_degenerate: u64,
    /// … of which large corrections no later node confirmed.
    pub loop_unconfirmed: u64,
    /// … of which confirming searches that found nothing where the hypothesis put the node.
    pub loop_disagreeing: u64,
    /// Large corrections (a widened window or the global search) held as hypotheses.
    pub loop_hypotheses: u64,
    /// … confirmed by a second, agreeing match (both become edges).
    pub loop_confirmed: u64,
    /// … of which found by the global search.
    pub loop_global_accepted: u64,
    /// Searches left out because a batch was over its budget.
    pub loop_over_budget: u64,
    /// Branch-and-bound grids built for finished submaps (first builds and rebuilds after
    /// the memory budget dropped them).
    pub grids_built: u64,
    /// The most bytes of branch-and-bound grids held at once.
    pub grids_peak_bytes: usize,
    /// Pose-graph optimisations run.
    pub optimisations: u64,
    /// Optimisations that failed (the previous poses were kept), with the reason.
    pub optimisation_failures: Vec<String>,
    /// The last optimisation.
    pub last_optimisation: Option<OptimizeReport>,
    /// Wall time in local matching, seconds.
    pub matching_s: f64,
    /// Wall time in loop-closure search (precomputation included), seconds.
    pub loop_search_s: f64,
    /// Wall time in pose-graph optimisation, seconds.
    pub optimisation_s: f64,
}
