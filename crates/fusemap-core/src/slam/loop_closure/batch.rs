//! Running a batch of searches on every core, and what becomes of each result: an edge,
//! a hypothesis waiting for confirmation, or an open search in the report.

use super::{
    Hypothesis, Kind, OpenReason, OpenSearch, Outcome, Pair, Planned, CONFIRM_SEPARATION_M, MAX_HYPOTHESES,
    MAX_OPEN_REPORTED,
};
use crate::geometry::{normalize_angle, Pose2};
use crate::parallel::map_all;
use crate::slam::global_match::{search_branch_and_bound, search_work, GlobalSearch};
use crate::slam::local_match::{match_information, mean_probability, refine, LocalMatchParams};
use crate::slam::mapper::Slam;
use crate::slam::pose_graph::{Edge, EdgeKind, Loss};
use std::time::Instant;

impl Slam {
    /// Runs the pending searches: grids first, then every search in parallel, then the
    /// results in the order of the pairs.
    pub(in crate::slam) fn run_loop_batch(&mut self) {
        self.loops.nodes_since_batch = 0;
        let t0 = Instant::now();
        if self.loops.drift_stale {
            self.update_drift();
            self.loops.drift_stale = false;
        }
        let (work, planned) = self.plan_batch();
        if planned.is_empty() {
            self.report.loop_search_s += t0.elapsed().as_secs_f64();
            return;
        }
        let mut needed: Vec<usize> = planned.iter().map(|p| p.pair.submap).collect();
        needed.sort_unstable();
        needed.dedup();
        let submaps = &self.submaps;
        self.grids.prepare(&needed, |s| submaps.finished_field(s));
        let (grids, nodes) = (&self.grids, &self.nodes);
        let local = LocalMatchParams { degeneracy_ratio: self.p.loop_closure_degeneracy_ratio, ..self.p.local };
        let local = &local;
        // The costliest searches start first, so the threads finish together; the results
        // are taken in the pairs' order whatever the order they ran in.
        let mut order: Vec<usize> = (0..planned.len()).collect();
        order.sort_by(|&a, &b| work[b].total_cmp(&work[a]).then(a.cmp(&b)));
        let mut ran: Vec<(usize, Outcome)> = map_all(&order, |&k| {
            let pl = &planned[k];
            let node = &nodes[pl.pair.node];
            let (field, pre) = grids.peek(pl.pair.submap).expect("prepared above");
            let out = search_branch_and_bound(pre, &node.search_points(), pl.initial, &pl.search);
            let found = out.found.map(|f| {
                let points = node.points();
                let pose = refine(field, &points, f.pose, f.pose, local);
                let score = mean_probability(field, &points, pose);
                (pose, score, match_information(field, &points, pose, local).1)
            });
            (k, Outcome { found, best_score: out.best_score, on_edge: out.on_edge })
        });
        ran.sort_unstable_by_key(|r| r.0);
        self.report.loop_searches += planned.len() as u64;
        for (pl, (_, out)) in planned.iter().zip(ran) {
            self.take_outcome(pl, out);
        }
        self.expire_hypotheses();
        self.report.loop_search_s += t0.elapsed().as_secs_f64();
    }

    /// The batch's searches, each with its work: the pending pairs and the global ones,
    /// planned; confirmations first, then local, then global, cheaper ones first within a
    /// kind, until the batch's work budget is spent (the first one always runs).
    fn plan_batch(&mut self) -> (Vec<f64>, Vec<Planned>) {
        let mut pairs = std::mem::take(&mut self.loops.pending);
        pairs.extend(self.global_pairs());
        // Confirmations first, then local, then global, within the budget.
        let rank = |k: &Kind| match k {
            Kind::Confirm(_) => 0,
            Kind::Local => 1,
            Kind::Global => 2,
        };
        // Within a kind, cheaper searches first; the batch takes searches until its work
        // budget is spent (the first one always runs).
        let mut planned: Vec<(usize, f64, Planned)> = pairs
            .into_iter()
            .filter_map(|p| self.plan(p))
            .map(|pl| {
                let points = self.nodes[pl.pair.node].search.len();
                let w = search_work(
                    &pl.search,
                    self.p.resolution,
                    self.p.loop_closure_max_range_m,
                    points,
                    pl.search.depth,
                );
                (rank(&pl.pair.kind), w, pl)
            })
            .collect();
        planned.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let budget = self.p.loop_closure_work_per_batch;
        let mut spent = 0.0;
        let total = planned.len();
        let (work, planned): (Vec<f64>, Vec<Planned>) = planned
            .into_iter()
            .take_while(|(_, w, _)| {
                let first = spent == 0.0;
                spent += w;
                first || spent <= budget
            })
            .map(|(_, w, pl)| (w, pl))
            .unzip();
        self.report.loop_over_budget += (total - planned.len()) as u64;
        (work, planned)
    }

