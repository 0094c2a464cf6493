//! Scan-to-submap matching: a correlative search for robustness, then a Gauss–Newton
//! refinement on the smooth map, and the match's information from the score surface.
//!
//! 1. **Correlative search** (Olson 2009, "Real-time correlative scan matching"): every
//!    pose of a window around the prediction, at one cell of translation and the angular
//!    step at which the farthest point moves by about one cell, is scored by the mean
//!    probability of the scan's points in the submap, times a Gaussian-shaped penalty on
//!    the distance from the prediction (Olson's motion prior). A slip of a few centimetres
//!    or a few degrees in the odometry cannot pull the match into a wrong local minimum.
//! 2. **Refinement**: Gauss–Newton on `Σ (1 − M(T pᵢ))² · w_map²/N` plus quadratic pulls of
//!    the translation to the prediction and of the heading to the correlative result
//!    (Hess et al. 2016, §IV, with `M` interpolated bicubically), to sub-cell precision.
//! 3. **Information**: the curvature of the map cost at the optimum (see
//!    [`match_information`]) is the information of the match (Olson 2009 §IV-C derives the covariance from the score
//!    surface; its curvature is the Laplace approximation of the same). Along a featureless
//!    corridor the curvature is nearly zero, so the match says nothing there: the ratio of
//!    the smallest to the largest translational eigenvalue flags a degenerate match.

use super::grid::{floor_i64, ProbabilityGrid, P_MAX};
use super::interpolation::probability_and_gradient;
use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::parallel::{join, map_halves};

/// Parameters of one scan-to-submap match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalMatchParams {
    /// Half-width of the correlative search in x and y, metres.
    pub linear_window_m: f64,
    /// Half-width of the correlative search in heading, radians.
    pub angular_window_rad: f64,
    /// Penalty on the distance of a correlative candidate from the prediction, per metre.
    pub translation_delta_cost: f64,
    /// Penalty on the heading change of a correlative candidate, per radian.
    pub rotation_delta_cost: f64,
    /// Weight of the map term in the refinement.
    pub map_weight: f64,
    /// Pull of the refinement's translation towards the prediction, per metre.
    pub translation_weight: f64,
    /// Pull of the refinement's heading towards the correlative result, per radian.
    pub rotation_weight: f64,
    /// σ of one point's residual (probability units) for the information matrix.
    pub residual_sigma: f64,
    /// A match whose smallest/largest translational information ratio is below this is
    /// degenerate (a corridor); the caller decides what to trust (see `Slam`).
    pub degeneracy_ratio: f64,
}

impl Default for LocalMatchParams {
    fn default() -> Self {
        Self {
            linear_window_m: 0.15,
            angular_window_rad: 6f64.to_radians(),
            translation_delta_cost: 0.1,
            rotation_delta_cost: 0.1,
            map_weight: 1.0,
            translation_weight: 2.0,
            rotation_weight: 5.0,
            residual_sigma: 0.5,
            degeneracy_ratio: 0.05,
        }
    }
}

/// The outcome of a match.
#[derive(Clone, Copy, Debug)]
pub struct LocalMatch {
    /// The scan's pose in the grid frame.
    pub pose: Pose2,
    /// Mean probability of the points at `pose` (nearest cell), in `[P_MIN, P_MAX]`.
    pub score: f32,
    /// The correlative search's best score (with its motion penalty).
    pub search_score: f32,
    /// Information of `pose` (x, y, θ) from the map term's curvature.
    pub information: [[f64; 3]; 3],
    /// The translational information is nearly rank one (a corridor).
    pub degenerate: bool,
}

/// Mean probability of `points` (scan frame) at `pose` in `grid`, nearest cell.
pub fn mean_probability(grid: &ProbabilityGrid, points: &[Point2], pose: Pose2) -> f32 {
    if points.is_empty() {
        return 0.0;
    }
    let r = grid.resolution();
    let (s, c) = pose.theta.sin_cos();
    let sum: f32 = points
        .iter()
        .map(|q| {
            let (wx, wy) = (pose.x + c * q.x - s * q.y, pose.y + s * q.x + c * q.y);
            grid.probability(floor_i64(wx / r), floor_i64(wy / r))
        })
        .sum();
    sum / points.len() as f32
}

/// Olson's step moves the farthest point by one cell; far returns of a long corridor
/// would make it tiny. The refinement converges from a cell or two away, so the step is
/// taken for points up to this range (metres) and farther ones may move a few cells.
const STEP_RANGE_M: f64 = 10.0;

