//! Levenberg–Marquardt on the sparse normal equations of a [`PoseGraph`].
//!
//! Each iteration linearises every residual, accumulates `H = Σ Jᵀ W J` and `g = Σ Jᵀ W r`
//! (Grisetti et al. 2010, §IV, eq. 20–21) with the robust weight `W = ρ'(rᵀΩr) Ω` (IRLS),
//! solves `(H + λ D) δ = −g` with `D = diag(H)` (Marquardt's scaling, clamped away from 0
//! and ∞) by a sparse Cholesky factorisation, and keeps the step when the true cost falls.
//! `λ` follows Nielsen's gain-ratio rule (Madsen, Nielsen & Tingleff 2004, "Methods for
//! non-linear least squares problems", §3.2).
//!
//! The upper triangle of `H` is stored in compressed columns with 3×3 node blocks.  The
//! layout, a fill-reducing ordering and the symbolic factorisation depend only on which
//! nodes are free and which pairs share an edge, so they are built once per structure and
//! reused while only the numbers change: warm-started re-optimisations after new estimates
//! pay only for the numeric factorisation.  The ordering is approximate minimum degree
//! (Amestoy, Davis & Duff 1996) on the node graph, expanded to 3×3 blocks: nine times fewer
//! entries to order than the scalar matrix, and each pose's three unknowns stay together,
//! which favours dense supernodes.

use super::{edge_residual, OptimizeOptions, OptimizeReport, PoseGraph, PoseGraphError, PositionPrior};
use crate::geometry::{normalize_angle, Pose2};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// Marker for a node held fixed (no columns in the normal equations).
const FIXED: usize = usize::MAX;
/// Clamp of Marquardt's diagonal scaling, so that an unobserved direction still gets damped.
const MIN_DIAGONAL: f64 = 1e-6;
const MAX_DIAGONAL: f64 = 1e32;
/// Damping beyond which no step can make progress.
const MAX_LAMBDA: f64 = 1e32;
/// Damping floor: below it the step is Gauss–Newton's to machine precision anyway.
const MIN_LAMBDA: f64 = 1e-15;

type Mat3 = [[f64; 3]; 3];

/// The sparsity layout and symbolic factorisation for one graph structure.
pub(super) struct Structure {
    /// Number of edges when built; edges are only ever appended.
    n_edges: usize,
    /// Per node: its block column, or [`FIXED`].
    free: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Per free node: position of its diagonal block's first row in each of its 3 columns.
    diag: Vec<[usize; 3]>,
    /// Per edge: position of the off-diagonal block's first row in each of its 3 columns
    /// (block row = smaller free index), or [`FIXED`] when an end is fixed.
    off: Vec<[usize; 3]>,
    symbolic: SymbolicCholesky<usize>,
    /// Workspace of the numeric factorisation and solve.
    mem: MemBuffer,
    /// Values of the Cholesky factor, kept so repeated calls do not page in fresh memory.
    factor: Vec<f64>,
}

impl std::fmt::Debug for Structure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Structure")
            .field("n_edges", &self.n_edges)
            .field("n_free", &self.diag.len())
            .field("nnz", &self.row_idx.len())
            .field("factor_len", &self.symbolic.len_val())
            .finish()
    }
}

