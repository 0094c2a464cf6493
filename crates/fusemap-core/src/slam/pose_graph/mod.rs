//! A sparse 2D pose graph and its Levenberg–Marquardt optimiser.
//!
//! Graph-based SLAM (Grisetti et al. 2010, "A tutorial on graph-based SLAM") keeps one pose
//! per node and turns every relative measurement between two nodes into a soft constraint.
//! The optimiser looks for the poses `x` minimising
//!
//! ```text
//! F(x) = Σ_edges ½ ρ(r_ijᵀ Ω_ij r_ij) + Σ_priors ½ ρ(r_kᵀ Ω_k r_k)
//! ```
//!
//! where `r_ij` is the edge residual, `Ω_ij` its information matrix (inverse covariance) and
//! `ρ` a robust loss that keeps a wrong loop closure from dragging the whole map (Hess et
//! al. 2016, "Real-Time Loop Closure in 2D LIDAR SLAM", §V use Huber for the same reason).
//!
//! The edge residual is expressed in the frame of the `from` node, the form Hess et al. use:
//!
//! ```text
//! r = [ R(θ_from)ᵀ (t_to − t_from) − t_z ;  wrap(θ_to − θ_from − θ_z) ]
//! ```
//!
//! It is not the exact SE(2) log of `z⁻¹ ∘ from⁻¹ ∘ to`, but it vanishes exactly when the
//! measurement is met and its Jacobians are short closed forms, which keeps the per-edge
//! linearisation cheap on graphs of 10⁵ edges.
//!
//! The private `solver` module does the work: Gauss–Newton normal equations
//! `JᵀWJ δ = −JᵀWr` with Marquardt damping, a sparse Cholesky (faer) on a block fill-reducing
//! ordering, and the symbolic factorisation kept while the graph's structure does not change.
//!
//! ```
//! use fusemap_core::geometry::Pose2;
//! use fusemap_core::slam::pose_graph::*;
//! let mut graph = PoseGraph::new();
//! let a = graph.add_node(Pose2::IDENTITY);
//! let b = graph.add_node(Pose2::new(0.8, 0.3, 0.1)); // a poor initial guess
//! let information = [[100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [0.0, 0.0, 400.0]];
//! let measurement = Pose2::new(1.0, 0.0, 0.0); // b is 1 m ahead of a
//! graph.add_edge(Edge { from: a, to: b, measurement, information, loss: Loss::Trivial, kind: EdgeKind::Odometry }).unwrap();
//! let report = graph.optimize(&OptimizeOptions::default()).unwrap();
//! assert!(report.converged && report.final_cost < 1e-12);
//! assert!((graph.nodes()[b].x - 1.0).abs() < 1e-6); // node a holds the gauge
//! ```

mod solver;
#[cfg(test)]
mod tests;

use crate::geometry::{normalize_angle, Point2, Pose2};
use serde::Serialize;

/// A robust loss `ρ(s)` applied to the squared whitened residual `s = rᵀ Ω r`.
///
/// Scales are in whitened units (standard deviations): `Huber(1.0)` treats residuals beyond
/// 1 σ as outliers whose influence grows only linearly.  The optimiser uses iteratively
/// re-weighted least squares: each residual is weighted by `ρ'(s)` at the linearisation
/// point (Triggs et al. 2000, "Bundle adjustment — a modern synthesis", §6.8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Loss {
    /// Plain least squares: `ρ(s) = s`.
    Trivial,
    /// Huber with threshold `δ` σ: quadratic inside, linear outside (`ρ(s) = 2δ√s − δ²`).
    Huber(f64),
    /// Cauchy (Lorentzian) with scale `c` σ: `ρ(s) = c² ln(1 + s/c²)`; outliers' influence
    /// decays towards zero, stronger than Huber against gross mistakes.
    Cauchy(f64),
    /// Dynamic covariance scaling with parameter `Φ` (Agarwal et al. 2013, "Robust map
    /// optimization using dynamic covariance scaling"): the closed form of switchable
    /// constraints (Sünderhauf & Protzel 2012), each edge's information scaled by
    /// `s² = min(1, 2Φ / (Φ + χ²))²`. Quadratic up to `χ² = Φ`, then
    /// `ρ(s) = 3Φ − 4Φ² / (Φ + s)`, bounded: an edge far off the rest of the graph stops
    /// pulling at all, where Huber's pull stays constant.
    Dcs(f64),
}