    pub(super) fn record_open(&mut self, pl: &Planned, best_score: f32, reason: OpenReason, on_edge: bool) {
        self.report.loop_rejected += 1;
        match reason {
            OpenReason::Score => {}
            OpenReason::Degenerate => self.report.loop_degenerate += 1,
            OpenReason::Unconfirmed => self.report.loop_unconfirmed += 1,
            OpenReason::Disagrees => self.report.loop_disagreeing += 1,
        }
        if self.loops.open.len() < MAX_OPEN_REPORTED {
            let global = pl.pair.kind == Kind::Global;
            self.loops.open.push(OpenSearch {
                node: pl.pair.node,
                submap: pl.pair.submap,
                best_score,
                reason,
                on_edge,
                global,
            });
        }
    }

    /// Accepts, holds as a hypothesis, or records a search's result.
    pub(super) fn take_outcome(&mut self, pl: &Planned, out: Outcome) {
        let Some((pose, score, degenerate)) = out.found else {
            let reason =
                if matches!(pl.pair.kind, Kind::Confirm(_)) { OpenReason::Disagrees } else { OpenReason::Score };
            return self.record_open(pl, out.best_score, reason, out.on_edge);
        };
        let min = if pl.pair.kind == Kind::Global {
            self.p.loop_closure_global_min_score
        } else {
            self.p.loop_closure_min_score
        };
        if score < min {
            return self.record_open(pl, score, OpenReason::Score, out.on_edge);
        }
        // A closure along a corridor fits anywhere in the window: it would hold the node
        // wherever the search happened to stop, against the odometry and the fixes.
        if degenerate {
            return self.record_open(pl, score, OpenReason::Degenerate, out.on_edge);
        }
        let (s, n) = (pl.pair.submap, pl.pair.node);
        let sm = &self.submaps.all()[s];
        let edge = Edge {
            from: self.submap_graph[s],
            to: self.nodes[n].graph,
            measurement: sm.local_pose.inverse().compose(pose),
            information: crate::slam::mapper::information_diag(
                self.p.loop_closure_sigma_m,
                self.p.loop_closure_sigma_rad,
            ),
            loss: Loss::Huber(self.p.loop_closure_huber),
            kind: EdgeKind::LoopClosure,
        };
        let shift = pl.initial.inverse().compose(pose);
        let small = shift.x.hypot(shift.y) <= pl.base.0 && normalize_angle(shift.theta).abs() <= pl.base.1;
        match pl.pair.kind {
            Kind::Local if small => self.accept(edge, n, s),
            Kind::Confirm(id) => self.confirm_hypothesis(id, edge, (n, s), score),
            _ => self.hold_hypothesis(pl, edge, pose, score),
        }
    }

    /// A confirming search found the place hypothesis `id` predicted: the two close
    /// together (a hypothesis already dropped is left alone).
    fn confirm_hypothesis(&mut self, id: u64, edge: Edge, (n, s): (usize, usize), score: f32) {
        let Some(i) = self.loops.hypotheses.iter().position(|h| h.id == id) else { return };
        let h = self.loops.hypotheses.remove(i);
        let (correction, expires_m) = (h.correction, h.expires_m);
        let second = Hypothesis {
            id: u64::MAX,
            edge,
            node: n,
            submap: s,
            correction,
            expires_m,
            score,
            global: false,
            attempts: 0,
        };
        self.confirmed(h, second);
    }

    /// A match that moves the node too far to take alone: held as a hypothesis until another
    /// node's match agrees with it (then both close), or it expires.
    fn hold_hypothesis(&mut self, pl: &Planned, edge: Edge, pose: Pose2, score: f32) {
        let (s, n) = (pl.pair.submap, pl.pair.node);
        let sm = &self.submaps.all()[s];
        // Where the graph has the node now, and where the match puts it.
        let gs = self.graph.nodes()[self.submap_graph[s]];
        let gn = self.graph.nodes()[self.nodes[n].graph];
        let truth = gs.compose(sm.local_pose.inverse()).compose(pose);
        let correction = truth.compose(gn.inverse());
        self.report.loop_hypotheses += 1;

        if self.loops.hypotheses.len() >= MAX_HYPOTHESES {
            let old = self.loops.hypotheses.remove(0);
            self.open_hypothesis(&old);
        }
        let id = self.loops.next_id;
        self.loops.next_id += 1;
        let expires_m = self.nodes.last().map_or(0.0, |l| l.path_m) + self.p.loop_closure_confirm_within_m;
        let global = pl.pair.kind == Kind::Global;
        let h = Hypothesis { id, edge, node: n, submap: s, correction, expires_m, score, global, attempts: 0 };
        // Another hypothesis, from another node, that moves the trajectory the same
        // way confirms this one (and this one it).
        match self.loops.hypotheses.iter().position(|o| self.agree(o, &h)) {
            Some(i) => {
                let o = self.loops.hypotheses.remove(i);
                self.confirmed(o, h);
            }
            None => self.loops.hypotheses.push(h),
        }
    }

