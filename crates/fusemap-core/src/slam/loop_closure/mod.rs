//! Loop closure: which node–submap pairs are searched, in batches on every core, and which
//! of the matches found become pose-graph edges.
//!
//! **Where to look.** A node is searched against the finished submaps near it in the
//! current estimate, and a submap just finished against the earlier nodes near it (Hess et
//! al. 2016, §V). The window is not fixed: the estimate's error grows with the distance
//! driven since the last accepted closure, so the window grows with it
//! (`loop_closure_window_growth`, `loop_closure_angular_growth_rad_per_m`, up to
//! `loop_closure_max_linear_window_m`), and so does the radius in which submaps count as
//! near. After `loop_closure_global_after_m` without closing a loop with a submap left
//! behind (one last added to at least `loop_closure_max_distance_m` of travel before),
//! every batch also searches the newest node against a few finished submaps (round robin
//! over all of them) with no heading and a window over the whole of each submap: a place
//! revisited after more drift than any window allows is still found. (Cartographer
//! searches globally only across trajectories, slam_toolbox not at all.) The graph
//! distance is no trigger for it: once a building's loops are tied it is short
//! everywhere, and on the Intel bag the global search then took two thirds of all the
//! search work.
//!
//! **How often.** At most one node per `loop_closure_node_spacing_m` of travel is searched
//! against the submaps near it, so a 40 Hz log and one with a scan per metre search as
//! often per metre; two submaps already tied by `loop_closure_links_per_pair` accepted
//! closures are not searched against each other again.
//!
//! **When.** Pairs are collected as nodes arrive and searched every
//! `loop_closure_batch_nodes` nodes (and before each optimisation and at the end): the
//! branch-and-bound grids the batch needs are built first, then every search of the batch
//! runs in parallel (rayon), and the results are taken in the order the pairs were made.
//! Batches fall at fixed nodes, never on a timer, so the trajectory is the same to the bit
//! on any number of threads. A batch does at most `loop_closure_work_per_batch` work (grid
//! lookups at the coarsest level of branch and bound), confirmations first, then the
//! cheapest searches: the cost per node is bounded whatever the number of submaps.
//!
//! **What is accepted.** A match must reach the score threshold and must not be degenerate
//! (a corridor fits anywhere along itself). A match that moves the node by no more than the
//! base window (the drift ordinary local SLAM leaves) becomes an edge at once. A larger
//! correction, from a widened window or the global search, is a hypothesis until a later
//! node, searched in a small window around where the hypothesis puts it, agrees: one
//! wrong match is easy to find in a repetitive building, two that agree on the same
//! rigid correction are not (the pairwise-consistency idea of Olson's single-cluster
//! graph partitioning, 2009, in its simplest form). A hypothesis that no node confirms
//! within `loop_closure_confirm_within_m` of travel is dropped.
//!
//! Every search that did not close a loop is kept with its best score (or an upper bound
//! of it), the reason, and whether the best pose lay on the window's edge, for the report:
//! a user can see why a loop stayed open.

use super::global_match::{levels_for, GlobalSearch};
use super::mapper::Slam;
use super::pose_graph::Edge;
use crate::geometry::Pose2;
use serde::Serialize;
use std::collections::HashMap;

mod batch;
mod drift;
mod index;

pub(super) use index::Footprint;
use index::SpatialHash;

/// Why a loop-closure search did not add an edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OpenReason {
    /// Nothing in the window reached the score threshold.
    Score,
    /// The best match fits anywhere along one direction (a corridor).
    Degenerate,
    /// A large correction no later node confirmed.
    Unconfirmed,
    /// A confirming search found nothing where the hypothesis puts the node.
    Disagrees,
}

/// A search that did not close a loop, as the report shows it.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct OpenSearch {
    /// The node (index among the nodes).
    pub node: usize,
    /// The submap (index among the submaps).
    pub submap: usize,
    /// The best match's score, or, when nothing reached the threshold, an upper bound of
    /// every score in the window.
    pub best_score: f32,
    /// Why it was not accepted.
    pub reason: OpenReason,
    /// The best pose lay on the edge of the window (the place may lie beyond it).
    pub on_edge: bool,
    /// A global search (no heading, the whole submap).
    pub global: bool,
}

