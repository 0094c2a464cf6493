//! Exact grid traversal of a segment (Amanatides & Woo, "A Fast Voxel Traversal Algorithm
//! for Ray Tracing", Eurographics 1987).
//!
//! The traversal visits every cell whose interior the segment crosses, each exactly once,
//! in order from the start cell to the end cell, stepping to a 4-connected neighbour at
//! each step. Where the segment passes exactly through a cell corner it touches neither
//! side cell's interior; the walk still has to go through one of them to stay connected
//! and takes the y step first.
//!
//! The design document instead samples the beam every half cell: that skips the corner
//! cells a beam clips (its samples jump over them) and updates most cells twice per beam
//! (≈ 1.55× the updates of an exact traversal on the corridor), which counts one
//! observation twice. Bresenham lines have the same holes (nav2 costmap issue #267).
//!
//! **Robust end.** The number of x and y steps is fixed up front from the integer cells
//! of the two ends (`|Δi| + |Δj|` steps), and the floating-point crossing parameters only
//! choose the order. So the walk always ends in exactly the cell `floor(end)` — the cell
//! the sensor model marks occupied — however the rounding falls.

use super::CellIndex;

/// An allocation-free walk over the cells a segment crosses.
///
/// Coordinates are in continuous cell units (see
/// [`GridGeometry::to_cell_units`](super::GridGeometry::to_cell_units)): cell `(i, j)` spans
/// `[i, i+1) × [j, j+1)`.
///
/// ```
/// use fusemap_core::grid::{CellIndex, CellRay};
/// let cells: Vec<CellIndex> = CellRay::new((0.5, 0.5), (2.5, 1.5)).collect();
/// assert_eq!(cells.first(), Some(&CellIndex::new(0, 0)));
/// assert_eq!(cells.last(), Some(&CellIndex::new(2, 1)));
/// assert_eq!(cells.len(), 4);
/// ```
#[derive(Clone, Debug)]
pub struct CellRay {
    x: i64,
    y: i64,
    step_x: i64,
    step_y: i64,
    t_max_x: f64,
    t_max_y: f64,
    t_delta_x: f64,
    t_delta_y: f64,
    remaining_x: u64,
    remaining_y: u64,
    remaining: u64,
    finished: bool,
}

impl CellRay {
    /// A walk from `start` to `end` (cell units). Both must be finite and within ±2^62.
    #[inline]
    pub fn new(start: (f64, f64), end: (f64, f64)) -> Self {
        let (x0, y0) = (start.0.floor(), start.1.floor());
        let (x1, y1) = (end.0.floor(), end.1.floor());
        let (ix0, iy0, ix1, iy1) = (x0 as i64, y0 as i64, x1 as i64, y1 as i64);
        let dx = end.0 - start.0;
        let dy = end.1 - start.1;
        let (step_x, t_max_x, t_delta_x) = axis(start.0, x0, dx);
        let (step_y, t_max_y, t_delta_y) = axis(start.1, y0, dy);
        let (remaining_x, remaining_y) = (ix1.abs_diff(ix0), iy1.abs_diff(iy0));
        // An axis with no step left never wins the comparison in `step`.
        let t_max_x = if remaining_x == 0 { f64::INFINITY } else { t_max_x };
        let t_max_y = if remaining_y == 0 { f64::INFINITY } else { t_max_y };
        Self {
            x: ix0,
            y: iy0,
            step_x,
            step_y,
            t_max_x,
            t_max_y,
            t_delta_x,
            t_delta_y,
            remaining_x,
            remaining_y,
            remaining: remaining_x + remaining_y,
            finished: false,
        }
    }

    /// Number of cells the walk visits in all (`|Δi| + |Δj| + 1`), known before walking.
    pub fn len_cells(&self) -> u64 {
        if self.finished {
            0
        } else {
            self.remaining + 1
        }
    }

    /// Cells the walk visits after the current one (its steps left).
    #[inline(always)]
    pub fn cells_after(&self) -> u64 {
        self.remaining
    }

    /// The cell the walk is at.
    #[inline(always)]
    pub fn cell(&self) -> CellIndex {
        CellIndex::new(self.x, self.y)
    }