/// The most candidate poses the correlative search scores for one scan with a window of
/// `linear_window_m` and `angular_window_rad` on cells of `resolution` (each candidate is
/// scored against every return of the scan): what its time grows with.
pub fn search_candidates(linear_window_m: f64, angular_window_rad: f64, resolution: f64) -> f64 {
    let step = angular_step(resolution, STEP_RANGE_M);
    let n_lin = (linear_window_m / resolution).ceil();
    let n_ang = (angular_window_rad / step).ceil();
    (2.0 * n_lin + 1.0).powi(2) * (2.0 * n_ang + 1.0)
}

/// The heading step at which a point `range` metres away moves by one cell of `r`, at
/// least 10⁻⁴ rad.
fn angular_step(r: f64, range: f64) -> f64 {
    super::global_match::angular_step(r, range).max(1e-4)
}

/// The correlative search: the best pose of the window around `predicted`.
pub fn correlative_search(
    grid: &ProbabilityGrid,
    points: &[Point2],
    predicted: Pose2,
    p: &LocalMatchParams,
) -> (Pose2, f32) {
    let r = grid.resolution();
    let max_range = points.iter().map(|q| q.x.hypot(q.y)).fold(r, f64::max).min(STEP_RANGE_M);
    let step = angular_step(r, max_range);
    let n_ang = (p.angular_window_rad / step).ceil() as i64;
    let n_lin = (p.linear_window_m / r).ceil() as i64;
    // The headings in two halves on two threads; the first half wins a tie, as the first
    // heading does in one loop, so the result does not depend on the split.
    // Each half is visited from the prediction's heading outwards, where the best scores
    // are, so that the bound below cuts the far headings short.
    let mid = -n_ang + (2 * n_ang + 1) / 2;
    let search = |headings: Vec<i64>| search_headings(grid, points, predicted, p, Window { step, n_lin, headings });
    let ((b1, s1), (b2, s2)) = join(|| search((-n_ang..mid).rev().collect()), || search((mid..=n_ang).collect()));
    let (best, best_score) = if s2 > s1 { (b2, s2) } else { (b1, s1) };
    (best.normalized(), best_score)
}

/// The candidate poses of one part of the correlative search: heading steps `headings`
/// (in the order to visit them) of `step` radians, translations of up to `n_lin` cells.
struct Window {
    step: f64,
    n_lin: i64,
    headings: Vec<i64>,
}

/// Points added between two checks of a heading's bound.
const BOUND_EVERY: usize = 32;