/// What kind of search a pair is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Around the current estimate, window widened with the drift since the last closure.
    Local,
    /// No heading, the whole submap.
    Global,
    /// Around where hypothesis `id` puts the node, small window.
    Confirm(u64),
}

/// A node–submap search waiting for its batch.
#[derive(Clone, Copy, Debug)]
struct Pair {
    node: usize,
    submap: usize,
    kind: Kind,
}

/// A search ready to run: its pair, where it starts, its window.
#[derive(Clone, Copy, Debug)]
struct Planned {
    pair: Pair,
    initial: Pose2,
    search: GlobalSearch,
    /// The part of the window a correction may use and still be taken at once.
    base: (f64, f64),
}

/// What a search found.
struct Outcome {
    /// Refined pose in the submap's grid frame, its score, degenerate.
    found: Option<(Pose2, f32, bool)>,
    best_score: f32,
    on_edge: bool,
}

/// A large correction waiting for a second, agreeing match.
#[derive(Clone, Copy, Debug)]
struct Hypothesis {
    id: u64,
    edge: Edge,
    node: usize,
    submap: usize,
    /// The rigid motion, in the graph's frame, that moves the recent trajectory to where
    /// the match puts it.
    correction: Pose2,
    /// Travel at which it expires.
    expires_m: f64,
    score: f32,
    global: bool,
    /// Confirming searches asked for so far.
    attempts: usize,
}

/// The loop-closure state of a run.
#[derive(Debug)]
pub(super) struct Loops {
    pending: Vec<Pair>,
    nodes_since_batch: usize,
    /// Travel of the local trajectory at the last accepted closure.
    closed_at_m: f64,
    node_sampler: f64,
    /// Travel at the last node searched (NaN before the first).
    sampled_at_m: f64,
    hypotheses: Vec<Hypothesis>,
    next_id: u64,
    global_cursor: usize,
    /// Submap footprints, by submap.
    pub(super) footprints: Vec<Footprint>,
    /// Finished submaps' centres and the nodes, in the graph's current estimate.
    submap_index: SpatialHash,
    node_index: SpatialHash,
    /// Searches that did not close a loop.
    pub(super) open: Vec<OpenSearch>,
    /// Closures accepted since the last optimisation.
    pub(super) since_optimisation: usize,
    /// Accepted closures as pairs of submaps (one the node went into, the one it matched).
    links: Vec<(usize, usize)>,
    /// Accepted closures by unordered pair of submaps.
    link_count: HashMap<(usize, usize), usize>,
    /// Every submap's distance from the newest one through the graph, when last computed
    /// ([`Slam::update_drift`]), and the travel then.
    drift: Vec<f64>,
    drift_at_m: f64,
    /// A long loop was closed since: compute the distances again before the next batch.
    drift_stale: bool,
    /// A confirmed large correction: optimise before the next batch.
    pub(super) optimise_now: bool,
}

/// Cells of the spatial indices, metres.
const INDEX_CELL_M: f64 = 10.0;
/// Two matches confirm each other only from nodes at least this far apart along the path,
/// metres: one scan matched into two neighbouring submaps is one observation.
const CONFIRM_SEPARATION_M: f64 = 1.0;
/// A hypothesis asks at most this many later nodes to confirm it.
const CONFIRM_ATTEMPTS: usize = 6;
/// At most this many hypotheses wait at once (the oldest goes first).
const MAX_HYPOTHESES: usize = 16;
/// At most this many open searches are kept for the report.
pub(super) const MAX_OPEN_REPORTED: usize = 100_000;

impl Loops {
    pub(super) fn new() -> Self {
        Self {
            pending: Vec::new(),
            nodes_since_batch: 0,
            closed_at_m: 0.0,
            node_sampler: 0.0,
            sampled_at_m: f64::NAN,
            hypotheses: Vec::new(),
            next_id: 0,
            global_cursor: 0,
            footprints: Vec::new(),
            submap_index: SpatialHash::new(INDEX_CELL_M),
            node_index: SpatialHash::new(INDEX_CELL_M),
            open: Vec::new(),
            since_optimisation: 0,
            links: Vec::new(),
            link_count: HashMap::new(),
            drift: Vec::new(),
            drift_at_m: 0.0,
            drift_stale: false,
            optimise_now: false,
        }
    }
}

