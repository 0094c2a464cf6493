//! Parameters of the SLAM back end, with the reasons for their defaults.

use super::local_match::LocalMatchParams;
use super::submap::SubmapBounds;

/// Everything [`Slam`](super::Slam) can be tuned by. The `[slam]` config section maps onto
/// it key by key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlamParams {
    /// Submap cell size, metres. 5 cm, as Hess et al. 2016 use for 2D.
    pub resolution: f64,
    /// When a submap is full and the next starts (the older active submap then holds twice
    /// as much when it is finished): metres driven, radians turned, scans taken.
    pub submap: SubmapBounds,
    /// Probability of a return's cell being occupied (one update).
    pub hit_probability: f32,
    /// Probability of a crossed cell being occupied (one update).
    pub miss_probability: f32,
    /// σ of the likelihood field scans are matched against (`field.rs`), metres: the
    /// spread of a return around the wall it came from (range noise, the cell, the scan's
    /// own pose error).
    pub field_sigma_m: f64,
    /// Returns farther than this are not used for matching or submaps, metres: far returns
    /// grow the submaps and their angular error is largest.
    pub max_range_m: f64,
    /// A scan with fewer usable returns is not matched (its pose is predicted).
    pub min_points: usize,
    /// The pose track moving faster than this between two scans is a jump, not a motion
    /// (an odometry reset, a teleported pose): the scan is matched as in a gap of the
    /// track. Metres per second; the plan sets it from `log.max_speed_m_s`, the limit the
    /// glitch filter holds every pose stream to.
    pub max_track_speed_m_s: f64,
    /// … or turning faster than this, radians per second (`log.max_turn_rate_deg_s`).
    pub max_track_turn_rate_rad_s: f64,
    /// A scan becomes a node (and goes into the submaps) once the robot has moved this far
    /// since the last node, metres …
    pub node_distance_m: f64,
    /// … or turned this much, radians …
    pub node_angle_rad: f64,
    /// … or this much time has passed, seconds.
    pub node_time_s: f64,
    /// The constant-velocity prediction (from the last two scans' poses) replaces the
    /// track's when its match's mean probability is higher by this much: odometry that
    /// stalls for a few scans and then catches up is followed, a corridor (where both fit
    /// equally) is not.
    pub moving_prediction_margin: f64,
    /// A match whose mean probability is below this share of the recent matches' (an
    /// average over about ten scans) is searched again in the wide window below: the
    /// prediction was off by more than the search window.
    pub rescue_score_ratio: f64,
    /// Half-width of that wider search in x and y, metres …
    pub rescue_linear_window_m: f64,
    /// … and in heading, radians.
    pub rescue_angular_window_rad: f64,
    /// The local matcher.
    pub local: LocalMatchParams,
    /// Odometry edge σ: translational, per metre travelled (plus `odometry_floor_m`).
    pub odometry_translation_per_m: f64,
    /// Odometry edge σ floor, metres.
    pub odometry_floor_m: f64,
    /// Odometry edge σ: rotational, per radian turned (plus `odometry_floor_rad`).
    pub odometry_rotation_per_rad: f64,
    /// Odometry edge σ floor, radians.
    pub odometry_floor_rad: f64,
    /// Search for loop closures at all.
    pub loop_closure: bool,
    /// Share of nodes searched for a loop closure against the finished submaps near them.
    pub loop_closure_sampling_ratio: f64,
    /// … and only once this much travel separates it from the last node searched, metres:
    /// the rate follows the distance driven, not the scan rate.
    pub loop_closure_node_spacing_m: f64,
    /// A sampled node is searched against at most this many nearest finished submaps.
    pub loop_closure_submaps_per_node: usize,
    /// A submap just finished is searched by at most this many earlier nodes near it.
    pub loop_closure_nodes_per_submap: usize,
    /// Two submaps already tied by this many accepted closures are not searched against
    /// each other again (0: no limit): more matches of the same overlap add little.
    pub loop_closure_links_per_pair: usize,
    /// Returns farther than this are left out of the branch-and-bound search (its angular
    /// step, hence its cost, follows the farthest point), metres.
    pub loop_closure_max_range_m: f64,
    /// … and at most this many of them (evenly spread).
    pub loop_closure_max_points: usize,
    /// Memory for the finished submaps' branch-and-bound grids and their unpacked fields,
    /// MiB: past it the least recently searched are dropped and rebuilt when needed (same
    /// results, more time).
    pub loop_closure_grid_cache_mib: usize,
    /// Only submaps whose centre is within this distance of the node are searched, metres.
    pub loop_closure_max_distance_m: f64,
    /// Half-width of the loop-closure search in x and y, metres.
    pub loop_closure_linear_window_m: f64,
    /// Half-width of the loop-closure search in heading, radians.
    pub loop_closure_angular_window_rad: f64,
    /// Minimum mean probability of a loop closure's points.
    pub loop_closure_min_score: f32,
    /// A loop closure whose smallest/largest translational information ratio is below
    /// this is refused as degenerate: stricter than a local match's, since a closure's
    /// edge is stiff (σ 1 cm) and links places far apart along the path.
    pub loop_closure_degeneracy_ratio: f64,
    /// Huber scale of loop-closure edges (whitened units), in the first pass of every
    /// optimisation.
    pub loop_closure_huber: f64,
    /// Φ of the dynamic covariance scaling of loop-closure edges in the second pass
    /// (whitened units): a closure whose χ² exceeds it pulls less, and one far beyond it
    /// not at all.
    pub loop_closure_dcs: f64,
    /// The search window grows by this many metres per metre driven since the last
    /// accepted closure (the drift the estimate may have gathered) …
    pub loop_closure_window_growth: f64,
    /// … and by this many radians per metre …
    pub loop_closure_angular_growth_rad_per_m: f64,
    /// … up to this half-width, metres.
    pub loop_closure_max_linear_window_m: f64,
    /// A closure moving its node by at most this much (metres) …
    pub loop_closure_accept_shift_m: f64,
    /// … and this much (radians) from where the graph has it becomes an edge at once.
    pub loop_closure_accept_shift_rad: f64,
    /// A closure moving the node by more is a hypothesis until a later node, searched
    /// within this half-width (metres) …
    pub loop_closure_confirm_linear_window_m: f64,
    /// … and this (radians) around where the hypothesis puts it, agrees …
    pub loop_closure_confirm_angular_window_rad: f64,
    /// … within this much travel, metres.
    pub loop_closure_confirm_within_m: f64,
    /// After this much travel without a closure, metres, every batch also searches the
    /// newest node against finished submaps with no heading and no position …
    pub loop_closure_global_after_m: f64,
    /// … this many of them a batch (round robin) …
    pub loop_closure_global_submaps_per_batch: usize,
    /// … and needs this score.
    pub loop_closure_global_min_score: f32,
    /// Searches are run together every this many nodes …
    pub loop_closure_batch_nodes: usize,
    /// … within this much work a batch (grid lookups at the coarsest level of branch and
    /// bound: angles × coarsest nodes × points).
    pub loop_closure_work_per_batch: f64,
    /// σ of a loop closure (translation, metres).
    pub loop_closure_sigma_m: f64,
    /// σ of a loop closure (rotation, radians).
    pub loop_closure_sigma_rad: f64,
    /// Optimise the pose graph every this many new nodes (and once at the end).
    pub optimize_every_n_nodes: usize,
    /// … and this much travel, metres (a log with a node every few centimetres would
    /// otherwise optimise every few metres, most of its run time).
    pub optimize_every_m: f64,
    /// Levels of the branch-and-bound precomputation.
    pub branch_and_bound_depth: usize,
    /// GNSS fixes given with [`Slam::add_fixes`](super::Slam::add_fixes) become position
    /// priors on the nodes.
    pub fixes: bool,
    /// A fix is attached to the node nearest in time, if that is within this, seconds.
    pub fix_max_offset_s: f64,
    /// Huber scale of a fix's prior (whitened units).
    pub fix_huber: f64,
}