/// The best pose of `w` around `predicted` and its score (`f32::MIN` when `w` is empty);
/// of equal scores, the first in heading (lowest step), then row, then column order,
/// whatever the order of visit.
///
/// A heading is given up part-way when even its best partial sum plus [`P_MAX`] for every
/// point still to come, times the largest penalty of the heading, falls short of the best
/// score so far (branch and bound on the points, Olson 2009 §IV's bound on a coarser
/// axis): it cannot hold the best pose. The bound is inflated by the worst rounding of
/// the `f32` sums, so the result is that of the full search to the bit.
fn search_headings(
    grid: &ProbabilityGrid,
    points: &[Point2],
    predicted: Pose2,
    p: &LocalMatchParams,
    w: Window,
) -> (Pose2, f32) {
    let (r, step, n_lin) = (grid.resolution(), w.step, w.n_lin);
    let side = (2 * n_lin + 1) as usize;
    // One sum per translation of the window, accumulated point by point: each point's
    // `side × side` patch is a few contiguous rows of the grid, read once per heading and
    // added eight lanes at a time from the active grid's `f32` mirror (lanes past `side`
    // are read and ignored). Every sum still adds its points in scan order, so the scores
    // are those of the textbook loop (translation outer, points inner) to the last bit.
    const LANES: usize = 8;
    let chunks = side.div_ceil(LANES);
    let mut sums = vec![[0f32; LANES]; side * chunks];
    let mirror = grid.probabilities();
    let row_stride = grid.limits().width;
    let (mut best, mut best_score, mut best_a) = (predicted, f32::MIN, i64::MAX);
    let inv_n = 1.0 / points.len().max(1) as f32;
    let cell_max = P_MAX * (1.0 + f32::EPSILON);
    let rounding = 1.0 + 2.0 * points.len() as f32 * f32::EPSILON;
    'headings: for a in w.headings {
        let dtheta = a as f64 * step;
        let (s, c) = (predicted.theta + dtheta).sin_cos();
        // The heading's largest penalty: the candidate at the prediction's translation.
        let top_penalty = (-(dtheta.abs() * p.rotation_delta_cost).powi(2)).exp() as f32 * (1.0 + f32::EPSILON);
        sums.iter_mut().for_each(|v| *v = [0.0; LANES]);
        for (k, q) in points.iter().enumerate() {
            if k > 0 && k % BOUND_EVERY == 0 && best_score > f32::MIN {
                let top = sums.as_flattened().iter().fold(0f32, |m, &v| m.max(v));
                let bound = (top + (points.len() - k) as f32 * cell_max) * rounding;
                if bound * inv_n * top_penalty < best_score {
                    continue 'headings;
                }
            }
            let (wx, wy) = (predicted.x + c * q.x - s * q.y, predicted.y + s * q.x + c * q.y);
            let (cx, cy) = (floor_i64(wx / r), floor_i64(wy / r));
            // Saturating: a prediction 10¹⁸ cells out (a pose from nowhere) reads cells
            // outside every grid, never wraps into one.
            let (x0, y0) = (cx.saturating_sub(n_lin), cy.saturating_sub(n_lin));
            match mirror.zip(grid.block_start(x0, y0, chunks * LANES, side)) {
                Some((probabilities, start)) => {
                    for (row, acc) in sums.chunks_exact_mut(chunks).enumerate() {
                        let cells = &probabilities[start + row * row_stride..][..chunks * LANES];
                        for (lanes, cells) in acc.iter_mut().zip(cells.chunks_exact(LANES)) {
                            for (sum, &p) in lanes.iter_mut().zip(cells) {
                                *sum += p;
                            }
                        }
                    }
                }
                None => {
                    for (row, acc) in sums.chunks_exact_mut(chunks).enumerate() {
                        for (col, sum) in acc.as_flattened_mut()[..side].iter_mut().enumerate() {
                            *sum += grid.probability(x0.saturating_add(col as i64), y0.saturating_add(row as i64));
                        }
                    }
                }
            }
        }
        for dy in -n_lin..=n_lin {
            for dx in -n_lin..=n_lin {
                let sum = sums[(dy + n_lin) as usize * chunks..][..chunks].as_flattened()[(dx + n_lin) as usize];
                let dist = ((dx * dx + dy * dy) as f64).sqrt() * r;
                let penalty = (-(dist * p.translation_delta_cost + dtheta.abs() * p.rotation_delta_cost).powi(2)).exp();
                let score = sum * inv_n * penalty as f32;
                if score > best_score || (score == best_score && a < best_a) {
                    (best_score, best_a) = (score, a);
                    best =
                        Pose2::new(predicted.x + dx as f64 * r, predicted.y + dy as f64 * r, predicted.theta + dtheta);
                }
            }
        }
    }
    (best, best_score)
}

