//! How far the estimate may have drifted between a node and a submap, and the search
//! windows that follow from it.

use super::index::Ordered;
use crate::geometry::Point2;
use crate::slam::mapper::Slam;

impl Slam {
    /// The travel since the last accepted closure of a loop longer than
    /// `loop_closure_global_after_m`, metres.
    pub(super) fn since_closure_m(&self) -> f64 {
        self.nodes.last().map_or(0.0, |n| n.path_m - self.loops.closed_at_m)
    }

    /// The drift between node `n` and submap `s`: how far one must travel from either to
    /// now through the graph (closures are shortcuts), added.
    pub(super) fn drift(&self, n: usize, s: usize) -> f64 {
        let now = self.nodes.last().map_or(0.0, |l| l.path_m);
        let since = now - self.loops.drift_at_m;
        let of_submap = |s: usize| match self.loops.drift.get(s) {
            Some(d) => d + since,
            None => now - self.loops.footprints[s].first_path_m,
        };
        let of_node = self.nodes[n].submaps.iter().map(|&a| of_submap(a)).fold(f64::INFINITY, f64::min);
        let of_node = if of_node.is_finite() { of_node } else { now - self.nodes[n].path_m };
        of_node + of_submap(s)
    }

    /// Every submap's distance from the newest one through the graph: travel along the
    /// trajectory between consecutive submaps, nothing across an accepted loop closure
    /// (Dijkstra). The windows of later searches grow with it.
    pub(in crate::slam) fn update_drift(&mut self) {
        let n = self.loops.footprints.len();
        let Some(last) = self.nodes.last() else { return };
        let mut adjacent: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for i in 1..n {
            let (a, b) = (&self.loops.footprints[i - 1], &self.loops.footprints[i]);
            let cost = (b.first_path_m - a.first_path_m).abs();
            adjacent[i - 1].push((i, cost));
            adjacent[i].push((i - 1, cost));
        }
        for &(a, b) in &self.loops.links {
            adjacent[a].push((b, 0.0));
            adjacent[b].push((a, 0.0));
        }
        let mut dist = vec![f64::INFINITY; n];
        let mut heap = std::collections::BinaryHeap::new();
        if let Some(&start) = last.submaps.last() {
            dist[start] = last.path_m - self.loops.footprints[start].first_path_m;
            heap.push(std::cmp::Reverse((Ordered(dist[start]), start)));
        }
        while let Some(std::cmp::Reverse((Ordered(d), i))) = heap.pop() {
            if d > dist[i] {
                continue;
            }
            for &(j, c) in &adjacent[i] {
                if d + c < dist[j] {
                    dist[j] = d + c;
                    heap.push(std::cmp::Reverse((Ordered(d + c), j)));
                }
            }
        }
        self.loops.drift = dist;
        self.loops.drift_at_m = last.path_m;
    }

    /// The window `(linear, angular)` of a search of node `n` in submap `s`, widened for the
    /// drift between them.
    pub(super) fn window(&self, n: usize, s: usize) -> (f64, f64) {
        let d = self.drift(n, s);
        let p = &self.p;
        let lin = (p.loop_closure_linear_window_m + p.loop_closure_window_growth * d)
            .min(p.loop_closure_max_linear_window_m.max(p.loop_closure_linear_window_m));
        let ang =
            (p.loop_closure_angular_window_rad + p.loop_closure_angular_growth_rad_per_m * d).min(std::f64::consts::PI);
        (lin, ang)
    }

    /// How far from node `n` a submap's centre may lie and still be searched: the base
    /// distance, plus what the window of `s` adds.
    pub(super) fn reach(&self, n: usize, s: usize) -> f64 {
        self.p.loop_closure_max_distance_m + (self.window(n, s).0 - self.p.loop_closure_linear_window_m)
    }

    /// The farthest any submap may lie from node `n` and be searched.
    pub(super) fn max_reach(&self) -> f64 {
        self.p.loop_closure_max_distance_m
            + (self.p.loop_closure_max_linear_window_m - self.p.loop_closure_linear_window_m).max(0.0)
    }

    /// A finished submap's centre in the graph's current estimate.
    pub(super) fn submap_centre(&self, s: usize) -> Point2 {
        let g = self.graph.nodes()[self.submap_graph[s]];
        g.transform_point(self.loops.footprints[s].centre())
    }

    pub(super) fn node_position(&self, n: usize) -> Point2 {
        self.graph.nodes()[self.nodes[n].graph].translation()
    }
}
