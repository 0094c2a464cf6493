//! Global scan matching by branch and bound: a scan against a finished submap over a large
//! window, for loop closure (Hess et al. 2016, "Real-Time Loop Closure in 2D LIDAR SLAM",
//! §V).
//!
//! The search space is discrete. Angles step by `δθ = arccos(1 − r² / (2 d_max²))`
//! (eq. (7)): the rotation that moves the scan's farthest point by at most one cell of size
//! `r`. Translations step by whole cells. For every angle the scan is rotated once and
//! turned into integer cells ("discretised scans", §V-A); a candidate pose is then an angle
//! index plus an integer cell offset, and scoring it is a sum of grid lookups.
//!
//! Branch and bound (§V-B, Algorithm 3): a node at height `h` stands for the `2^h × 2^h`
//! offsets starting at its own; its bound is the sum of the level-`h` precomputed grid
//! ([`PrecomputedGrids`]) at the scan's cells, never below the score of any offset it stands
//! for. The search starts from the coarsest nodes tiling the window, every angle, sorted by
//! bound; it goes depth first, best child first, and drops a node whose bound does not beat
//! the best leaf so far (initially the score threshold). A node splits into its four
//! quadrants; a leaf (height 0) is scored on level 0, the grid itself at byte precision.
//! The result is the best discretised pose, exactly as an exhaustive search over the same
//! window would find, at a small fraction of the lookups.

mod precomputed;

pub use precomputed::PrecomputedGrids;

use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::slam::grid::{floor_i64, ProbabilityGrid, P_MAX, P_MIN};
use precomputed::Level;

/// The search window and acceptance threshold of [`match_branch_and_bound`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalSearch {
    /// Half-width of the square translation window around the initial guess, metres.
    pub linear_window_m: f64,
    /// Half-width of the rotation window around the initial guess, radians.
    pub angular_window_rad: f64,
    /// The lowest mean probability a match may have; below it there is no match.
    pub min_score: f32,
    /// Levels of the precomputed grids the search uses (the coarsest nodes cover
    /// `2^(depth−1)` cells a side); the search uses at most the levels the grids hold.
    pub depth: usize,
}

impl Default for GlobalSearch {
    /// Hess et al.'s 2D loop-closure settings: 7 m, 30°, score 0.55, depth 7.
    fn default() -> Self {
        Self { linear_window_m: 7.0, angular_window_rad: 30f64.to_radians(), min_score: 0.55, depth: 7 }
    }
}

/// A loop-closure match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalMatch {
    /// The scan's pose in the grid's (local) frame.
    pub pose: Pose2,
    /// Mean probability of the scan points at `pose`, in `[P_MIN, P_MAX]`, from the
    /// byte-precision grid: never below the exact [`score_at`], at most `(P_MAX − P_MIN) / 255`
    /// above it.
    pub score: f32,
}

/// Mean probability of the grid cells holding `points` (scan frame) moved by `pose`; the
/// score the global search maximises, at full precision. Non-finite points are skipped;
/// with no point left the score is [`P_MIN`] (nothing is explained).
pub fn score_at(grid: &ProbabilityGrid, points: &[Point2], pose: Pose2) -> f32 {
    let (r, to) = (grid.resolution(), pose.point_transform());
    let (sum, n) = points.iter().filter(|p| p.is_finite()).fold((0.0f64, 0usize), |(s, n), p| {
        let q = to(*p);
        let (cx, cy) = (floor_i64(q.x / r), floor_i64(q.y / r));
        (s + f64::from(grid.probability(cx, cy)), n + 1)
    });
    if n == 0 {
        P_MIN
    } else {
        (sum / n as f64) as f32
    }
}

/// One rotation of the scan: its angle and the cells of its points at that angle with the
/// initial translation, relative to the grid's first cell. Points that no candidate of
/// the window can move onto a non-zero cell of any level are left out (they add zero to
/// every sum), but still count in the mean.
#[derive(Clone, Debug)]
struct DiscreteScan {
    theta: f64,
    cells: Vec<[i32; 2]>,
}

/// The discretised search problem: every rotation, the window in cells, the point count.
#[derive(Clone, Debug)]
struct Problem {
    scans: Vec<DiscreteScan>,
    /// Translation offsets run over `[−window, window]` cells on each axis.
    window: i32,
    /// Points scored (the mean's denominator).
    n: usize,
}

/// The work of a search, in grid lookups at the coarsest level: every angle times every
/// coarsest node of the window times the points. What a batch's budget counts; the descent
/// below the coarsest level adds a share that depends on the map, not the window.
pub fn search_work(search: &GlobalSearch, resolution: f64, d_max: f64, points: usize, levels: usize) -> f64 {
    let step = angular_step(resolution, d_max).max(1e-6);
    let angles = 2.0 * (search.angular_window_rad.max(0.0) / step).ceil() + 1.0;
    let w = (search.linear_window_m.max(0.0) / resolution).ceil();
    let top = (1u64 << levels.clamp(1, 30).saturating_sub(1)) as f64;
    let per_axis = (2.0 * w / top).floor() + 1.0;
    angles * per_axis * per_axis * points as f64
}