/// Solves the 3×3 system `a x = b` (symmetric positive definite) by Cholesky.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let d = a[i][i] - s;
                if d <= 0.0 || !d.is_finite() {
                    return None;
                }
                l[i][j] = d.sqrt();
            } else {
                l[i][j] = (a[i][j] - s) / l[j][j];
            }
        }
    }
    let mut y = [0.0; 3];
    for i in 0..3 {
        y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        x[i] = (y[i] - (i + 1..3).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    Some(x)
}

/// The map term's Gauss–Newton system at `pose`: `(JᵀJ, Jᵀr, Σr²)` of the residuals
/// `1 − M(T pᵢ)` (unweighted).
fn map_system(grid: &ProbabilityGrid, points: &[Point2], pose: Pose2) -> ([[f64; 3]; 3], [f64; 3], f64) {
    let inv_r = 1.0 / grid.resolution();
    let (s, c) = pose.theta.sin_cos();
    // The interpolation (nearly all of the work) on two threads, the sums in point order.
    let samples = map_halves(points, |q| {
        let (wx, wy) = (pose.x + c * q.x - s * q.y, pose.y + s * q.x + c * q.y);
        probability_and_gradient(grid, wx * inv_r, wy * inv_r)
    });
    let (mut h, mut g, mut cost) = ([[0.0; 3]; 3], [0.0; 3], 0.0);
    for (q, &(m, gu, gv)) in points.iter().zip(&samples) {
        let res = 1.0 - m;
        // d res / d (x, y, θ) = −∇M · d(world)/d(pose), ∇M per metre.
        let (gx, gy) = (gu * inv_r, gv * inv_r);
        let j = [-gx, -gy, -(gx * (-s * q.x - c * q.y) + gy * (c * q.x - s * q.y))];
        for a in 0..3 {
            g[a] += j[a] * res;
            for b in 0..3 {
                h[a][b] += j[a] * j[b];
            }
        }
        cost += res * res;
    }
    (h, g, cost)
}

/// Refines `start` by Gauss–Newton with pulls towards `target`.
pub fn refine(grid: &ProbabilityGrid, points: &[Point2], start: Pose2, target: Pose2, p: &LocalMatchParams) -> Pose2 {
    if points.is_empty() {
        return start;
    }
    let wm2 = p.map_weight * p.map_weight / points.len() as f64;
    let (wt2, wr2) = (p.translation_weight.powi(2), p.rotation_weight.powi(2));
    let total = |pose: Pose2, map_cost: f64| {
        wm2 * map_cost
            + wt2 * ((pose.x - target.x).powi(2) + (pose.y - target.y).powi(2))
            + wr2 * normalize_angle(pose.theta - target.theta).powi(2)
    };
    let mut pose = start;
    let (mut h, mut g, map_cost) = map_system(grid, points, pose);
    let mut cost = total(pose, map_cost);
    // Levenberg–Marquardt with Nielsen's damping update (Madsen, Nielsen & Tingleff 2004,
    // *Methods for non-linear least squares problems*, §3.2): λ shrinks by up to 3× after a
    // step the quadratic model predicted well (gain ratio ρ near 1) and grows by doubling
    // factors after a rejected one. A plain ×10 / ÷10 schedule settles at λ ≈ 1 on this
    // cost and rejects every other step, so it ran to the cap on nearly every scan.
    let mut lambda = 1.0;
    let mut nu = 2.0;
    for _ in 0..30 {
        let mut a = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] = wm2 * h[i][j];
            }
        }
        a[0][0] += wt2;
        a[1][1] += wt2;
        a[2][2] += wr2;
        let b = [
            -(wm2 * g[0] + wt2 * (pose.x - target.x)),
            -(wm2 * g[1] + wt2 * (pose.y - target.y)),
            -(wm2 * g[2] + wr2 * normalize_angle(pose.theta - target.theta)),
        ];
        let diagonal = [a[0][0], a[1][1], a[2][2]];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] *= 1.0 + lambda;
        }
        let Some(d) = solve3(a, b) else { break };
        let cand = Pose2::new(pose.x + d[0], pose.y + d[1], normalize_angle(pose.theta + d[2]));
        let (h2, g2, mc2) = map_system(grid, points, cand);
        let c2 = total(cand, mc2);
        // The decrease the damped quadratic model predicts: dᵀ(λ·diag·d + b) (the cost is a
        // plain sum of squares and `b` half its negative gradient).
        let predicted: f64 = (0..3).map(|i| d[i] * (lambda * diagonal[i] * d[i] + b[i])).sum();
        if c2 <= cost {
            let small = d[0].abs() < 1e-5 && d[1].abs() < 1e-5 && d[2].abs() < 1e-6;
            let rho = (cost - c2) / predicted.max(f64::MIN_POSITIVE);
            (pose, h, g, cost) = (cand, h2, g2, c2);
            lambda *= f64::max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
            if small {
                break;
            }
        } else {
            lambda *= nu;
            nu *= 2.0;
            if lambda > 1e4 {
                break;
            }
        }
    }
    pose
}