impl Loss {
    /// `ρ(s)` and `ρ'(s)` for a squared whitened residual `s ≥ 0`.
    pub fn evaluate(self, s: f64) -> (f64, f64) {
        match self {
            Loss::Trivial => (s, 1.0),
            Loss::Huber(delta) => {
                let d2 = delta * delta;
                if s <= d2 {
                    (s, 1.0)
                } else {
                    let r = s.sqrt();
                    (2.0 * delta * r - d2, delta / r)
                }
            }
            Loss::Cauchy(c) => {
                let c2 = c * c;
                let q = 1.0 + s / c2;
                (c2 * q.ln(), 1.0 / q)
            }
            Loss::Dcs(phi) => {
                if s <= phi {
                    (s, 1.0)
                } else {
                    let k = 2.0 * phi / (phi + s);
                    (3.0 * phi - 4.0 * phi * phi / (phi + s), k * k)
                }
            }
        }
    }

    fn is_valid(self) -> bool {
        match self {
            Loss::Trivial => true,
            Loss::Huber(k) | Loss::Cauchy(k) | Loss::Dcs(k) => k.is_finite() && k > 0.0,
        }
    }
}

/// Where an edge came from; carried through for reports and for filtering by callers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum EdgeKind {
    /// Consecutive poses from wheel/IMU odometry.
    Odometry,
    /// A scan-to-scan or scan-to-submap match between nearby nodes.
    Match,
    /// A match closing a loop to a node visited long ago.
    LoopClosure,
}

/// A relative-pose constraint between two nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// Index of the node whose frame the measurement is expressed in.
    pub from: usize,
    /// Index of the measured node.
    pub to: usize,
    /// Relative pose of `to` in the frame of `from`, i.e. the measured `from⁻¹ ∘ to`.
    pub measurement: Pose2,
    /// Information matrix (inverse covariance) of the residual `[x, y, θ]`, in the `from`
    /// frame; symmetric positive semi-definite.
    pub information: [[f64; 3]; 3],
    /// Robust loss applied to this edge.
    pub loss: Loss,
    /// Provenance, for reports.
    pub kind: EdgeKind,
}

/// An absolute position measurement of a point rigidly attached to a node (a GNSS antenna).
///
/// The residual is `node.transform_point(lever_arm) − position`.  Priors anchor the graph in
/// their frame, so when any prior is present no node is fixed implicitly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionPrior {
    /// The constrained node.
    pub node: usize,
    /// Measured position of the antenna in the graph's world frame.
    pub position: Point2,
    /// Antenna position in the node's own frame.
    pub lever_arm: Point2,
    /// Information matrix of the 2D residual; symmetric positive semi-definite.
    pub information: [[f64; 2]; 2],
    /// Robust loss applied to this prior.
    pub loss: Loss,
}

/// Stopping rules and damping of [`PoseGraph::optimize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizeOptions {
    /// Linear solves at most (accepted and rejected steps alike).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction of it.
    pub function_tolerance: f64,
    /// Stop when the largest gradient component is at most this.
    pub gradient_tolerance: f64,
    /// Stop when `‖δ‖ ≤ parameter_tolerance · (‖x‖ + parameter_tolerance)`.
    pub parameter_tolerance: f64,
    /// Starting Marquardt damping `λ` relative to the Hessian's diagonal; small values
    /// suit warm starts (Gauss–Newton-like first step), large ones poor initial guesses.
    pub initial_lambda: f64,
}

impl Default for OptimizeOptions {
    /// Tolerances in the spirit of common nonlinear least-squares defaults: a relative cost
    /// change of 1e-6 is far below what scan matching noise can resolve.
    fn default() -> Self {
        OptimizeOptions {
            max_iterations: 50,
            function_tolerance: 1e-6,
            gradient_tolerance: 1e-10,
            parameter_tolerance: 1e-8,
            initial_lambda: 1e-5,
        }
    }
}

/// What [`PoseGraph::optimize`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OptimizeReport {
    /// Linear solves performed (each is one LM iteration, accepted or not).
    pub iterations: usize,
    /// Steps that lowered the cost and were kept.
    pub accepted_steps: usize,
    /// Cost `F` before optimising.
    pub initial_cost: f64,
    /// Cost `F` after optimising.
    pub final_cost: f64,
    /// True when a tolerance was met (rather than the iteration limit or damping ceiling).
    pub converged: bool,
    /// True when the symbolic factorisation of the previous call was reused.
    pub reused_symbolic: bool,
}

