//! GNSS fixes as position priors on the pose graph's nodes.
//!
//! Scan matching and loop closures fix the map's shape; they cannot fix where it lies on
//! the Earth, nor the drift along a corridor where no scan constrains the motion. A fix
//! can: it enters the graph as an absolute position of the antenna on the node nearest in
//! time (Kümmerle et al. 2011, g2o's `EdgeXYPrior`; Cartographer's fixed-frame pose
//! data), with the antenna's lever arm and the motion between the fix's stamp and the
//! node's taken from the pose track. The track is the estimator's, so the graph's frame is
//! the fixes' (the local ENU frame) from its first node on.
//!
//! A fix is gated against the track before it goes in: the estimator already refused the
//! fixes that disagree with everything else (multipath, a jump), and its smoothed track is
//! what the fix is tested against, with both covariances (χ², 2 degrees of freedom,
//! 99.9 %). The ones that pass still enter under a Huber loss, and, as in the estimator,
//! with their covariance scaled by `correlation_time / interval` (at least 1): ten fixes a
//! second whose error lasts ten seconds carry the weight of one fix per ten seconds.

use super::params::SlamParams;
use super::pose_graph::{Loss, PoseGraph, PositionPrior};
use super::report::SlamReport;
use crate::geometry::{Point2, Pose2};
use crate::time::Stamp;

/// χ² quantile, 2 degrees of freedom, probability 0.999: `−2 ln(0.001)`.
const GATE_CHI2: f64 = 13.815510557964274;

/// A GNSS antenna position, in the pose track's map frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionFix {
    /// The fix's stamp.
    pub stamp: Stamp,
    /// The antenna's position, metres.
    pub position: Point2,
    /// Its covariance, m² (floored per fix quality by the caller).
    pub covariance: [[f64; 2]; 2],
    /// The antenna in the base frame.
    pub antenna: Point2,
    /// Correlation time of the fix's error, seconds: fixes closer together than this are
    /// not independent, and share the weight of one (the estimator's rule, design
    /// document §2.4). 0 for independent fixes (RTK fixed).
    pub correlation_time_s: f64,
    /// The track's `map_from_base` at the fix's stamp and its covariance (x, y, θ; zero
    /// when the track has none): the motion from the node to the fix comes from it, and
    /// the fix is gated against it. `None` inside a gap of the track: the fix is not used.
    pub track: Option<(Pose2, [[f64; 3]; 3])>,
}

/// A node a fix can be attached to.
#[derive(Clone, Copy, Debug)]
pub(super) struct FixNode {
    pub stamp: Stamp,
    pub track: Option<Pose2>,
    pub graph: usize,
}

fn inverse2(m: [[f64; 2]; 2]) -> Option<[[f64; 2]; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    (det.is_finite() && det > 0.0 && m[0][0] > 0.0)
        .then(|| [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]])
}

/// The covariance of `pose.transform_point(antenna)` from the pose's (first order:
/// `J Σ Jᵀ` with `J = [I₂ | ∂R(θ)a/∂θ]`).
fn antenna_covariance(pose: Pose2, cov: [[f64; 3]; 3], antenna: Point2) -> [[f64; 2]; 2] {
    let (s, c) = pose.theta.sin_cos();
    let j = [[1.0, 0.0, -s * antenna.x - c * antenna.y], [0.0, 1.0, c * antenna.x - s * antenna.y]];
    let mut out = [[0.0; 2]; 2];
    for (r, row) in out.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|a| (0..3).map(|b| j[r][a] * cov[a][b] * j[k][b]).sum::<f64>()).sum();
        }
    }
    out
}

fn add2(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    [[a[0][0] + b[0][0], a[0][1] + b[0][1]], [a[1][0] + b[1][0], a[1][1] + b[1][1]]]
}

/// The fixes of a run, attached to nodes as the nodes are made.
pub(super) struct FixPriors {
    fixes: Vec<PositionFix>,
    next: usize,
    last_stamp: Option<Stamp>,
    lo: Point2,
    hi: Point2,
    max_sigma: f64,
    pub since_optimisation: usize,
}

impl FixPriors {
    pub fn new() -> Self {
        Self {
            fixes: Vec::new(),
            next: 0,
            last_stamp: None,
            lo: Point2::new(f64::INFINITY, f64::INFINITY),
            hi: Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            max_sigma: 0.0,
            since_optimisation: 0,
        }
    }