    /// Moves to the next cell; `false` when the current cell was the last one.
    #[inline(always)]
    pub fn advance(&mut self) -> bool {
        self.step() != Step::Done
    }

    /// Moves to the next cell and says which way it went, so that a caller walking
    /// inside a tile can update its own offset instead of recomputing it from the cell.
    #[inline(always)]
    pub fn step(&mut self) -> Step {
        if self.remaining == 0 {
            return Step::Done;
        }
        self.remaining -= 1;
        // Ties (the segment passes exactly through a cell corner) take the y step. An
        // exhausted axis has `t_max = ∞`, so the step counts, not the rounding of the
        // crossing parameters, decide where the walk ends.
        if self.t_max_x < self.t_max_y {
            self.x += self.step_x;
            self.remaining_x -= 1;
            self.t_max_x = if self.remaining_x == 0 { f64::INFINITY } else { self.t_max_x + self.t_delta_x };
            Step::X
        } else {
            self.y += self.step_y;
            self.remaining_y -= 1;
            self.t_max_y = if self.remaining_y == 0 { f64::INFINITY } else { self.t_max_y + self.t_delta_y };
            Step::Y
        }
    }

    /// The x step direction: -1, 0 or +1.
    #[inline(always)]
    pub fn step_x(&self) -> i64 {
        self.step_x
    }

    /// The y step direction: -1, 0 or +1.
    #[inline(always)]
    pub fn step_y(&self) -> i64 {
        self.step_y
    }

    /// Calls `visit` on every cell in order; stops early when it returns `false`.
    /// Returns `false` when stopped early.
    #[inline]
    pub fn for_each(mut self, mut visit: impl FnMut(CellIndex) -> bool) -> bool {
        if self.finished {
            return true;
        }
        loop {
            if !visit(self.cell()) {
                return false;
            }
            if !self.advance() {
                return true;
            }
        }
    }
}

/// Which way [`CellRay::step`] moved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The previous cell was the last one.
    Done,
    /// One cell along x (by [`CellRay::step_x`]).
    X,
    /// One cell along y (by [`CellRay::step_y`]).
    Y,
}

impl Iterator for CellRay {
    type Item = CellIndex;

    fn next(&mut self) -> Option<CellIndex> {
        if self.finished {
            return None;
        }
        let c = self.cell();
        if !self.advance() {
            self.finished = true;
        }
        Some(c)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.len_cells() as usize;
        (n, Some(n))
    }
}