/// Why a graph could not be built or optimised.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PoseGraphError {
    /// A node index beyond the graph.
    #[error("node {node} does not exist (the graph has {len} nodes)")]
    UnknownNode {
        /// The index given.
        node: usize,
        /// Number of nodes.
        len: usize,
    },
    /// An edge from a node to itself carries no information.
    #[error("edge from node {0} to itself")]
    SelfEdge(usize),
    /// NaN or infinity in a measurement, information matrix or loss scale.
    #[error("non-finite {0}")]
    NonFinite(&'static str),
    /// An information matrix that is not symmetric positive semi-definite.
    #[error("information matrix is not symmetric positive semi-definite")]
    BadInformation,
    /// A loss whose scale is not a positive finite number.
    #[error("loss scale must be positive and finite")]
    BadLoss,
    /// A node pose is NaN or infinite at the start of optimisation.
    #[error("node {0} has a non-finite pose")]
    NonFinitePose(usize),
    /// The damped normal equations could not be factorised even with heavy damping.
    #[error("the normal equations are singular")]
    Singular,
}

/// A 2D pose graph: nodes (poses), relative-pose edges and absolute position priors.
#[derive(Debug, Default)]
pub struct PoseGraph {
    nodes: Vec<Pose2>,
    fixed: Vec<bool>,
    edges: Vec<Edge>,
    priors: Vec<PositionPrior>,
    cache: Option<solver::Structure>,
}

impl PoseGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a node with its initial estimate and returns its index.
    pub fn add_node(&mut self, initial: Pose2) -> usize {
        self.nodes.push(initial);
        self.fixed.push(false);
        self.nodes.len() - 1
    }

    /// Holds a node at its current pose during optimisation (removes its columns from the
    /// normal equations).  The graph is only defined up to a rigid motion (the gauge
    /// freedom); when no node is fixed and there is no position prior, node 0 is held.
    ///
    /// # Panics
    /// When `node` is out of range.
    pub fn set_fixed(&mut self, node: usize, fixed: bool) {
        self.fixed[node] = fixed;
    }

    /// True when `node` was fixed with [`PoseGraph::set_fixed`].
    pub fn is_fixed(&self, node: usize) -> bool {
        self.fixed[node]
    }

    /// Adds a relative-pose constraint after checking indices, finiteness and that the
    /// information matrix is symmetric positive semi-definite; returns the edge index.
    pub fn add_edge(&mut self, e: Edge) -> Result<usize, PoseGraphError> {
        self.check_node(e.from)?;
        self.check_node(e.to)?;
        if e.from == e.to {
            return Err(PoseGraphError::SelfEdge(e.from));
        }
        if !e.measurement.is_finite() {
            return Err(PoseGraphError::NonFinite("measurement"));
        }
        check_information(&e.information)?;
        if !e.loss.is_valid() {
            return Err(PoseGraphError::BadLoss);
        }
        self.edges.push(e);
        Ok(self.edges.len() - 1)
    }

    /// Adds an absolute position constraint (see [`PositionPrior`]).
    pub fn add_position_prior(&mut self, p: PositionPrior) -> Result<(), PoseGraphError> {
        self.check_node(p.node)?;
        if !p.position.is_finite() || !p.lever_arm.is_finite() {
            return Err(PoseGraphError::NonFinite("prior position or lever arm"));
        }
        let [[a, b], [c, d]] = p.information;
        let mut info = [[0.0; 3]; 3];
        info[0][0] = a;
        info[0][1] = b;
        info[1][0] = c;
        info[1][1] = d;
        check_information(&info)?;
        if !p.loss.is_valid() {
            return Err(PoseGraphError::BadLoss);
        }
        self.priors.push(p);
        Ok(())
    }

    /// Current pose estimates, indexed by node.
    pub fn nodes(&self) -> &[Pose2] {
        &self.nodes
    }

    /// Overwrites a node's estimate, e.g. to seed a new node from its predecessor's
    /// optimised pose and the odometry increment before the next optimisation.
    ///
    /// # Panics
    /// When `i` is out of range.
    pub fn set_node(&mut self, i: usize, pose: Pose2) {
        self.nodes[i] = pose;
    }

    /// A copy of the graph to optimise elsewhere (another thread), which takes the
    /// solver's cached structure along: this graph will have grown by the time the copy
    /// comes back, see [`adopt`](Self::adopt).
    pub fn take_copy(&mut self) -> PoseGraph {
        PoseGraph {
            nodes: self.nodes.clone(),
            fixed: self.fixed.clone(),
            edges: self.edges.clone(),
            priors: self.priors.clone(),
            cache: self.cache.take(),
        }
    }

    /// Takes the poses of `optimised`, a copy made by [`take_copy`](Self::take_copy), for the
    /// nodes it has (nodes added since keep theirs), and its cached structure back.
    ///
    /// # Panics
    /// When `optimised` has more nodes than this graph.
    pub fn adopt(&mut self, optimised: PoseGraph) {
        self.nodes[..optimised.nodes.len()].copy_from_slice(&optimised.nodes);
        self.cache = optimised.cache;
    }

    /// The edges, in insertion order.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Gives every edge of `kind` the loss `loss` (a schedule of losses: Huber to bring
    /// closures in, then a redescending loss to let the wrong ones go).
    pub fn set_loss_of(&mut self, kind: EdgeKind, loss: Loss) -> Result<(), PoseGraphError> {
        if !loss.is_valid() {
            return Err(PoseGraphError::BadLoss);
        }
        self.edges.iter_mut().filter(|e| e.kind == kind).for_each(|e| e.loss = loss);
        Ok(())
    }

    /// The position priors, in insertion order.
    pub fn position_priors(&self) -> &[PositionPrior] {
        &self.priors
    }

    /// The residual `[x, y, θ]` of edge `i` at the current estimates (see the module docs).
    ///
    /// # Panics
    /// When `i` is out of range.
    pub fn edge_error(&self, i: usize) -> [f64; 3] {
        let e = &self.edges[i];
        edge_residual(&self.nodes[e.from], &self.nodes[e.to], &e.measurement)
    }

    /// The objective `F = Σ ½ ρ(rᵀΩr)` at the current estimates.
    pub fn cost(&self) -> f64 {
        solver::total_cost(self, &self.nodes)
    }

    /// Runs Levenberg–Marquardt from the current estimates and stores the result.
    ///
    /// Fails without touching the estimates when a pose is not finite, or when the damped
    /// normal equations cannot be factorised.
    pub fn optimize(&mut self, opts: &OptimizeOptions) -> Result<OptimizeReport, PoseGraphError> {
        if let Some(i) = self.nodes.iter().position(|p| !p.is_finite()) {
            return Err(PoseGraphError::NonFinitePose(i));
        }
        solver::optimize(self, opts)
    }

    fn check_node(&self, node: usize) -> Result<(), PoseGraphError> {
        if node < self.nodes.len() {
            Ok(())
        } else {
            Err(PoseGraphError::UnknownNode { node, len: self.nodes.len() })
        }
    }
}