    /// Queues `fixes` (any order) after those not yet attached.
    pub fn add(&mut self, fixes: &[PositionFix], report: &mut SlamReport) {
        report.fixes += fixes.len() as u64;
        self.fixes.drain(..self.next);
        self.next = 0;
        self.fixes.extend_from_slice(fixes);
        self.fixes.sort_by_key(|f| f.stamp);
    }

    /// Attaches every queued fix stamped at or before `upto` to whichever of `before` and
    /// `after` is nearer in time, if that node is within `fix_max_offset_s` and both have
    /// a track pose. `in_track_frame` is false when the graph's first node had no track
    /// pose: the graph is then not in the fixes' frame, and none is used.
    #[allow(clippy::too_many_arguments)]
    pub fn attach(
        &mut self,
        upto: Stamp,
        before: Option<FixNode>,
        after: Option<FixNode>,
        in_track_frame: bool,
        graph: &mut PoseGraph,
        p: &SlamParams,
        report: &mut SlamReport,
    ) {
        let max_offset = p.fix_max_offset_s;
        while let Some(f) = self.fixes.get(self.next).copied().filter(|f| f.stamp <= upto) {
            self.next += 1;
            let interval = self.last_stamp.map_or(f64::INFINITY, |l| (f.stamp.0 - l.0) as f64 * 1e-9);
            self.last_stamp = Some(f.stamp);
            let k =
                if interval > 0.0 { (f.correlation_time_s / interval).max(1.0) } else { f.correlation_time_s.max(1.0) };
            let offset = |n: &FixNode| (f.stamp.0 - n.stamp.0).unsigned_abs() as f64 * 1e-9;
            let node = [before, after].into_iter().flatten().min_by(|a, b| offset(a).total_cmp(&offset(b)));
            let placed = node.filter(|n| in_track_frame && offset(n) <= max_offset).and_then(|n| {
                let (at_fix, track_cov) = f.track?;
                Some((n.graph, n.track?.inverse().compose(at_fix), at_fix, track_cov))
            });
            let Some((node, motion, at_fix, track_cov)) = placed else {
                report.fixes_unplaced += 1;
                continue;
            };
            let track_cov = antenna_covariance(at_fix, track_cov, f.antenna);
            let weighted =
                [[f.covariance[0][0] * k, f.covariance[0][1] * k], [f.covariance[1][0] * k, f.covariance[1][1] * k]];
            let (Some(information), Some(gate)) = (inverse2(weighted), inverse2(add2(f.covariance, track_cov))) else {
                report.fixes_unplaced += 1;
                continue;
            };
            let expected = at_fix.transform_point(f.antenna);
            let r = [f.position.x - expected.x, f.position.y - expected.y];
            let d2 = (0..2).map(|i| (0..2).map(|j| r[i] * gate[i][j] * r[j]).sum::<f64>()).sum::<f64>();
            // NaN (a non-finite fix) fails the gate too.
            if d2.is_nan() || d2 > GATE_CHI2 {
                report.fixes_gated += 1;
                continue;
            }
            let prior = PositionPrior {
                node,
                position: f.position,
                // The antenna at the fix's stamp, in the node's frame.
                lever_arm: motion.transform_point(f.antenna),
                information,
                loss: Loss::Huber(p.fix_huber),
            };
            if graph.add_position_prior(prior).is_err() {
                report.fixes_unplaced += 1;
                continue;
            }
            report.fix_priors += 1;
            self.since_optimisation += 1;
            self.lo = Point2::new(self.lo.x.min(f.position.x), self.lo.y.min(f.position.y));
            self.hi = Point2::new(self.hi.x.max(f.position.x), self.hi.y.max(f.position.y));
            self.max_sigma = self.max_sigma.max(f.covariance[0][0].max(f.covariance[1][1]).sqrt());
        }
    }

    /// Fixes queued and not yet attached (nor gated, nor counted as unplaced).
    pub fn pending(&self) -> usize {
        self.fixes.len() - self.next
    }

    /// True once the attached fixes span at least ten times their largest σ: they then
    /// hold the graph's heading as well as its position, and its first node need not be
    /// held where the track put it.
    pub fn anchor_the_graph(&self) -> bool {
        let span = (self.hi.x - self.lo.x).hypot(self.hi.y - self.lo.y);
        span.is_finite() && span >= 10.0 * self.max_sigma
    }
}

#[cfg(test)]
#[path = "fixes_tests.rs"]
mod tests;