/// The number of levels that leaves about six coarsest nodes across a window of
/// `linear_window_m`, within `[1, max]`: a wide window starts coarser.
pub fn levels_for(linear_window_m: f64, resolution: f64, max: usize) -> usize {
    let w = (linear_window_m.max(0.0) / resolution).ceil().max(1.0);
    (1 + (2.0 * w / 6.0).log2().ceil().max(0.0) as usize).clamp(1, max.max(1))
}

/// The angular step of eq. (7) for a scan reaching `d_max` on a grid of cell `r` (Hess et
/// al. 2016): the heading change that moves the farthest point by one cell. The local
/// matcher steps its headings by the same rule.
pub(crate) fn angular_step(r: f64, d_max: f64) -> f64 {
    let d = d_max.max(r);
    (1.0 - r * r / (2.0 * d * d)).clamp(-1.0, 1.0).acos()
}

impl Problem {
    fn new(grids: &PrecomputedGrids, points: &[Point2], initial: Pose2, search: &GlobalSearch, levels: usize) -> Self {
        let r = grids.resolution();
        let points: Vec<Point2> = points.iter().copied().filter(|p| p.is_finite()).collect();
        let d_max = points.iter().map(|p| p.x.hypot(p.y)).fold(0.0, f64::max);
        let step = angular_step(r, d_max);
        let ang = search.angular_window_rad.max(0.0);
        let n_angles = if ang > 0.0 && step > 0.0 { (ang / step).ceil().min(1e6) as i64 } else { 0 };
        let window = (search.linear_window_m.max(0.0) / r).ceil().min(1e6) as i32;
        let min = grids.min();
        let (w, h) = grids.size();
        let coarse = 1i64 << (levels - 1);
        // A point cell c is useful when some offset in [−window, window] puts a block of
        // 2^(levels−1) cells starting at c + offset over [0, size).
        // Saturating: a point 10¹⁸ cells out (a pose from nowhere) is useless, never wraps.
        let useful = |c: i64, size: i32| {
            c.saturating_add(window as i64 + coarse) > 0 && c.saturating_sub(window as i64) < size as i64
        };
        let scans = (-n_angles..=n_angles)
            .map(|k| {
                let theta = initial.theta + k as f64 * step;
                let to = Pose2::new(initial.x, initial.y, theta).point_transform();
                let cells = points
                    .iter()
                    .filter_map(|p| {
                        let q = to(*p);
                        let cx = floor_i64(q.x / r).saturating_sub(min.x);
                        let cy = floor_i64(q.y / r).saturating_sub(min.y);
                        (useful(cx, w) && useful(cy, h)).then_some([cx as i32, cy as i32])
                    })
                    .collect();
                DiscreteScan { theta, cells }
            })
            .collect();
        Self { scans, window, n: points.len() }
    }

    /// The smallest byte sum whose mean probability reaches `min_score`, or `None` when
    /// no sum can.
    fn threshold(&self, min_score: f32) -> Option<u32> {
        let top = 255 * self.n as u64;
        let frac = f64::from((min_score - P_MIN) / (P_MAX - P_MIN));
        let mut s = (frac * top as f64).ceil().clamp(0.0, top as f64 + 1.0) as u64;
        while s > 0 && self.score(s - 1) >= min_score {
            s -= 1;
        }
        while s <= top && self.score(s) < min_score {
            s += 1;
        }
        (s <= top).then_some(s as u32)
    }

    /// The mean probability a byte sum stands for.
    fn score(&self, sum: u64) -> f32 {
        P_MIN + (P_MAX - P_MIN) * (sum as f64 / (255.0 * self.n as f64)) as f32
    }
}

/// A search node: angle index, the first cell offset it stands for, its bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Candidate {
    scan: u32,
    dx: i32,
    dy: i32,
    bound: u32,
}

/// The depth-first search state: the best leaf so far.
struct Search<'a> {
    grids: &'a PrecomputedGrids,
    problem: &'a Problem,
    best: Option<Candidate>,
    /// A node must beat this sum to be worth opening (the best leaf, or threshold − 1).
    floor: i64,
}

impl Search<'_> {
    fn bound(&self, level: &Level, scan: u32, dx: i32, dy: i32) -> Candidate {
        let bound = level.sum(&self.problem.scans[scan as usize].cells, dx, dy, self.floor);
        Candidate { scan, dx, dy, bound }
    }

    /// Opens node `c` at height `h` (its bound already beats the floor).
    fn descend(&mut self, c: Candidate, h: usize) {
        if h == 0 {
            self.floor = i64::from(c.bound);
            self.best = Some(c);
            return;
        }
        let s = 1i32 << (h - 1);
        let level = self.grids.level(h - 1);
        let w = self.problem.window;
        let sums = level.sum4(&self.problem.scans[c.scan as usize].cells, c.dx, c.dy, s, self.floor);
        let mut children = [c; 4];
        let mut n = 0;
        for ((ox, oy), bound) in [(0, 0), (s, 0), (0, s), (s, s)].into_iter().zip(sums) {
            let (dx, dy) = (c.dx + ox, c.dy + oy);
            if dx <= w && dy <= w {
                children[n] = Candidate { scan: c.scan, dx, dy, bound };
                n += 1;
            }
        }
        let children = &mut children[..n];
        children.sort_unstable_by_key(|c| std::cmp::Reverse(c.bound));
        for &child in children.iter() {
            if i64::from(child.bound) <= self.floor {
                break;
            }
            self.descend(child, h - 1);
        }
    }
}