/// Step direction, parameter of the first border crossing, and parameter per cell, for
/// one axis of a segment parameterised by t ∈ [0, 1].
#[inline(always)]
fn axis(start: f64, start_floor: f64, d: f64) -> (i64, f64, f64) {
    if d > 0.0 {
        (1, (start_floor + 1.0 - start) / d, 1.0 / d)
    } else if d < 0.0 {
        (-1, (start - start_floor) / -d, 1.0 / -d)
    } else {
        (0, f64::INFINITY, f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashSet;

    fn walk(a: (f64, f64), b: (f64, f64)) -> Vec<(i64, i64)> {
        CellRay::new(a, b).map(|c| (c.x, c.y)).collect()
    }

    #[test]
    fn single_cell() {
        assert_eq!(walk((0.2, 0.3), (0.8, 0.9)), vec![(0, 0)]);
        assert_eq!(walk((0.5, 0.5), (0.5, 0.5)), vec![(0, 0)]);
        assert_eq!(walk((-0.5, -0.5), (-0.1, -0.9)), vec![(-1, -1)]);
    }

    #[test]
    fn axis_aligned_both_ways() {
        assert_eq!(walk((0.5, 0.5), (3.5, 0.5)), vec![(0, 0), (1, 0), (2, 0), (3, 0)]);
        assert_eq!(walk((3.5, 0.5), (0.5, 0.5)), vec![(3, 0), (2, 0), (1, 0), (0, 0)]);
        assert_eq!(walk((0.5, 0.5), (0.5, 3.5)), vec![(0, 0), (0, 1), (0, 2), (0, 3)]);
        assert_eq!(walk((0.5, 3.5), (0.5, 0.5)), vec![(0, 3), (0, 2), (0, 1), (0, 0)]);
    }

    #[test]
    fn diagonal_through_corners_is_connected() {
        let w = walk((0.5, 0.5), (2.5, 2.5));
        assert_eq!(w.len(), 5);
        assert_eq!(w.first(), Some(&(0, 0)));
        assert_eq!(w.last(), Some(&(2, 2)));
        assert_connected(&w);
        // Through the exact corner (1, 1) the walk takes the y step first.
        assert_eq!(w[1], (0, 1));
    }

    #[test]
    fn steep_and_flat() {
        // Crosses x = 1 at y = 3.9: four cells in column 0, five in column 1.
        let steep = walk((0.5, 0.5), (1.5, 7.3));
        assert_eq!(steep.len(), 9);
        assert_connected(&steep);
        assert_eq!(steep.iter().filter(|c| c.0 == 0).count(), 4);
        let flat = walk((0.5, 0.5), (7.3, 1.5));
        assert_eq!(flat.len(), 9);
        assert_connected(&flat);
        assert_eq!(flat.iter().filter(|c| c.1 == 0).count(), 4);
    }

    #[test]
    fn starting_and_ending_on_borders() {
        // On a border, floor decides: x = 1.0 belongs to cell 1.
        assert_eq!(walk((1.0, 0.5), (3.0, 0.5)), vec![(1, 0), (2, 0), (3, 0)]);
        assert_eq!(walk((3.0, 0.5), (1.0, 0.5)), vec![(3, 0), (2, 0), (1, 0)]);
        assert_eq!(walk((0.5, 2.0), (0.5, 0.0)), vec![(0, 2), (0, 1), (0, 0)]);
        // Starting exactly on a corner, going down-left.
        let w = walk((2.0, 2.0), (0.0, 0.0));
        assert_eq!(w.first(), Some(&(2, 2)));
        assert_eq!(w.last(), Some(&(0, 0)));
        assert_connected(&w);
    }

    #[test]
    fn negative_coordinates() {
        let w = walk((-0.5, -0.5), (-3.5, -1.5));
        assert_eq!(w.first(), Some(&(-1, -1)));
        assert_eq!(w.last(), Some(&(-4, -2)));
        assert_eq!(w.len(), 5);
        assert_connected(&w);
        let w = walk((-2.3, 1.7), (4.1, -3.9));
        assert_eq!(w.last(), Some(&(4, -4)));
        assert_connected(&w);
    }

    #[test]
    fn same_ray_at_many_scales() {
        // The same geometric ray scaled by k crosses about k times as many cells, and
        // always ends in the end point's cell (Cartographer's ray_to_pixel_mask test idea).
        for k in 1..=50 {
            let s = k as f64;
            let a = (0.37 * s, 0.21 * s);
            let b = (4.91 * s, -2.63 * s);
            let w = walk(a, b);
            assert_eq!(w.last().copied(), Some((b.0.floor() as i64, b.1.floor() as i64)));
            assert_connected(&w);
            assert_no_repeats(&w);
            assert_eq!(w, reference_walk_cells(a, b, &w));
        }
    }

    #[test]
    fn early_stop() {
        let mut n = 0;
        let complete = CellRay::new((0.5, 0.5), (10.5, 0.5)).for_each(|_| {
            n += 1;
            n < 3
        });
        assert!(!complete);
        assert_eq!(n, 3);
    }

    fn assert_connected(w: &[(i64, i64)]) {
        for p in w.windows(2) {
            let d = (p[1].0 - p[0].0).abs() + (p[1].1 - p[0].1).abs();
            assert_eq!(d, 1, "not 4-connected at {:?}", p);
        }
    }

    fn assert_no_repeats(w: &[(i64, i64)]) {
        let s: HashSet<_> = w.iter().collect();
        assert_eq!(s.len(), w.len(), "a cell was visited twice");
    }

    /// Parameter interval of the segment inside cell (i, j), expanded by `eps` on every
    /// side. `None` when the segment misses the (expanded) cell.
    fn clip(a: (f64, f64), b: (f64, f64), i: i64, j: i64, eps: f64) -> Option<(f64, f64)> {
        let mut lo: f64 = 0.0;
        let mut hi: f64 = 1.0;
        for (s, d, c) in [(a.0, b.0 - a.0, i as f64), (a.1, b.1 - a.1, j as f64)] {
            let (cmin, cmax) = (c - eps, c + 1.0 + eps);
            if d == 0.0 {
                if s < cmin || s > cmax {
                    return None;
                }
            } else {
                let (t0, t1) = ((cmin - s) / d, (cmax - s) / d);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// Brute force: every cell whose interior the segment crosses (shrunk cells, so grazing
    /// a corner or running along a border does not count), plus the start and end cells.
    fn must_visit(a: (f64, f64), b: (f64, f64)) -> HashSet<(i64, i64)> {
        let (xmin, xmax) = (a.0.min(b.0).floor() as i64 - 1, a.0.max(b.0).floor() as i64 + 1);
        let (ymin, ymax) = (a.1.min(b.1).floor() as i64 - 1, a.1.max(b.1).floor() as i64 + 1);
        let mut s = HashSet::new();
        for i in xmin..=xmax {
            for j in ymin..=ymax {
                if let Some((lo, hi)) = clip(a, b, i, j, -1e-9) {
                    if hi - lo > 1e-9 {
                        s.insert((i, j));
                    }
                }
            }
        }
        s.insert((a.0.floor() as i64, a.1.floor() as i64));
        s.insert((b.0.floor() as i64, b.1.floor() as i64));
        s
    }

    /// Orders the walk's cells by where the segment enters them, checking on the way that
    /// each cell is at least touched by the segment (closed cell, small tolerance), that
    /// every cell whose interior is crossed is in the walk, and that the walk is monotone
    /// along the segment. Returns the walk unchanged when all holds.
    fn reference_walk_cells(a: (f64, f64), b: (f64, f64), w: &[(i64, i64)]) -> Vec<(i64, i64)> {
        let mut last_lo = -1.0;
        for &(i, j) in w {
            let (lo, _) =
                clip(a, b, i, j, 1e-9).unwrap_or_else(|| panic!("cell {:?} not on segment {a:?}->{b:?}", (i, j)));
            assert!(lo >= last_lo - 1e-9, "walk goes backwards at {:?}", (i, j));
            last_lo = lo;
        }
        let set: HashSet<_> = w.iter().copied().collect();
        for c in must_visit(a, b) {
            assert!(set.contains(&c), "walk {a:?}->{b:?} misses crossed cell {c:?}");
        }
        w.to_vec()
    }

    fn coord() -> impl Strategy<Value = f64> {
        // Mix free floats with coordinates snapped to borders and half cells.
        prop_oneof![-20.0..20.0f64, (-40i32..40).prop_map(|k| k as f64 * 0.5), (-20i32..20).prop_map(|k| k as f64),]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn traversal_matches_brute_force(ax in coord(), ay in coord(), bx in coord(), by in coord()) {
            let (a, b) = ((ax, ay), (bx, by));
            let w = walk(a, b);
            prop_assert_eq!(w.first().copied(), Some((ax.floor() as i64, ay.floor() as i64)));
            prop_assert_eq!(w.last().copied(), Some((bx.floor() as i64, by.floor() as i64)));
            let expect_len = (bx.floor() - ax.floor()).abs() + (by.floor() - ay.floor()).abs() + 1.0;
            prop_assert_eq!(w.len() as f64, expect_len);
            assert_connected(&w);
            assert_no_repeats(&w);
            reference_walk_cells(a, b, &w);
        }

        #[test]
        fn far_from_the_origin(ox in -1e9..1e9f64, oy in -1e9..1e9f64,
                               dx in -300.0..300.0f64, dy in -300.0..300.0f64) {
            let a = (ox, oy);
            let b = (ox + dx, oy + dy);
            let w = walk(a, b);
            prop_assert_eq!(w.last().copied(), Some((b.0.floor() as i64, b.1.floor() as i64)));
            assert_connected(&w);
            assert_no_repeats(&w);
        }
    }
}
