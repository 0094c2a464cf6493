//! A new scan node's edges in the pose graph: to the submaps it went into (its match's
//! information) and to the node before (the track's motion, where it agrees with the
//! matches).

use super::mapper::{information_diag, Slam};
use super::pose_graph::{Edge, EdgeKind, Loss};
use crate::geometry::Pose2;

/// The information floor of a match edge, σ: enough to keep the graph solvable where a
/// match says nothing (along a corridor), and far below the odometry's, so that there the
/// odometry and the fixes place the node, not the submap it went into. (A floor of 0.5 m
/// counted the odometry twice along a corridor: each submap stiffened the odometry's
/// scale error over its length.)
const FLOOR_M: f64 = 10.0;
const FLOOR_DEG: f64 = 30.0;

impl Slam {
    /// Ties node `g` at `local` to the submaps `into` it went into.
    pub(super) fn add_match_edges(
        &mut self,
        g: usize,
        local: Pose2,
        into: &[usize],
        information: Option<[[f64; 3]; 3]>,
    ) {
        // Every node is tied to the submaps it went into by its match's information, a
        // submap's first node too: tied rigidly, it carried the odometry's stretch along a
        // corridor (where the match says nothing) into the whole submap (a 27 cm error at
        // each submap's start on the corridor of `fixes_tests.rs`, 11 cm without). Only a
        // first node that was not matched (the run's first) defines its submap's frame: its
        // heading stiffly (a turn on the spot has nothing else to hold the submap's
        // rotation), its position to 5 cm.
        let info = self.match_information(information);
        for &s in into {
            let sm = &self.submaps.all()[s];
            let defines = sm.scans == 1 && information.is_none();
            let e = Edge {
                from: self.submap_graph[s],
                to: g,
                measurement: sm.local_pose.inverse().compose(local),
                information: if defines { information_diag(0.05, 0.01f64.to_radians()) } else { info },
                loss: Loss::Trivial,
                kind: EdgeKind::Match,
            };
            // A match far out (a pose from nowhere) can give a non-finite curvature or
            // measurement: that edge is left out and counted, never a panic.
            if self.graph.add_edge(e).is_err() {
                self.report.edges_refused += 1;
            }
        }
    }

    /// Ties node `g` at `local` to the node before by the track's motion `track` between
    /// them, unless that disagrees with the matched motion.
    pub(super) fn add_odometry_edge(&mut self, g: usize, local: Pose2, track: Option<Pose2>) {
        if let Some((prev, before, now)) = self.nodes.last().and_then(|p| Some((p, p.track?, track?))) {
            let d = before.inverse().compose(now);
            let (st, sr) = self.odometry.sigmas(&self.p, d);
            // Odometry that disagrees with the matched motion by more than 5 σ (a jump, a
            // stall, a slip) is left out of the graph and counted, not averaged in.
            let m = prev.local.inverse().compose(local);
            // The test is never tighter than the configured model: learnt-stiff odometry
            // still agrees with the matches only to their own noise.
            let consistent = self.odometry.plausible(&self.p, d, m, 5.0);
            if !consistent {
                self.report.odometry_edges_rejected += 1;
            }
            let e = Edge {
                from: prev.graph,
                to: g,
                measurement: d,
                information: information_diag(st, sr),
                loss: Loss::Trivial,
                kind: EdgeKind::Odometry,
            };
            if d.is_finite() && consistent && self.graph.add_edge(e).is_err() {
                self.report.edges_refused += 1;
            }
        }
    }

    /// The information of a scan's local pose as a graph edge: the match's own (positive
    /// semi-definite, from its curvature) plus a floor — an unmatched or degenerate
    /// direction is as good as the odometry, not infinitely bad — and scaled down as a
    /// whole if it claims more than a few millimetres, which stays positive definite.
    pub(super) fn match_information(&self, info: Option<[[f64; 3]; 3]>) -> [[f64; 3]; 3] {
        let floor = information_diag(FLOOR_M, FLOOR_DEG.to_radians());
        let cap = information_diag(0.005, 0.05f64.to_radians());
        let mut out = info.unwrap_or([[0.0; 3]; 3]);
        for (i, f) in floor.iter().enumerate() {
            out[i][i] += f[i];
        }
        for (i, j) in [(1, 0), (2, 0), (2, 1)] {
            let v = 0.5 * (out[i][j] + out[j][i]);
            (out[i][j], out[j][i]) = (v, v);
        }
        let over = (0..3).map(|i| out[i][i] / cap[i][i]).fold(1.0, f64::max);
        out.iter_mut().flatten().for_each(|v| *v /= over);
        out
    }
}