/// `Σ (1 − M(T pᵢ))²` at `pose` (the unweighted map cost).
fn map_cost(grid: &ProbabilityGrid, points: &[Point2], pose: Pose2) -> f64 {
    let inv_r = 1.0 / grid.resolution();
    let (s, c) = pose.theta.sin_cos();
    points
        .iter()
        .map(|q| {
            let (wx, wy) = (pose.x + c * q.x - s * q.y, pose.y + s * q.x + c * q.y);
            let (m, _, _) = probability_and_gradient(grid, wx * inv_r, wy * inv_r);
            (1.0 - m) * (1.0 - m)
        })
        .sum()
}

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations:
/// `(eigenvalues, eigenvectors as columns)`.
fn eigen_symmetric3(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-14 * (a[0][0].abs() + a[1][1].abs() + a[2][2].abs()).max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            let mut b = a;
            for k in 0..3 {
                b[k][p] = c * a[k][p] - s * a[k][q];
                b[k][q] = s * a[k][p] + c * a[k][q];
            }
            a = b;
            for k in 0..3 {
                b[p][k] = c * a[p][k] - s * a[q][k];
                b[q][k] = s * a[p][k] + c * a[q][k];
            }
            a = b;
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

/// The information of a match at `pose`, and whether it is degenerate.
///
/// The curvature of the smooth map cost `C = Σ (1 − M)²` by central differences (half a
/// cell; the angle that moves the mean point by half a cell), read as the information of
/// a likelihood `exp(−C / 2σ²)`: `∇²C / 2σ²`. The Gauss–Newton `JᵀJ` will not do here: at
/// the optimum the points sit on the crests of the walls, where the gradient vanishes and
/// the curvature lives in the second-derivative term it drops. Negative curvature (noise
/// on a flat surface) is clipped to zero, so a flat direction carries no information.
pub fn match_information(
    grid: &ProbabilityGrid,
    points: &[Point2],
    pose: Pose2,
    p: &LocalMatchParams,
) -> ([[f64; 3]; 3], bool) {
    if points.len() < 3 {
        return ([[0.0; 3]; 3], true);
    }
    let r = grid.resolution();
    let mean_range = points.iter().map(|q| q.x.hypot(q.y)).sum::<f64>() / points.len() as f64;
    let h = [0.5 * r, 0.5 * r, (0.5 * r / mean_range.max(r)).min(0.05)];
    // The 19 costs of the central differences (centre, ±1 along each axis, the four
    // corners of each pair of axes), evaluated on two threads and read back in order.
    let unit = |i: usize, s: f64| {
        let mut d = [0.0; 3];
        d[i] = s * h[i];
        d
    };
    let corner = |i: usize, j: usize, si: f64, sj: f64| {
        let mut d = unit(i, si);
        d[j] = sj * h[j];
        d
    };
    let mut offsets = vec![[0.0; 3]];
    for i in 0..3 {
        offsets.extend([unit(i, 1.0), unit(i, -1.0)]);
        for j in 0..i {
            offsets.extend([
                corner(i, j, 1.0, 1.0),
                corner(i, j, 1.0, -1.0),
                corner(i, j, -1.0, 1.0),
                corner(i, j, -1.0, -1.0),
            ]);
        }
    }
    let costs =
        map_halves(&offsets, |d| map_cost(grid, points, Pose2::new(pose.x + d[0], pose.y + d[1], pose.theta + d[2])));
    let mut next = costs[1..].iter().copied();
    let mut take = || next.next().expect("one cost per offset");
    let c0 = costs[0];
    let mut hess = [[0.0; 3]; 3];
    for i in 0..3 {
        let (plus, minus) = (take(), take());
        hess[i][i] = (plus - 2.0 * c0 + minus) / (h[i] * h[i]);
        for j in 0..i {
            let (pp, pm, mp, mm) = (take(), take(), take(), take());
            let v = (pp - pm - mp + mm) / (4.0 * h[i] * h[j]);
            hess[i][j] = v;
            hess[j][i] = v;
        }
    }
    let (vals, vecs) = eigen_symmetric3(hess);
    let scale = 1.0 / (2.0 * p.residual_sigma * p.residual_sigma);
    let mut info = [[0.0; 3]; 3];
    for (k, &l) in vals.iter().enumerate() {
        let l = l.max(0.0) * scale;
        for i in 0..3 {
            for j in 0..3 {
                info[i][j] += l * vecs[i][k] * vecs[j][k];
            }
        }
    }
    let (a, b, c) = (info[0][0], info[0][1], info[1][1]);
    let disc = ((a - c) * (a - c) / 4.0 + b * b).sqrt();
    let (l_max, l_min) = ((a + c) / 2.0 + disc, (a + c) / 2.0 - disc);
    let degenerate = points.len() < 10 || l_max <= 0.0 || l_min / l_max < p.degeneracy_ratio;
    (info, degenerate)
}

/// Matches `points` (scan frame) against `grid` around `predicted`.
pub fn match_scan(grid: &ProbabilityGrid, points: &[Point2], predicted: Pose2, p: &LocalMatchParams) -> LocalMatch {
    let (coarse, search_score) = correlative_search(grid, points, predicted, p);
    // The translation is pulled to the prediction (the motion prior) and the heading to
    // the search's best, as Cartographer's Ceres matcher does: along a featureless wall the
    // search's best cell is noise and the prior carries the pose; a heading error of the
    // prediction beyond the refinement's reach is the search's to find.
    let target = Pose2::new(predicted.x, predicted.y, coarse.theta);
    let pose = refine(grid, points, coarse, target, p);
    let (information, degenerate) = match_information(grid, points, pose, p);
    LocalMatch { pose, score: mean_probability(grid, points, pose), search_score, information, degenerate }
}

#[cfg(test)]
#[path = "local_match_tests.rs"]
mod tests;
