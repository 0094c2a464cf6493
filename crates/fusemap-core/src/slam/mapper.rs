//! The SLAM loop: local matching into submaps, nodes and constraints into a pose graph,
//! loop-closure search on finished submaps, and the optimised trajectory.
//!
//! Local SLAM (Hess et al. 2016, §IV): each scan's pose is predicted from the previous
//! scan's matched pose and the pose track's motion between the two stamps (odometry, IMU
//! and fixes already fused by the estimator), then matched against the older active
//! submap. The predicted motion is the prior of the match: where the lidar sees structure
//! the match dominates (the refinement pulls the translation to the prediction, weakly),
//! and where the match is degenerate (a corridor) it is refined again from the prediction
//! with ten times that pull, so the prediction carries the pose there.
//!
//! Global SLAM (§V): every scan that moved far enough becomes a node; it is tied to the
//! submaps it went into by its local pose (information from the match's curvature) and to
//! the previous node by the track's motion (an odometry edge, whose σ grows with the
//! distance). Nodes are searched against finished submaps near them by branch-and-bound
//! (loop closures, Huber loss), and the graph is optimised every few nodes and at the end.
//! GNSS fixes, when given, are position priors on the nodes nearest them in time
//! (`fixes.rs`). Every scan's final pose is its nearest earlier node's optimised pose
//! composed with the local offset between the two.

use super::fixes::{FixNode, FixPriors, PositionFix};
use super::grid::ProbabilityGrid;
use super::grid_cache::GridCache;
use super::local_match::{refine, LocalMatch, LocalMatchParams};
use super::loop_closure::{Loops, OpenSearch};
use super::odometry::OdometryAgreement;
use super::optimisation::Pending;
use super::params::SlamParams;
use super::pose_graph::PoseGraph;
use super::report::SlamReport;
use super::submap::Submaps;
use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::parallel::{join, on_worker};
use crate::time::Stamp;
use std::time::Instant;

/// Where a scan is searched from (`Mapper::predict`).
struct Prediction {
    /// The track's reading repeats the last one bit for bit.
    held: bool,
    /// The track's motion since the last scan, when it has a plausible one.
    track_motion: Option<Pose2>,
    /// The prediction.
    predicted: Pose2,
    /// The constant-velocity hypothesis.
    moving: Option<Pose2>,
}

/// One scan as SLAM takes it. Points are in the base frame.
#[derive(Clone, Copy, Debug)]
pub struct ScanInput<'a> {
    /// The scan's stamp.
    pub stamp: Stamp,
    /// `map_from_base` at the stamp from the pose track (odometry or the estimator): only
    /// its motion between scans is used. `None` inside a gap of the track: the scan is
    /// matched from the previous scan's pose.
    pub track: Option<Pose2>,
    /// The sensor's origin in the base frame.
    pub origin: Point2,
    /// Returns.
    pub hits: &'a [Point2],
    /// Ends of free rays without a return (beyond the sensor's range), if any.
    pub misses: &'a [Point2],
}

/// What became of a scan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScanOutcome {
    /// Matched against a submap.
    Matched,
    /// Matched, but degenerate (a corridor): refined again from the prediction with ten
    /// times the pull towards it.
    Degenerate,
    /// Too few usable returns (or no submap yet): the predicted pose was kept.
    Predicted,
    /// Refused: a non-finite track pose, or a sensor origin not finite or farther from the
    /// base than `max_range_m`.
    Refused,
}

struct ScanRecord {
    stamp: Stamp,
    local: Pose2,
    anchor: Option<usize>,
}