impl Slam {
    /// Rebuilds the spatial indices from the graph's estimate (after an optimisation).
    pub(super) fn reindex(&mut self) {
        let mut submaps = SpatialHash::new(INDEX_CELL_M);
        for s in (0..self.finished.len()).filter(|&s| self.finished[s]) {
            submaps.insert(s, self.submap_centre(s));
        }
        let mut nodes = SpatialHash::new(INDEX_CELL_M);
        for n in 0..self.nodes.len() {
            nodes.insert(n, self.node_position(n));
        }
        (self.loops.submap_index, self.loops.node_index) = (submaps, nodes);
    }

    /// Queues the searches a new node brings (and a submap it finished), and runs the
    /// batch when due.
    pub(super) fn loop_closure_after_node(&mut self, finished: &[usize]) {
        let n = self.nodes.len() - 1;
        let p = self.node_position(n);
        self.loops.node_index.insert(n, p);
        let far = self.max_reach();
        for &f in finished {
            self.finished[f] = true;
            let c = self.submap_centre(f);
            self.loops.submap_index.insert(f, c);
            // Earlier nodes near the submap just finished, evenly sampled.
            let near: Vec<usize> =
                self.loops.node_index.near(c, far).into_iter().filter(|&m| self.is_candidate(m, f)).collect();
            let stride = near.len().div_ceil(self.p.loop_closure_nodes_per_submap.max(1)).max(1);
            for &m in near.iter().step_by(stride) {
                self.loops.pending.push(Pair { node: m, submap: f, kind: Kind::Local });
            }
        }
        // The new node, sampled, against the nearest finished submaps.
        let spaced = self.nodes[n].path_m - self.loops.sampled_at_m >= self.p.loop_closure_node_spacing_m
            || self.loops.sampled_at_m.is_nan();
        if spaced {
            self.loops.node_sampler += self.p.loop_closure_sampling_ratio;
        }
        if spaced && self.loops.node_sampler >= 1.0 {
            self.loops.node_sampler -= 1.0;
            self.loops.sampled_at_m = self.nodes[n].path_m;
            let mut near: Vec<(f64, usize)> = self
                .loops
                .submap_index
                .near(p, far)
                .into_iter()
                .filter(|&s| self.is_candidate(n, s))
                .map(|s| (self.submap_centre(s).distance(p), s))
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(_, s) in near.iter().take(self.p.loop_closure_submaps_per_node) {
                self.loops.pending.push(Pair { node: n, submap: s, kind: Kind::Local });
            }
        }
        // Every waiting hypothesis asks the new node to confirm it, in the submap (of its own
        // and the two beside it) nearest where it puts the node, a few times at most.
        let gn = self.graph.nodes()[self.nodes[n].graph];
        for k in 0..self.loops.hypotheses.len() {
            let h = self.loops.hypotheses[k];
            if h.attempts >= CONFIRM_ATTEMPTS
                || (self.nodes[n].path_m - self.nodes[h.node].path_m).abs() < CONFIRM_SEPARATION_M
            {
                continue;
            }
            let at = h.correction.compose(gn).translation();
            let best = [h.submap.wrapping_sub(1), h.submap, h.submap + 1]
                .into_iter()
                .filter(|&s| s < self.finished.len() && self.finished[s] && !self.nodes[n].submaps.contains(&s))
                .min_by(|&a, &b| self.submap_centre(a).distance(at).total_cmp(&self.submap_centre(b).distance(at)));
            if let Some(s) = best {
                self.loops.hypotheses[k].attempts += 1;
                self.loops.pending.push(Pair { node: n, submap: s, kind: Kind::Confirm(h.id) });
            }
        }
        self.loops.nodes_since_batch += 1;
        if self.loops.nodes_since_batch >= self.p.loop_closure_batch_nodes.max(1) {
            self.run_loop_batch();
        }
    }

    /// True when node `n` may close a loop with finished submap `s`: not one it went
    /// into, and within the reach its drift allows.
    fn is_candidate(&self, n: usize, s: usize) -> bool {
        let limit = self.p.loop_closure_links_per_pair;
        // Tied: every submap the node went into already has `limit` closures to `s`.
        let tied = |a: usize| self.loops.link_count.get(&(a.min(s), a.max(s))).is_some_and(|&c| c >= limit);
        self.finished[s]
            && !self.nodes[n].submaps.contains(&s)
            && !(limit > 0 && !self.nodes[n].submaps.is_empty() && self.nodes[n].submaps.iter().all(|&a| tied(a)))
            && self.submap_centre(s).distance(self.node_position(n)) <= self.reach(n, s)
    }