    /// True when hypotheses `a` and `b`, from nodes at least a metre apart, put `b`'s node
    /// at the same place within the confirming window.
    pub(super) fn agree(&self, a: &Hypothesis, b: &Hypothesis) -> bool {
        let apart = (self.nodes[a.node].path_m - self.nodes[b.node].path_m).abs() >= CONFIRM_SEPARATION_M;
        let gb = self.graph.nodes()[self.nodes[b.node].graph];
        let d = a.correction.compose(gb).inverse().compose(b.correction.compose(gb));
        apart
            && d.x.hypot(d.y) <= self.p.loop_closure_confirm_linear_window_m
            && normalize_angle(d.theta).abs() <= self.p.loop_closure_confirm_angular_window_rad
    }

    /// Two agreeing matches: both become edges, and the graph is optimised before the next
    /// batch (the correction is large).
    pub(super) fn confirmed(&mut self, first: Hypothesis, second: Hypothesis) {
        self.report.loop_confirmed += 1;
        if first.global || second.global {
            self.report.loop_global_accepted += 1;
        }
        self.accept(first.edge, first.node, first.submap);
        self.accept(second.edge, second.node, second.submap);
        // Other hypotheses for the same place are now moot or wrong.
        self.loops.hypotheses.retain(|o| o.submap.abs_diff(first.submap) > 1);
        self.loops.optimise_now = true;
    }

    pub(super) fn accept(&mut self, edge: Edge, node: usize, submap: usize) {
        if self.graph.add_edge(edge).is_err() {
            self.report.edges_refused += 1;
            return;
        }
        self.report.loop_accepted += 1;
        self.loops.since_optimisation += 1;
        let gap = self.drift(node, submap);
        for &a in &self.nodes[node].submaps {
            self.loops.links.push((a, submap));
            *self.loops.link_count.entry((a.min(submap), a.max(submap))).or_default() += 1;
        }
        let now = self.nodes.last().map_or(0.0, |l| l.path_m);
        let (path, fp) = (self.nodes[node].path_m, &self.loops.footprints[submap]);
        let left_behind = path - fp.last_path_m;
        // The travel to the submap's nearest scan (an older node matched into a submap just
        // finished is as much a loop).
        let span = if path >= fp.first_path_m { left_behind } else { fp.first_path_m - path };
        self.report.longest_loop_m = self.report.longest_loop_m.max(span.max(0.0));
        // A loop closed by the newest stretch, with a submap left behind long ago (not a
        // neighbour along the path): the estimate is anchored, the global search rests.
        // The graph distance (`gap`) is no test: once a building's loops are tied it is
        // short everywhere, and the global search would run all the time.
        if left_behind >= self.p.loop_closure_max_distance_m
            && now - self.nodes[node].path_m <= self.p.loop_closure_confirm_within_m
        {
            self.loops.closed_at_m = now;
        }
        if gap > self.p.loop_closure_global_after_m {
            self.loops.drift_stale = true;
        }
    }

    pub(super) fn open_hypothesis(&mut self, h: &Hypothesis) {
        let pl = Planned {
            pair: Pair { node: h.node, submap: h.submap, kind: if h.global { Kind::Global } else { Kind::Local } },
            initial: Pose2::IDENTITY,
            search: GlobalSearch { linear_window_m: 0.0, angular_window_rad: 0.0, min_score: 0.0, depth: 1 },
            base: (0.0, 0.0),
        };
        self.record_open(&pl, h.score, OpenReason::Unconfirmed, false);
    }

    /// Drops the hypotheses no node confirmed in time.
    pub(in crate::slam) fn expire_hypotheses(&mut self) {
        let now = self.nodes.last().map_or(0.0, |n| n.path_m);
        let (gone, kept): (Vec<Hypothesis>, Vec<Hypothesis>) =
            self.loops.hypotheses.drain(..).partition(|h| h.expires_m < now);
        self.loops.hypotheses = kept;
        for h in &gone {
            self.open_hypothesis(h);
        }
    }

    /// Ends the run's searching: the last batch, and every hypothesis left unconfirmed.
    pub(in crate::slam) fn finish_loops(&mut self) {
        if !self.p.loop_closure {
            return;
        }
        self.run_loop_batch();
        for h in std::mem::take(&mut self.loops.hypotheses) {
            self.open_hypothesis(&h);
        }
    }
}