pub(super) struct Node {
    pub(super) stamp: Stamp,
    pub(super) local: Pose2,
    pub(super) track: Option<Pose2>,
    pub(super) graph: usize,
    /// The scan's returns in the base frame, for the loop-closure refinement, in `f32` (to
    /// 4 µm within 64 m of the base): a node is kept for the whole log, and in `f64` its
    /// points were 168 MB of an hour's simulated run.
    pub(super) points: Vec<[f32; 2]>,
    /// Which of `points` the loop-closure search matches (indices: a node is kept for the
    /// whole log, and copies of the points were 35 MB of an hour's nodes).
    pub(super) search: Vec<u32>,
    pub(super) submaps: Vec<usize>,
    /// Travel of the local trajectory up to this node, metres.
    pub(super) path_m: f64,
}

impl Node {
    /// The points the loop-closure refinement matches.
    pub(super) fn points(&self) -> Vec<Point2> {
        self.points.iter().map(|&p| widen(p)).collect()
    }

    /// The points the loop-closure search matches.
    pub(super) fn search_points(&self) -> Vec<Point2> {
        self.search.iter().map(|&i| widen(self.points[i as usize])).collect()
    }
}

fn widen(p: [f32; 2]) -> Point2 {
    Point2::new(f64::from(p[0]), f64::from(p[1]))
}

/// The SLAM state over one log. Feed scans in time order with [`add_scan`](Self::add_scan),
/// then [`finish`](Self::finish).
pub struct Slam {
    pub(super) p: SlamParams,
    pub(super) submaps: Submaps,
    pub(super) submap_graph: Vec<usize>,
    /// Finished submaps (searched for loop closures).
    pub(super) finished: Vec<bool>,
    pub(super) grids: GridCache,
    pub(super) loops: Loops,
    pub(super) graph: PoseGraph,
    pub(super) nodes: Vec<Node>,
    scans: Vec<ScanRecord>,
    /// The last scan's local pose, and its track pose if it had one.
    pub(super) last: Option<(Pose2, Option<Pose2>)>,
    /// The stamp of that scan.
    last_stamp: Stamp,
    /// The most bytes the submaps' grids have held at once.
    submap_peak_bytes: usize,
    /// Bytes held by the nodes (their points, search indices and submap lists).
    node_bytes: usize,
    /// The last two scans' stamps and local poses (the constant-velocity prediction).
    pub(super) recent: [Option<(Stamp, Pose2)>; 2],
    pub(super) global_from_local: Pose2,
    /// The recent matches' mean probability (the rescue search's reference).
    pub(super) typical_score: Option<f64>,
    pub(super) since_optimisation: usize,
    /// Travel at the last optimisation, metres.
    pub(super) optimised_at_m: f64,
    /// The optimisation under way beside the matching.
    pub(super) pending: Option<Pending>,
    pub(super) fixes: FixPriors,
    /// How well the track's motion has agreed with the matches.
    pub(super) odometry: OdometryAgreement,
    pub(super) report: SlamReport,
}

/// The result of a SLAM run.
pub struct SlamResult {
    /// Every scan's optimised `map_from_base`, in input order.
    pub trajectory: Vec<(Stamp, Pose2)>,
    /// The nodes' stamps, graph indices of nodes in node order.
    pub node_stamps: Vec<Stamp>,
    /// The pose graph (nodes: scans then submaps interleaved as created).
    pub graph: PoseGraph,
    /// Graph indices of the submaps.
    pub submap_nodes: Vec<usize>,
    /// Graph indices of the scan nodes.
    pub scan_nodes: Vec<usize>,
    /// Counts and timings.
    pub report: SlamReport,
    /// The loop-closure searches that closed no loop, and why (at most
    /// 100,000).
    pub open_loops: Vec<OpenSearch>,
}

/// Two poses equal to the bit (a repeated reading, not a coincidence of motion).
fn same_bits(a: Pose2, b: Pose2) -> bool {
    [a.x, a.y, a.theta].map(f64::to_bits) == [b.x, b.y, b.theta].map(f64::to_bits)
}

/// A match whose translational information is this well conditioned (smallest over largest
/// eigenvalue) constrains both directions of the plane: a room, not a corridor.
const WELL_POSED: f64 = 0.25;