impl Structure {
    fn build(graph: &PoseGraph, free: Vec<usize>, n_free: usize) -> Result<Self, PoseGraphError> {
        // Block rows above the diagonal of each block column.
        let mut above: Vec<Vec<usize>> = vec![Vec::new(); n_free];
        for e in &graph.edges {
            let (a, b) = (free[e.from], free[e.to]);
            if a != FIXED && b != FIXED {
                above[a.max(b)].push(a.min(b));
            }
        }
        for rows in &mut above {
            rows.sort_unstable();
            rows.dedup();
        }
        let n = 3 * n_free;
        let n_blocks: usize = above.iter().map(Vec::len).sum();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(9 * n_blocks + 6 * n_free);
        let mut diag = Vec::with_capacity(n_free);
        col_ptr.push(0);
        for (j, rows) in above.iter().enumerate() {
            let mut d = [0; 3];
            for (c, dc) in d.iter_mut().enumerate() {
                for &i in rows {
                    row_idx.extend([3 * i, 3 * i + 1, 3 * i + 2]);
                }
                *dc = row_idx.len();
                row_idx.extend((0..=c).map(|a| 3 * j + a));
                col_ptr.push(row_idx.len());
            }
            diag.push(d);
        }
        let off = graph
            .edges
            .iter()
            .map(|e| {
                let (a, b) = (free[e.from], free[e.to]);
                if a == FIXED || b == FIXED {
                    return [FIXED; 3];
                }
                let (i, j) = (a.min(b), a.max(b));
                let k = above[j].binary_search(&i).expect("block recorded above");
                [0, 1, 2].map(|c| col_ptr[3 * j + c] + 3 * k)
            })
            .collect();

        // Approximate minimum degree on the node graph, expanded to scalar unknowns.
        let mut bcol = Vec::with_capacity(n_free + 1);
        let mut brow = Vec::with_capacity(n_blocks + n_free);
        bcol.push(0);
        for (j, rows) in above.iter().enumerate() {
            brow.extend_from_slice(rows);
            brow.push(j);
            bcol.push(brow.len());
        }
        let bpattern = SymbolicSparseColMatRef::new_checked(n_free, n_free, &bcol, None, &brow);
        let mut bperm = vec![0usize; n_free];
        let mut bperm_inv = vec![0usize; n_free];
        let mut amd_mem = MemBuffer::new(amd::order_scratch::<usize>(n_free, brow.len()));
        amd::order(&mut bperm, &mut bperm_inv, bpattern, amd::Control::default(), MemStack::new(&mut amd_mem))
            .map_err(|_| PoseGraphError::Singular)?;
        let expand = |p: &[usize]| p.iter().flat_map(|&b| [3 * b, 3 * b + 1, 3 * b + 2]).collect::<Vec<_>>();
        let (perm, perm_inv) = (expand(&bperm), expand(&bperm_inv));

        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Upper,
            SymmetricOrdering::Custom(PermRef::new_checked(&perm, &perm_inv, n)),
            CholeskySymbolicParams::default(),
        )
        .map_err(|_| PoseGraphError::Singular)?;
        let mem = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        let factor = vec![0.0; symbolic.len_val()];
        Ok(Structure { n_edges: graph.edges.len(), free, col_ptr, row_idx, diag, off, symbolic, mem, factor })
    }
}

/// `F = Σ ½ ρ(rᵀΩr)` over edges and priors with the node poses `nodes`.
pub(super) fn total_cost(graph: &PoseGraph, nodes: &[Pose2]) -> f64 {
    let edges: f64 = graph
        .edges
        .iter()
        .map(|e| {
            let r = edge_residual(&nodes[e.from], &nodes[e.to], &e.measurement);
            e.loss.evaluate(quad3(&e.information, &r)).0
        })
        .sum();
    let priors: f64 = graph
        .priors
        .iter()
        .map(|p| {
            let (r, _) = prior_residual(p, &nodes[p.node]);
            p.loss.evaluate(quad2(&p.information, &r)).0
        })
        .sum();
    0.5 * (edges + priors)
}

fn quad3(m: &Mat3, r: &[f64; 3]) -> f64 {
    (0..3).map(|i| r[i] * (0..3).map(|j| m[i][j] * r[j]).sum::<f64>()).sum()
}

fn quad2(m: &[[f64; 2]; 2], r: &[f64; 2]) -> f64 {
    (0..2).map(|i| r[i] * (0..2).map(|j| m[i][j] * r[j]).sum::<f64>()).sum()
}

/// Residual `R(θ) l + t − p` of a position prior and its derivative with respect to θ.
fn prior_residual(p: &PositionPrior, x: &Pose2) -> ([f64; 2], [f64; 2]) {
    let (s, c) = x.theta.sin_cos();
    let (lx, ly) = (p.lever_arm.x, p.lever_arm.y);
    let r = [x.x + c * lx - s * ly - p.position.x, x.y + s * lx + c * ly - p.position.y];
    (r, [-s * lx - c * ly, c * lx - s * ly])
}