    /// The global searches of this batch: the newest node against the next few finished
    /// submaps, round robin, leaving out those the local search reaches.
    fn global_pairs(&mut self) -> Vec<Pair> {
        let Some(n) = self.nodes.len().checked_sub(1) else { return Vec::new() };
        if self.p.loop_closure_global_submaps_per_batch == 0
            || self.since_closure_m() < self.p.loop_closure_global_after_m
        {
            return Vec::new();
        }
        let finished: Vec<usize> = (0..self.finished.len()).filter(|&s| self.finished[s]).collect();
        let recent = self.nodes[n].path_m - self.p.loop_closure_global_after_m;
        let mut out = Vec::new();
        for k in 0..finished.len() {
            if out.len() >= self.p.loop_closure_global_submaps_per_batch {
                break;
            }
            let s = finished[(self.loops.global_cursor + k) % finished.len()];
            // Submaps built within the last stretch are the local search's.
            let last_node_path = self.loops.footprints[s].last_path_m;
            if last_node_path >= recent || self.nodes[n].submaps.contains(&s) {
                continue;
            }
            out.push(Pair { node: n, submap: s, kind: Kind::Global });
        }
        if !finished.is_empty() {
            self.loops.global_cursor = (self.loops.global_cursor + out.len().max(1)) % finished.len();
        }
        out
    }

    /// Plans one pair: where its search starts and its window.
    fn plan(&self, pair: Pair) -> Option<Planned> {
        let window = self.window(pair.node, pair.submap);
        let node = &self.nodes[pair.node];
        let sm = &self.submaps.all()[pair.submap];
        let gs = self.graph.nodes()[self.submap_graph[pair.submap]];
        let gn = self.graph.nodes()[node.graph];
        let p = &self.p;
        let base = (p.loop_closure_accept_shift_m, p.loop_closure_accept_shift_rad);
        let search = |lin: f64, ang: f64, min_score: f32| GlobalSearch {
            linear_window_m: lin,
            angular_window_rad: ang,
            min_score,
            depth: levels_for(lin, p.resolution, p.branch_and_bound_depth),
        };
        let (initial, search) = match pair.kind {
            Kind::Local => {
                (sm.local_pose.compose(gs.inverse().compose(gn)), search(window.0, window.1, p.loop_closure_min_score))
            }
            Kind::Global => {
                let f = &self.loops.footprints[pair.submap];
                let c = f.centre();
                let at = Pose2::new(sm.local_pose.x + c.x, sm.local_pose.y + c.y, 0.0);
                let lin = f.half_extent() + p.loop_closure_linear_window_m;
                (at, search(lin, std::f64::consts::PI, p.loop_closure_global_min_score))
            }
            Kind::Confirm(id) => {
                let h = self.loops.hypotheses.iter().find(|h| h.id == id)?;
                let guess = h.correction.compose(gn);
                (
                    sm.local_pose.compose(gs.inverse().compose(guess)),
                    search(
                        p.loop_closure_confirm_linear_window_m,
                        p.loop_closure_confirm_angular_window_rad,
                        p.loop_closure_min_score,
                    ),
                )
            }
        };
        initial.is_finite().then_some(Planned { pair, initial, search, base })
    }
}

#[cfg(test)]
impl Slam {
    /// `count` copies of finished submap `of`, finished, where it lies: a robot that stayed
    /// in one room for days, for tests of what a search over very many submaps costs.
    pub(in crate::slam) fn copy_finished_submap(&mut self, of: usize, count: usize) {
        for _ in 0..count {
            let s = self.submaps.push_copy_of_finished(of);
            let at = self.graph.nodes()[self.submap_graph[of]];
            self.submap_graph.push(self.graph.add_node(at));
            self.finished.push(true);
            self.grids.add_submap();
            self.loops.footprints.push(self.loops.footprints[of]);
            let c = self.submap_centre(s);
            self.loops.submap_index.insert(s, c);
        }
    }
}