/// The smallest over the largest eigenvalue of the translational part of `info`.
fn translation_conditioning(info: &[[f64; 3]; 3]) -> f64 {
    let (a, b, c) = (info[0][0], info[0][1], info[1][1]);
    let disc = ((a - c) * (a - c) / 4.0 + b * b).sqrt();
    let (hi, lo) = ((a + c) / 2.0 + disc, (a + c) / 2.0 - disc);
    if hi > 0.0 {
        (lo / hi).max(0.0)
    } else {
        0.0
    }
}

pub(super) fn information_diag(sx: f64, sth: f64) -> [[f64; 3]; 3] {
    [[1.0 / (sx * sx), 0.0, 0.0], [0.0, 1.0 / (sx * sx), 0.0], [0.0, 0.0, 1.0 / (sth * sth)]]
}

impl Slam {
    /// An empty run.
    pub fn new(p: SlamParams) -> Self {
        Self {
            submaps: Submaps::new(p.resolution, p.submap, p.hit_probability, p.miss_probability, p.field_sigma_m),
            p,
            submap_graph: Vec::new(),
            finished: Vec::new(),
            grids: GridCache::new(p.loop_closure_grid_cache_mib.saturating_mul(1 << 20), p.branch_and_bound_depth),
            loops: Loops::new(),
            graph: PoseGraph::new(),
            nodes: Vec::new(),
            scans: Vec::new(),
            last: None,
            last_stamp: Stamp(0),
            submap_peak_bytes: 0,
            node_bytes: 0,
            recent: [None, None],
            global_from_local: Pose2::IDENTITY,
            typical_score: None,
            since_optimisation: 0,
            optimised_at_m: 0.0,
            pending: None,
            fixes: FixPriors::new(),
            odometry: OdometryAgreement::default(),
            report: SlamReport::default(),
        }
    }

    /// The counters so far.
    pub fn report(&self) -> &SlamReport {
        &self.report
    }

    /// Adds GNSS fixes in the track's map frame (any order, before or between scans): each
    /// becomes a position prior on the node nearest it in time. Ignored when
    /// [`SlamParams::fixes`] is off.
    pub fn add_fixes(&mut self, fixes: &[PositionFix]) {
        if self.p.fixes {
            self.fixes.add(fixes, &mut self.report);
        }
    }

    /// The node `n` as a fix sees it.
    fn fix_node(&self, n: usize) -> Option<FixNode> {
        self.nodes.get(n).map(|n| FixNode { stamp: n.stamp, track: n.track, graph: n.graph })
    }

    /// Attaches the fixes up to `upto` to node `n` or the one before it.
    fn attach_fixes(&mut self, upto: Stamp, n: usize) {
        let in_track_frame = self.nodes.first().is_some_and(|n| n.track.is_some());
        let (before, after) = (n.checked_sub(1).and_then(|b| self.fix_node(b)), self.fix_node(n));
        self.fixes.attach(upto, before, after, in_track_frame, &mut self.graph, &self.p, &mut self.report);
    }

    /// Bytes held by the submaps' grids, the loop search's branch-and-bound grids and the
    /// nodes' points, what `limits.memory_mib` holds SLAM to (the scans' records and the
    /// pose graph, a few hundred bytes a scan, are left out).
    pub fn held_bytes(&self) -> usize {
        self.submaps.bytes() + self.grids.bytes() + self.node_bytes
    }