/// `Aᵀ B` for 3×3 matrices.
fn atb(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[k][i] * b[k][j]).sum();
        }
    }
    out
}

fn scaled_mul(w: f64, m: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = w * (0..3).map(|k| m[i][k] * b[k][j]).sum::<f64>();
        }
    }
    out
}

/// Adds the upper triangle of a diagonal block.
fn add_diag(h: &mut [f64], pos: &[usize; 3], m: &Mat3) {
    for (c, &p) in pos.iter().enumerate() {
        for a in 0..=c {
            h[p + a] += m[a][c];
        }
    }
}

/// Adds an off-diagonal block (rows of the smaller block index, columns of the larger).
fn add_off(h: &mut [f64], pos: &[usize; 3], m: &Mat3, transpose: bool) {
    for (c, &p) in pos.iter().enumerate() {
        for a in 0..3 {
            h[p + a] += if transpose { m[c][a] } else { m[a][c] };
        }
    }
}

/// Fills `h` (upper triangle of `JᵀWJ`) and `g` (`JᵀWr`) at `graph.nodes`; returns the cost.
fn linearize(graph: &PoseGraph, st: &Structure, h: &mut [f64], g: &mut [f64]) -> f64 {
    h.fill(0.0);
    g.fill(0.0);
    let mut cost = 0.0;
    let nodes = &graph.nodes;
    for (e, off) in graph.edges.iter().zip(&st.off) {
        let (a, b) = (&nodes[e.from], &nodes[e.to]);
        let (s, c) = a.theta.sin_cos();
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let r = edge_residual(a, b, &e.measurement);
        let (rho, w) = e.loss.evaluate(quad3(&e.information, &r));
        cost += 0.5 * rho;
        // ∂r/∂(x, y, θ) of the `from` and `to` poses.
        let ja = [[-c, -s, -s * dx + c * dy], [s, -c, -c * dx - s * dy], [0.0, 0.0, -1.0]];
        let jb = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
        let wr: [f64; 3] = std::array::from_fn(|i| w * (0..3).map(|k| e.information[i][k] * r[k]).sum::<f64>());
        let (fa, fb) = (st.free[e.from], st.free[e.to]);
        let wjb = scaled_mul(w, &e.information, &jb);
        if fa != FIXED {
            let wja = scaled_mul(w, &e.information, &ja);
            add_diag(h, &st.diag[fa], &atb(&ja, &wja));
            for (i, gi) in g[3 * fa..3 * fa + 3].iter_mut().enumerate() {
                *gi += (0..3).map(|k| ja[k][i] * wr[k]).sum::<f64>();
            }
            if fb != FIXED {
                add_off(h, off, &atb(&ja, &wjb), fa > fb);
            }
        }
        if fb != FIXED {
            add_diag(h, &st.diag[fb], &atb(&jb, &wjb));
            for (i, gi) in g[3 * fb..3 * fb + 3].iter_mut().enumerate() {
                *gi += (0..3).map(|k| jb[k][i] * wr[k]).sum::<f64>();
            }
        }
    }
    for p in &graph.priors {
        let (r, dtheta) = prior_residual(p, &nodes[p.node]);
        let (rho, w) = p.loss.evaluate(quad2(&p.information, &r));
        cost += 0.5 * rho;
        let f = st.free[p.node];
        if f == FIXED {
            continue;
        }
        let j = [[1.0, 0.0, dtheta[0]], [0.0, 1.0, dtheta[1]]];
        let info = &p.information;
        let wj: [[f64; 3]; 2] =
            std::array::from_fn(|i| std::array::from_fn(|k| w * (info[i][0] * j[0][k] + info[i][1] * j[1][k])));
        let wr: [f64; 2] = std::array::from_fn(|i| w * (info[i][0] * r[0] + info[i][1] * r[1]));
        let block: Mat3 = std::array::from_fn(|a| std::array::from_fn(|b| j[0][a] * wj[0][b] + j[1][a] * wj[1][b]));
        add_diag(h, &st.diag[f], &block);
        for (i, gi) in g[3 * f..3 * f + 3].iter_mut().enumerate() {
            *gi += j[0][i] * wr[0] + j[1][i] * wr[1];
        }
    }
    cost
}