impl Default for SlamParams {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            // About what 60 nodes made on the SLAM-benchmark logs (a node every 10 cm), now
            // in metres: a log with a scan every metre gets submaps as large, not ten
            // times larger. A full turn on the spot also fills one.
            submap: SubmapBounds { distance_m: 6.0, rotation_rad: std::f64::consts::TAU, max_scans: 200 },
            hit_probability: 0.55,
            miss_probability: 0.49,
            field_sigma_m: 0.05,
            max_range_m: 30.0,
            max_track_speed_m_s: 20.0,
            max_track_turn_rate_rad_s: 720f64.to_radians(),
            min_points: 20,
            node_distance_m: 0.1,
            node_angle_rad: 2f64.to_radians(),
            node_time_s: 5.0,
            moving_prediction_margin: 0.1,
            // Lost matches score about half the usual (points on free space); 0.7 leaves
            // the ordinary spread of a good match's score out. The window is that of
            // Cartographer's real-time correlative matcher (20°), with twice its reach.
            rescue_score_ratio: 0.7,
            rescue_linear_window_m: 0.3,
            rescue_angular_window_rad: 20f64.to_radians(),
            local: LocalMatchParams::default(),
            odometry_translation_per_m: 0.1,
            odometry_floor_m: 0.02,
            odometry_rotation_per_rad: 0.1,
            odometry_floor_rad: 1f64.to_radians(),
            loop_closure: true,
            loop_closure_sampling_ratio: 1.0,
            loop_closure_node_spacing_m: 1.0,
            loop_closure_submaps_per_node: 6,
            loop_closure_nodes_per_submap: 20,
            loop_closure_links_per_pair: 4,
            loop_closure_max_range_m: 12.0,
            loop_closure_max_points: 120,
            loop_closure_grid_cache_mib: 64,
            loop_closure_max_distance_m: 15.0,
            loop_closure_linear_window_m: 2.0,
            loop_closure_angular_window_rad: 10f64.to_radians(),
            loop_closure_min_score: 0.55,
            loop_closure_degeneracy_ratio: 0.1,
            loop_closure_huber: 1.0,
            loop_closure_dcs: 25.0,
            loop_closure_window_growth: 0.05,
            loop_closure_angular_growth_rad_per_m: 0.02f64.to_radians(),
            loop_closure_max_linear_window_m: 50.0,
            loop_closure_accept_shift_m: 1.0,
            loop_closure_accept_shift_rad: 5f64.to_radians(),
            loop_closure_confirm_linear_window_m: 0.3,
            loop_closure_confirm_angular_window_rad: 3f64.to_radians(),
            loop_closure_confirm_within_m: 10.0,
            loop_closure_global_after_m: 50.0,
            loop_closure_global_submaps_per_batch: 2,
            loop_closure_global_min_score: 0.65,
            loop_closure_batch_nodes: 10,
            // About two hundred searches of the base window, or three of the widest.
            loop_closure_work_per_batch: 5e7,
            // A closure is refined to a fraction of a cell like a local match (whose own σ
            // is capped at 5 mm, 0.05°): a fifth of a 5 cm cell, and the angle that moves a
            // point 3 m away by about that much. Beyond one σ the Huber loss makes a closure
            // pull with a constant force, so a wrong one cannot drag the graph far.
            loop_closure_sigma_m: 0.01,
            loop_closure_sigma_rad: 0.2f64.to_radians(),
            optimize_every_n_nodes: 90,
            optimize_every_m: 10.0,
            // Wide windows start at the coarsest level (levels_for); narrow ones lower.
            branch_and_bound_depth: 9,
            fixes: true,
            // Nodes come every 10 cm or 5 s; the track's motion over half a second moves the
            // lever arm by far less than a fix's σ.
            fix_max_offset_s: 0.5,
            // Fixes are gated already; past 2 σ one pulls with a constant force, so a
            // surviving multipath fix cannot bend the graph.
            fix_huber: 2.0,
        }
    }
}