    /// Adds the next scan (stamps non-decreasing).
    pub fn add_scan(&mut self, scan: ScanInput) -> ScanOutcome {
        self.report.scans += 1;
        // A sensor farther from the base than its own range is no mount (and would put the
        // scan's returns where no submap reaches).
        let far_origin = scan.origin.x.hypot(scan.origin.y) > self.p.max_range_m;
        if scan.track.is_some_and(|t| !t.is_finite()) || !scan.origin.is_finite() || far_origin {
            self.report.refused += 1;
            return ScanOutcome::Refused;
        }
        let max2 = self.p.max_range_m * self.p.max_range_m;
        let in_range = |q: &&Point2| {
            let (dx, dy) = (q.x - scan.origin.x, q.y - scan.origin.y);
            q.is_finite() && dx * dx + dy * dy <= max2
        };
        let hits: Vec<Point2> = scan.hits.iter().filter(in_range).copied().collect();
        let Prediction { held, track_motion, predicted, moving } = self.predict(&scan);
        let t0 = Instant::now();
        let (local, outcome, information) = on_worker(|| self.match_local(&hits, predicted, moving, track_motion));
        // The track is judged only by matches that pin the scan down in every direction: along
        // a corridor the match's position is the track's own, and would flatter it.
        let well_posed = information.is_some_and(|i| translation_conditioning(&i) >= WELL_POSED);
        if let (Some(d), Some((before, _)), ScanOutcome::Matched, true) = (track_motion, self.last, outcome, well_posed)
        {
            self.odometry.observe(&self.p, d, before.inverse().compose(local));
            self.report.odometry_samples += 1;
        }
        self.recent = [self.recent[1], Some((scan.stamp, local))];
        self.report.matching_s += t0.elapsed().as_secs_f64();
        match outcome {
            ScanOutcome::Matched => self.report.matched += 1,
            ScanOutcome::Degenerate => self.report.degenerate += 1,
            _ => self.report.predicted += 1,
        }
        if !held {
            self.last = Some((local, scan.track));
            self.last_stamp = scan.stamp;
        }
        let anchor = self.nodes.last().map(|_| self.nodes.len() - 1);
        self.scans.push(ScanRecord { stamp: scan.stamp, local, anchor });
        if self.is_new_node(scan.stamp, local) && !held {
            let misses: Vec<Point2> = scan.misses.iter().filter(|q| q.is_finite()).copied().collect();
            self.add_node(scan.stamp, local, scan.track, scan.origin, hits, &misses, information);
            self.scans.last_mut().expect("pushed above").anchor = Some(self.nodes.len() - 1);
        }
        outcome
    }

    /// The pose the scan is searched from: the last scan's moved by the track's motion
    /// since (none across a held reading or a jump of the track), and the
    /// constant-velocity hypothesis; counts held readings, jumps and scans without a track.
    fn predict(&mut self, scan: &ScanInput) -> Prediction {
        // A reading that repeats the anchor's bit for bit is held, not a standstill: odometry
        // latched on the scan lines (CARMEN logs) repeats its last value for a few scans
        // during a fast turn, then jumps by the whole turn. It says nothing of the motion
        // since, so the scan is predicted from the previous scan (the search and the
        // constant-velocity hypothesis find it), it is no node (a scan matched without a
        // prior must not go into the submaps), and the next fresh reading is composed onto
        // the scan where the held one was first seen. A robot at rest loses nothing: its
        // scans repeat the same view.
        let held = matches!((self.last, scan.track), (Some((_, Some(before))), Some(now)) if same_bits(before, now));
        if held {
            self.report.held_readings += 1;
        }
        // The track's own motion since the last scan, when it has one and it is a motion a
        // robot can make: a jump (an odometry reset, a GNSS teleport the estimator took) is
        // a gap of the track, counted, and the track is followed again from its new place.
        let last_track = self.last.and_then(|(_, t)| t).map(|t| (t, self.last_stamp));
        let jumped = !held
            && matches!((last_track, scan.track), (Some((before, t)), Some(now)) if self.jumps(t, before, scan.stamp, now));
        self.report.track_jumps += u64::from(jumped);
        let track_motion = match (last_track, scan.track) {
            (Some((before, _)), Some(now)) if !held && !jumped => Some(before.inverse().compose(now)),
            _ => None,
        };
        let predicted = match (self.last, track_motion) {
            _ if held => self.recent[1].map_or(Pose2::IDENTITY, |r| r.1),
            (Some((local, _)), Some(d)) => local.compose(d),
            // In or just out of a gap of the track: no motion known, the search finds it.
            (Some((local, _)), None) => local,
            (None, _) => scan.track.unwrap_or(Pose2::IDENTITY),
        };
        if scan.track.is_none() {
            self.report.without_track += 1;
        }
        // The constant-velocity prediction from the last two scans' poses: a second
        // hypothesis for when the track's motion is wrong (odometry written on scan lines
        // that stalls for a few scans and then catches up, a wheel that slips).
        let moving = match self.recent {
            [Some((t1, p1)), Some((t2, p2))] if t2 > t1 && scan.stamp > t2 => {
                let k = (scan.stamp.0 - t2.0) as f64 / (t2.0 - t1.0) as f64;
                let d = p1.inverse().compose(p2);
                (k <= 3.0).then(|| p2.compose(Pose2::new(d.x * k, d.y * k, d.theta * k)))
            }
            _ => None,
        };
        Prediction { held, track_motion, predicted, moving }
    }