/// See the module docs; `graph.nodes` holds the result on success and is unchanged on error.
pub(super) fn optimize(graph: &mut PoseGraph, opts: &OptimizeOptions) -> Result<OptimizeReport, PoseGraphError> {
    let gauge_free = !graph.fixed.iter().any(|&f| f) && graph.priors.is_empty();
    let mut free = vec![FIXED; graph.nodes.len()];
    let mut n_free = 0;
    for (i, slot) in free.iter_mut().enumerate() {
        if !(graph.fixed[i] || (gauge_free && i == 0)) {
            *slot = n_free;
            n_free += 1;
        }
    }
    let initial_cost = total_cost(graph, &graph.nodes);
    let mut report = OptimizeReport {
        iterations: 0,
        accepted_steps: 0,
        initial_cost,
        final_cost: initial_cost,
        converged: true,
        reused_symbolic: false,
    };
    if n_free == 0 {
        return Ok(report);
    }
    let reusable = matches!(&graph.cache, Some(st) if st.n_edges == graph.edges.len() && st.free == free);
    let mut st = match graph.cache.take() {
        Some(st) if reusable => st,
        _ => Structure::build(graph, free, n_free)?,
    };
    report.reused_symbolic = reusable;
    let start = graph.nodes.clone();
    let result = iterate(graph, &mut st, opts, &mut report);
    graph.cache = Some(st);
    if let Err(e) = result {
        graph.nodes = start;
        return Err(e);
    }
    Ok(report)
}

fn iterate(
    graph: &mut PoseGraph,
    st: &mut Structure,
    opts: &OptimizeOptions,
    report: &mut OptimizeReport,
) -> Result<(), PoseGraphError> {
    let n = 3 * st.diag.len();
    let mut h = vec![0.0; st.row_idx.len()];
    let mut damped = vec![0.0; st.row_idx.len()];
    let mut grad = vec![0.0; n];
    let mut scale = vec![0.0; n];
    let mut delta = vec![0.0; n];
    let mut trial = graph.nodes.clone();
    let mut cost = linearize(graph, st, &mut h, &mut grad);
    let mut lambda = opts.initial_lambda;
    let mut nu = 2.0;
    let mut last_failed_factorization = false;
    report.converged = false;
    loop {
        if cost == 0.0 || grad.iter().all(|g| g.abs() <= opts.gradient_tolerance) {
            report.converged = true;
            break;
        }
        if report.iterations >= opts.max_iterations {
            break;
        }
        if lambda > MAX_LAMBDA {
            if last_failed_factorization {
                return Err(PoseGraphError::Singular);
            }
            break;
        }
        report.iterations += 1;
        damp(st, &h, lambda, &mut damped, &mut scale);
        for (d, g) in delta.iter_mut().zip(&grad) {
            *d = -g;
        }
        last_failed_factorization = !solve_in_place(st, &damped, &mut delta);
        if last_failed_factorization {
            lambda *= nu;
            nu *= 2.0;
            continue;
        }
        if step_is_negligible(graph, st, &delta, opts) {
            report.converged = true;
            break;
        }
        apply_step(graph, st, &delta, &mut trial);
        let new_cost = total_cost(graph, &trial);
        if new_cost.is_finite() && new_cost < cost {
            let gain = (cost - new_cost) / predicted_decrease(&delta, &grad, &scale, lambda).max(f64::MIN_POSITIVE);
            std::mem::swap(&mut graph.nodes, &mut trial);
            report.accepted_steps += 1;
            let relative = (cost - new_cost) / cost;
            cost = linearize(graph, st, &mut h, &mut grad);
            lambda = (lambda * (1.0 - (2.0 * gain - 1.0).powi(3)).max(1.0 / 3.0)).max(MIN_LAMBDA);
            nu = 2.0;
            if relative <= opts.function_tolerance {
                report.converged = true;
                break;
            }
        } else {
            if new_cost.is_finite() && (new_cost - cost).abs() <= opts.function_tolerance * cost {
                // At the minimum up to round-off: no step can lower the cost measurably.
                report.converged = true;
                break;
            }
            lambda *= nu;
            nu *= 2.0;
        }
    }
    report.final_cost = cost;
    Ok(())
}