/// The edge residual of the module docs for estimates `a` (from) and `b` (to).
fn edge_residual(a: &Pose2, b: &Pose2, z: &Pose2) -> [f64; 3] {
    let (s, c) = a.theta.sin_cos();
    let dx = b.x - a.x;
    let dy = b.y - a.y;
    [c * dx + s * dy - z.x, -s * dx + c * dy - z.y, normalize_angle(b.theta - a.theta - z.theta)]
}

/// Checks that `m` is finite, symmetric and positive semi-definite.
///
/// Positive semi-definiteness holds when every principal minor is non-negative (for
/// semi-definite matrices the leading minors alone do not suffice); a small negative slack
/// relative to the matrix's scale accepts round-off from covariance inversion.
fn check_information(m: &[[f64; 3]; 3]) -> Result<(), PoseGraphError> {
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(PoseGraphError::NonFinite("information matrix"));
    }
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    if [(0, 1), (0, 2), (1, 2)].iter().any(|&(i, j)| (m[i][j] - m[j][i]).abs() > tol) {
        return Err(PoseGraphError::BadInformation);
    }
    let minor2 = |i: usize, j: usize| m[i][i] * m[j][j] - m[i][j] * m[j][i];
    let det = m[0][0] * minor2(1, 2) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let ok = (0..3).all(|i| m[i][i] >= -tol)
        && [(0, 1), (0, 2), (1, 2)].iter().all(|&(i, j)| minor2(i, j) >= -tol * scale)
        && det >= -tol * scale * scale;
    if ok {
        Ok(())
    } else {
        Err(PoseGraphError::BadInformation)
    }
}