    /// Whether a scan at `stamp` placed at `local` is far enough (in distance, angle or
    /// time) from the last node to be a node.
    fn is_new_node(&self, stamp: Stamp, local: Pose2) -> bool {
        match self.nodes.last() {
            None => true,
            Some(n) => {
                let d = n.local.inverse().compose(local);
                d.x.hypot(d.y) >= self.p.node_distance_m
                    || d.theta.abs() >= self.p.node_angle_rad
                    || (stamp.0 - n.stamp.0) as f64 * 1e-9 >= self.p.node_time_s
            }
        }
    }

    /// Whether the track moving from `before` (at `t0`) to `now` (at `t1`) is faster than
    /// `max_track_speed_m_s` or `max_track_turn_rate_rad_s` allow (with the glitch filter's
    /// stamp jitter). Equal stamps say nothing of speed and are never a jump (the `%g`
    /// stamps of some CARMEN logs).
    fn jumps(&self, t0: Stamp, before: Pose2, t1: Stamp, now: Pose2) -> bool {
        let limits = crate::time::MotionLimits {
            max_speed_m_s: self.p.max_track_speed_m_s,
            max_turn_rate_rad_s: self.p.max_track_turn_rate_rad_s,
        };
        t1 != t0 && !limits.plausible((t0, before), (t1, now))
    }