/// `damped` = `h` with `λ` times its clamped diagonal added (Levenberg–Marquardt with
/// Marquardt's scaling); `scale` receives that diagonal.
fn damp(st: &Structure, h: &[f64], lambda: f64, damped: &mut [f64], scale: &mut [f64]) {
    damped.copy_from_slice(h);
    for (j, d) in st.diag.iter().enumerate() {
        for (c, &p) in d.iter().enumerate() {
            let s = h[p + c].clamp(MIN_DIAGONAL, MAX_DIAGONAL);
            scale[3 * j + c] = s;
            damped[p + c] += lambda * s;
        }
    }
}

/// Solves `damped · x = delta` in place by sparse Cholesky on the symbolic factorisation of
/// `st`; false when the numeric factorisation fails (not positive definite).
fn solve_in_place(st: &mut Structure, damped: &[f64], delta: &mut [f64]) -> bool {
    let n = delta.len();
    let Structure { col_ptr, row_idx, symbolic, mem, factor, .. } = st;
    let stack = MemStack::new(mem);
    let matrix = SparseColMatRef::new(SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx), damped);
    match symbolic.factorize_numeric_llt(
        factor,
        matrix,
        Side::Upper,
        LltRegularization::default(),
        Par::Seq,
        stack,
        Default::default(),
    ) {
        Ok(llt) => {
            llt.solve_in_place_with_conj(Conj::No, MatMut::from_column_major_slice_mut(delta, n, 1), Par::Seq, stack);
            true
        }
        Err(_) => false,
    }
}

/// True when the step is below `parameter_tolerance` relative to the free poses' norm.
fn step_is_negligible(graph: &PoseGraph, st: &Structure, delta: &[f64], opts: &OptimizeOptions) -> bool {
    let step_norm = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
    let x_norm = graph
        .nodes
        .iter()
        .zip(&st.free)
        .filter(|(_, &f)| f != FIXED)
        .map(|(p, _)| p.x * p.x + p.y * p.y + p.theta * p.theta)
        .sum::<f64>()
        .sqrt();
    step_norm <= opts.parameter_tolerance * (x_norm + opts.parameter_tolerance)
}

/// `trial` = the graph's poses moved by `delta` (fixed poses unchanged).
fn apply_step(graph: &PoseGraph, st: &Structure, delta: &[f64], trial: &mut [Pose2]) {
    for ((t, x), &f) in trial.iter_mut().zip(&graph.nodes).zip(&st.free) {
        *t = if f == FIXED {
            *x
        } else {
            let d = &delta[3 * f..3 * f + 3];
            Pose2::new(x.x + d[0], x.y + d[1], normalize_angle(x.theta + d[2]))
        };
    }
}

/// The decrease of the cost the damped quadratic model predicts: ½ δᵀ(λ D δ − g).
fn predicted_decrease(delta: &[f64], grad: &[f64], scale: &[f64], lambda: f64) -> f64 {
    0.5 * delta.iter().zip(grad).zip(scale).map(|((d, g), s)| d * (lambda * s * d - g)).sum::<f64>()
}

/// `∇F` at the current estimates with every node free (for derivative checks).
#[cfg(test)]
pub(super) fn gradient(graph: &PoseGraph) -> Vec<f64> {
    let n = graph.nodes.len();
    let st = Structure::build(graph, (0..n).collect(), n).expect("structure");
    let mut h = vec![0.0; st.row_idx.len()];
    let mut g = vec![0.0; 3 * n];
    linearize(graph, &st, &mut h, &mut g);
    g
}