/// The best leaf of the discretised problem whose byte sum reaches `need`, searching from
/// height `levels − 1` (Algorithm 3); and the best root (the coarsest node with the highest
/// bound), which bounds every score of the window from above.
fn branch_and_bound(
    grids: &PrecomputedGrids,
    problem: &Problem,
    levels: usize,
    need: u32,
) -> (Option<Candidate>, Option<Candidate>) {
    let top = levels - 1;
    let step = 1usize << top;
    let w = problem.window;
    let coarse = grids.level(top);
    let mut state = Search { grids, problem, best: None, floor: i64::from(need) - 1 };
    let per_axis = (2 * w as usize) / step + 1;
    let mut roots = Vec::with_capacity(problem.scans.len() * per_axis * per_axis);
    for scan in 0..problem.scans.len() as u32 {
        for dx in (-w..=w).step_by(step) {
            for dy in (-w..=w).step_by(step) {
                roots.push(state.bound(coarse, scan, dx, dy));
            }
        }
    }
    // Sorted by bound, ties by position: the best root does not depend on the sort.
    roots.sort_unstable_by_key(|c| (std::cmp::Reverse(c.bound), c.scan, c.dx, c.dy));
    for &c in &roots {
        if i64::from(c.bound) <= state.floor {
            break;
        }
        state.descend(c, top);
    }
    (state.best, roots.first().copied())
}

/// What a search found, and how near it came when it found nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOutcome {
    /// The best pose reaching the threshold.
    pub found: Option<GlobalMatch>,
    /// The found match's score; without one, an upper bound of every score in the window
    /// (the best coarsest node's bound; `P_MIN` when there was nothing to score).
    pub best_score: f32,
    /// The found pose, or the best coarsest node, touches the window's edge (in x, y, or in
    /// heading when the window is not the full circle): the true pose may lie beyond it.
    pub on_edge: bool,
}

/// Finds the pose of a scan in a submap by branch and bound over the window `search`
/// around `initial` (Hess et al. 2016, §V).
///
/// `points` are the scan's points in its own frame (metres), `initial` the guess of its
/// pose in the grid's frame. Returns the best discretised pose and its score, or `None`
/// when no pose in the window reaches `search.min_score` (or there is no finite point).
pub fn match_branch_and_bound(
    grids: &PrecomputedGrids,
    points: &[Point2],
    initial: Pose2,
    search: &GlobalSearch,
) -> Option<GlobalMatch> {
    search_branch_and_bound(grids, points, initial, search).found
}

/// [`match_branch_and_bound`], with what the search saw when it found nothing.
pub fn search_branch_and_bound(
    grids: &PrecomputedGrids,
    points: &[Point2],
    initial: Pose2,
    search: &GlobalSearch,
) -> SearchOutcome {
    let nothing = SearchOutcome { found: None, best_score: P_MIN, on_edge: false };
    if !initial.is_finite() {
        return nothing;
    }
    let levels = search.depth.clamp(1, grids.depth());
    let problem = Problem::new(grids, points, initial, search, levels);
    if problem.n == 0 {
        return nothing;
    }
    let full_circle = search.angular_window_rad >= std::f64::consts::PI;
    let last = problem.scans.len() as u32 - 1;
    let w = problem.window;
    let edge_angle = |c: &Candidate| !full_circle && (c.scan == 0 || c.scan == last);
    let Some(need) = problem.threshold(search.min_score) else { return nothing };
    let (best, root) = branch_and_bound(grids, &problem, levels, need);
    let Some(best) = best else {
        let step = 1i32 << (levels - 1);
        return match root {
            Some(c) => SearchOutcome {
                found: None,
                best_score: problem.score(u64::from(c.bound)),
                on_edge: edge_angle(&c) || c.dx <= -w || c.dy <= -w || c.dx + step > w || c.dy + step > w,
            },
            None => nothing,
        };
    };
    let r = grids.resolution();
    let theta = problem.scans[best.scan as usize].theta;
    let found = GlobalMatch {
        pose: Pose2::new(
            initial.x + f64::from(best.dx) * r,
            initial.y + f64::from(best.dy) * r,
            normalize_angle(theta),
        ),
        score: problem.score(u64::from(best.bound)),
    };
    SearchOutcome {
        found: Some(found),
        best_score: found.score,
        on_edge: edge_angle(&best) || best.dx.abs() == w || best.dy.abs() == w,
    }
}

#[cfg(test)]
mod tests;