    fn match_local(
        &mut self,
        hits: &[Point2],
        predicted: Pose2,
        moving: Option<Pose2>,
        track_motion: Option<Pose2>,
    ) -> (Pose2, ScanOutcome, Option<[[f64; 3]; 3]>) {
        // A rescue (a wide search) may not put the scan where the track's motion makes it
        // implausible (beyond 5 σ of what the track has shown, never tighter than the
        // model): a good track outweighs one far match found in a wide window. An
        // ordinary match is not gated: odometry that has agreed for minutes still slips,
        // and on Freiburg 079 overriding weak matches with it moved the track by metres.
        let p = self.p;
        let odometry = self.odometry;
        let plausible = |pose: Pose2| {
            track_motion.is_none_or(|d| odometry.plausible(&p, d, d.compose(predicted.inverse().compose(pose)), 5.0))
        };
        let Some((_, submap)) = self.submaps.matching() else {
            return (predicted, ScanOutcome::Predicted, None);
        };
        if hits.len() < self.p.min_points {
            return (predicted, ScanOutcome::Predicted, None);
        }
        // Outside half the search window of the track's prediction, the constant-velocity
        // prediction is searched too (on the other thread), and kept only if its match is
        // clearly better (mean probability higher by `moving_prediction_margin`): in a
        // corridor both fit equally, and preferring the extrapolation there would feed its
        // own slide back into the next prediction.
        let local = &self.p.local;
        let g = &submap.grid;
        let (mut m, m2) = search_predictions(g, hits, predicted, moving, local);
        let mut predicted = predicted;
        // The constant-velocity prediction, clearly better, is the odometry's failure (a jump,
        // a stall).
        if let Some((m2, alt)) = m2 {
            self.report.moving_prediction_searched += 1;
            if f64::from(m2.score) > f64::from(m.score) + self.p.moving_prediction_margin {
                self.report.moving_prediction_used += 1;
                (m, predicted) = (m2, alt);
            }
        }
        // A match far below the recent ones lost the scan: the prediction was off by more
        // than the window (odometry that overshoots a fast turn). It is searched again in
        // the wide window and replaced only if that is clearly better.
        let typical = self.typical_score.unwrap_or(0.0);
        if f64::from(m.score) < self.p.rescue_score_ratio * typical {
            let wide = LocalMatchParams {
                linear_window_m: self.p.rescue_linear_window_m,
                angular_window_rad: self.p.rescue_angular_window_rad,
                ..*local
            };
            let r = super::local_match::match_scan(g, hits, predicted, &wide);
            self.report.rescue_searched += 1;
            if f64::from(r.score) > f64::from(m.score) + self.p.moving_prediction_margin && plausible(r.pose) {
                m = r;
                self.report.rescued += 1;
            }
        }
        // The recent matches' score, an exponential average over about ten scans.
        let score = f64::from(m.score);
        self.typical_score = Some(self.typical_score.map_or(score, |t| 0.9 * t + 0.1 * score));
        if m.degenerate {
            let strong = LocalMatchParams {
                translation_weight: self.p.local.translation_weight * 10.0,
                rotation_weight: self.p.local.rotation_weight,
                ..self.p.local
            };
            let pose = refine(g, hits, predicted, predicted, &strong);
            return (pose, ScanOutcome::Degenerate, Some(m.information));
        }
        (m.pose, ScanOutcome::Matched, Some(m.information))
    }

    #[allow(clippy::too_many_arguments)]
    fn add_node(
        &mut self,
        stamp: Stamp,
        local: Pose2,
        track: Option<Pose2>,
        origin: Point2,
        hits: Vec<Point2>,
        misses: &[Point2],
        information: Option<[[f64; 3]; 3]>,
    ) {
        let to = local.point_transform();
        let to_local = |q: &Point2| to(*q);
        let local_hits: Vec<Point2> = hits.iter().map(to_local).collect();
        let local_misses: Vec<Point2> = misses.iter().map(to_local).collect();
        let before = self.submaps.all().len();
        let (into, finished) = self.submaps.insert(local, local.transform_point(origin), &local_hits, &local_misses);
        self.submap_peak_bytes = self.submap_peak_bytes.max(self.submaps.bytes());
        for s in before..self.submaps.all().len() {
            let g = self.graph.add_node(self.global_from_local.compose(self.submaps.all()[s].local_pose));
            self.submap_graph.push(g);
            self.finished.push(false);
            self.grids.add_submap();
            self.loops.footprints.push(Default::default());
        }
        let g = self.graph.add_node(self.global_from_local.compose(local));
        if self.nodes.is_empty() {
            self.graph.set_fixed(g, true);
        }
        self.add_match_edges(g, local, &into, information);
        self.add_odometry_edge(g, local, track);
        // The global search's cost grows with the farthest point (its angular step), so
        // it looks at the returns within `loop_closure_max_range_m`.
        let r2 = self.p.loop_closure_max_range_m * self.p.loop_closure_max_range_m;
        // (A scan is held to `limits.beams`; points past index 2³² − 1 would not be
        // searched.)
        let near: Vec<u32> = (0..u32::try_from(hits.len()).unwrap_or(u32::MAX))
            .filter(|&i| {
                let q = hits[i as usize];
                let (dx, dy) = (q.x - origin.x, q.y - origin.y);
                dx * dx + dy * dy <= r2
            })
            .collect();
        // … and at most `loop_closure_max_points` of them, evenly spread over the scan.
        let stride = near.len().div_ceil(self.p.loop_closure_max_points.max(1)).max(1);
        let mut search: Vec<u32> = near.into_iter().step_by(stride).collect();
        search.shrink_to_fit();
        let path_m = self.nodes.last().map_or(0.0, |n| n.path_m + n.local.translation().distance(local.translation()));
        for &s in &into {
            let origin = self.submaps.all()[s].local_pose.translation();
            self.loops.footprints[s].add(Point2::new(local.x - origin.x, local.y - origin.y), path_m);
        }
        // A node is kept for the whole log: its points without spare room.
        let points: Vec<[f32; 2]> = hits.iter().map(|p| [p.x as f32, p.y as f32]).collect();
        self.node_bytes += std::mem::size_of::<Node>()
            + points.capacity() * std::mem::size_of::<[f32; 2]>()
            + search.capacity() * std::mem::size_of::<u32>()
            + into.capacity() * std::mem::size_of::<usize>();
        self.nodes.push(Node { stamp, local, track, graph: g, points, search, submaps: into, path_m });
        self.report.nodes += 1;
        self.attach_fixes(stamp, self.nodes.len() - 1);
        self.report.submaps = self.submaps.all().len();
        self.take_optimisation_if_due();
        if self.p.loop_closure {
            self.loop_closure_after_node(&finished);
        }
        self.optimise_if_due();
    }

    /// Optimises once more and returns every scan's pose.
    pub fn finish(mut self) -> SlamResult {
        self.take_optimisation();
        self.finish_loops();
        if let Some(last) = self.nodes.len().checked_sub(1) {
            self.attach_fixes(Stamp(i64::MAX), last + 1);
            self.optimise_last();
        }
        self.report.travel_m = self.nodes.last().map_or(0.0, |n| n.path_m);
        self.report.grids_built = self.grids.built;
        self.report.grids_peak_bytes = self.grids.peak_bytes;
        self.report.submap_peak_bytes = self.submap_peak_bytes;
        self.report.odometry_scale = self.odometry.scales();
        // Without a node (no scan), every fix is left unplaced, and counted.
        self.report.fixes_unplaced += self.fixes.pending() as u64;
        let trajectory = self
            .scans
            .iter()
            .filter_map(|s| {
                let n = &self.nodes[s.anchor?];
                let g = self.graph.nodes()[n.graph];
                let p = g.compose(n.local.inverse().compose(s.local));
                Some((s.stamp, Pose2::new(p.x, p.y, normalize_angle(p.theta))))
            })
            .collect();
        SlamResult {
            trajectory,
            node_stamps: self.nodes.iter().map(|n| n.stamp).collect(),
            scan_nodes: self.nodes.iter().map(|n| n.graph).collect(),
            submap_nodes: self.submap_graph,
            graph: self.graph,
            report: self.report,
            open_loops: self.loops.open,
        }
    }
}

/// The local match at the track's prediction and, when the constant-velocity prediction
/// `moving` lies outside half the search window of it, at that one too (on the other
/// thread), with the pose it was searched at.
fn search_predictions(
    g: &ProbabilityGrid,
    hits: &[Point2],
    predicted: Pose2,
    moving: Option<Pose2>,
    local: &LocalMatchParams,
) -> (LocalMatch, Option<(LocalMatch, Pose2)>) {
    let alt = moving.filter(|alt| {
        let d = predicted.inverse().compose(*alt);
        d.x.hypot(d.y) > 0.5 * local.linear_window_m || d.theta.abs() > 0.5 * local.angular_window_rad
    });
    let search = |at: Pose2| super::local_match::match_scan(g, hits, at, local);
    match alt {
        Some(alt) => {
            let (m, m2) = join(|| search(predicted), || search(alt));
            (m, Some((m2, alt)))
        }
        None => (search(predicted), None),
    }
}

#[cfg(test)]
#[path = "mapper_tests.rs"]
mod tests;
