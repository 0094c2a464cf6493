//! The probability grid of one submap: dense, growing to fit, updated in odds space.
//!
//! Scan matching reads a submap millions of times per second, so unlike the mapper's tiled
//! log-odds grid this one is a dense array of 16-bit values. A value `v` in `1..=32767`
//! stands for a probability linear in `[P_MIN, P_MAX]`; `0` is a cell never observed, read
//! as `P_MIN` by the matchers (an unexplored cell explains no return). An update multiplies
//! the cell's odds by the hit or miss odds (Thrun et al., *Probabilistic Robotics*, §9.2,
//! written multiplicatively as in Hess et al. 2016), through two 32 768-entry tables built
//! once, so an update is a table lookup. Each cell changes at most once per scan: a table
//! entry carries a marker bit, and cells marked during a scan are left alone until the scan
//! ends (the same once-per-scan rule as the mapper's grid).
//!
//! While a submap is being built it is also the local matcher's target, read ~50 times per
//! point per heading; so an active grid keeps a mirror of its cells as `f32`
//! probabilities, updated with the cells each scan changes, which the matchers add up with
//! vector instructions. [`ProbabilityGrid::freeze`] drops the mirror when the submap is
//! finished (loop closure reads its own precomputed grids, and the field unpacked beside
//! them).

use super::field::Crossing;
use crate::geometry::Point2;
use crate::grid::{CellIndex, CellRay};

/// The lowest probability a cell can hold (and what an unknown cell reads as).
pub const P_MIN: f32 = 0.1;
/// The highest probability a cell can hold.
pub const P_MAX: f32 = 0.9;
const MAX_VALUE: u16 = 32767;
const MARK: u16 = 1 << 15;

/// The probability a stored value stands for.
#[inline]
pub fn value_to_probability(v: u16) -> f32 {
    let v = (v & !MARK).max(1);
    P_MIN + (v - 1) as f32 * ((P_MAX - P_MIN) / (MAX_VALUE - 1) as f32)
}

/// `⌊x⌋` as an integer, as `x.floor() as i64` gives it (saturating, NaN → 0), without the
/// libm call that `floor` is on baseline x86-64: the matchers take it for every point of
/// every candidate pose.
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    i.saturating_sub(i64::from(i as f64 > x))
}

/// The stored value nearest to probability `p` (clamped to `[P_MIN, P_MAX]`).
#[inline]
pub fn probability_to_value(p: f32) -> u16 {
    let p = p.clamp(P_MIN, P_MAX);
    1 + ((p - P_MIN) / (P_MAX - P_MIN) * (MAX_VALUE - 1) as f32).round() as u16
}

fn odds(p: f32) -> f32 {
    p / (1.0 - p)
}

/// An odds-multiplying update as a table over stored values: entry `v` is the marked value
/// after one update of a cell holding `v` (unknown cells start at probability ½).
#[derive(Clone, Debug)]
pub struct UpdateTable {
    table: Vec<u16>,
}

impl UpdateTable {
    /// The table for an observation of probability `p` (hit: `p > ½`, miss: `p < ½`).
    pub fn new(p: f32) -> Self {
        let o = odds(p.clamp(0.01, 0.99));
        let table = (0..=MAX_VALUE)
            .map(|v| {
                let prior = if v == 0 { 0.5 } else { value_to_probability(v) };
                let post = odds(prior) * o;
                probability_to_value(post / (1.0 + post)) | MARK
            })
            .collect();
        Self { table }
    }
}

/// Cell limits of a grid: `width × height` cells from `min` (inclusive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellLimits {
    /// The lowest cell (x, y).
    pub min: CellIndex,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl CellLimits {
    /// The linear index of cell `(x, y)`, when inside.
    #[inline]
    pub fn index(&self, x: i64, y: i64) -> Option<usize> {
        let (dx, dy) = (x.wrapping_sub(self.min.x), y.wrapping_sub(self.min.y));
        if dx < 0 || dy < 0 || dx as usize >= self.width || dy as usize >= self.height {
            None
        } else {
            Some(dy as usize * self.width + dx as usize)
        }
    }
}

/// The most cells one submap grid may hold: 2²⁶, a 8,192-cell square (410 m at 5 cm),
/// 400 MB with its mirror. A submap holds a few metres of travel and the returns around
/// them; a grid that would grow past this spans a pose that came from nowhere.
pub const MAX_GRID_CELLS: i128 = 1 << 26;

/// A submap's dense probability grid, in the local SLAM frame: cell `(i, j)` spans
/// `[i·r, (i+1)·r) × [j·r, (j+1)·r)` metres.
#[derive(Clone, Debug)]
pub struct ProbabilityGrid {
    resolution: f64,
    limits: CellLimits,
    cells: Vec<u16>,
    marked: Vec<u32>,
    /// `value_to_probability` of every cell, while the grid is active.
    mirror: Option<Vec<f32>>,
}

impl ProbabilityGrid {
    /// An empty grid of cell size `resolution` (metres).
    pub fn new(resolution: f64) -> Self {
        assert!(resolution > 0.0 && resolution.is_finite(), "grid resolution must be positive");
        Self {
            resolution,
            limits: CellLimits { min: CellIndex::new(0, 0), width: 0, height: 0 },
            cells: Vec::new(),
            marked: Vec::new(),
            mirror: Some(Vec::new()),
        }
    }

    /// Cell size, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The cells held.
    pub fn limits(&self) -> CellLimits {
        self.limits
    }

    /// The stored values, row-major over [`limits`](Self::limits) (`0` = unknown).
    pub fn values(&self) -> &[u16] {
        &self.cells
    }

    /// The probabilities of [`values`](Self::values) as `f32`, while the grid is active
    /// (not [frozen](Self::freeze)).
    pub fn probabilities(&self) -> Option<&[f32]> {
        self.mirror.as_deref()
    }

    /// Drops the `f32` mirror (the grid will not be matched against locally again) and
    /// crops the grid to its known cells: an unknown cell reads as one outside ([`P_MIN`]),
    /// so every lookup is unchanged, and a finished submap no longer carries the margin
    /// it grew with (64 cells a side: a small room's submap was mostly margin).
    pub fn freeze(&mut self) {
        self.mirror = None;
        let l = self.limits;
        let (mut lo, mut hi) = ((usize::MAX, usize::MAX), (0, 0));
        for (row, cells) in self.cells.chunks_exact(l.width.max(1)).enumerate() {
            if let (Some(a), Some(b)) = (cells.iter().position(|&v| v != 0), cells.iter().rposition(|&v| v != 0)) {
                (lo, hi) = ((lo.0.min(a), lo.1.min(row)), (hi.0.max(b), hi.1.max(row)));
            }
        }
        if lo.0 == usize::MAX {
            self.cells = Vec::new();
            self.limits = CellLimits { min: l.min, width: 0, height: 0 };
        } else {
            let (w, h) = (hi.0 - lo.0 + 1, hi.1 - lo.1 + 1);
            let mut cells = Vec::with_capacity(w * h);
            for row in lo.1..=hi.1 {
                cells.extend_from_slice(&self.cells[row * l.width + lo.0..row * l.width + hi.0 + 1]);
            }
            self.cells = cells;
            let min = CellIndex::new(l.min.x + lo.0 as i64, l.min.y + lo.1 as i64);
            self.limits = CellLimits { min, width: w, height: h };
        }
        self.marked = Vec::new();
    }

    /// A frozen grid of `cells` over `limits` (row-major, as [`values`](Self::values)
    /// gives them): a finished field unpacked (`packed_grid.rs`).
    pub(crate) fn frozen(resolution: f64, limits: CellLimits, cells: Vec<u16>) -> Self {
        assert_eq!(cells.len(), limits.width * limits.height, "cells fill the limits");
        Self { resolution, limits, cells, marked: Vec::new(), mirror: None }
    }

    /// The probability of cell `(x, y)`; [`P_MIN`] when unknown or outside.
    #[inline]
    pub fn probability(&self, x: i64, y: i64) -> f32 {
        match self.limits.index(x, y) {
            Some(i) => value_to_probability(self.cells[i]),
            None => P_MIN,
        }
    }

    /// The index in [`values`](Self::values) of cell `(x, y)` when the `w × h` block of
    /// cells from it lies wholly inside the grid, so a matcher may read the block's rows
    /// as slices with no per-cell bounds check.
    #[inline]
    pub fn block_start(&self, x: i64, y: i64, w: usize, h: usize) -> Option<usize> {
        let l = self.limits;
        let (dx, dy) = (x.wrapping_sub(l.min.x), y.wrapping_sub(l.min.y));
        (dx >= 0 && dy >= 0 && (dx as usize).checked_add(w)? <= l.width && (dy as usize).checked_add(h)? <= l.height)
            .then(|| dy as usize * l.width + dx as usize)
    }

    /// True when cell `(x, y)` was ever updated.
    pub fn is_known(&self, x: i64, y: i64) -> bool {
        self.limits.index(x, y).is_some_and(|i| self.cells[i] != 0)
    }

    /// Bytes the grid holds: its cells, their `f32` mirror while active, and the marks'
    /// scratch.
    pub fn bytes(&self) -> usize {
        let mirror = self.mirror.as_ref().map_or(0, |m| m.capacity() * std::mem::size_of::<f32>());
        self.cells.capacity() * std::mem::size_of::<u16>()
            + mirror
            + self.marked.capacity() * std::mem::size_of::<u32>()
    }

    /// Observed cells.
    pub fn known_cells(&self) -> usize {
        self.cells.iter().filter(|&&v| v != 0).count()
    }

    /// Continuous cell coordinates of a point (cell `(i, j)` spans `[i, i+1) × [j, j+1)`).
    #[inline]
    pub fn to_cell_units(&self, p: Point2) -> (f64, f64) {
        (p.x / self.resolution, p.y / self.resolution)
    }

    /// Grows the grid to hold the box `[lo, hi]` (cells), with a margin, keeping its data.
    /// A grid that would pass [`MAX_GRID_CELLS`] is not grown (false): the cells outside
    /// it are left out of every update, which skips cells outside the grid.
    fn grow_to(&mut self, lo: (i64, i64), hi: (i64, i64)) -> bool {
        let l = self.limits;
        let (max_x, max_y) = (l.min.x + l.width as i64 - 1, l.min.y + l.height as i64 - 1);
        if l.width > 0 && lo.0 >= l.min.x && lo.1 >= l.min.y && hi.0 <= max_x && hi.1 <= max_y {
            return true;
        }
        // In i128: a box from a pose 10¹⁷ m away overflows i64 arithmetic.
        const MARGIN: i128 = 64;
        let (lo, hi) = ((i128::from(lo.0), i128::from(lo.1)), (i128::from(hi.0), i128::from(hi.1)));
        let (min_x, min_y, max_x, max_y) =
            (i128::from(l.min.x), i128::from(l.min.y), i128::from(max_x), i128::from(max_y));
        let (nx0, ny0, nx1, ny1) = if l.width == 0 {
            (lo.0 - MARGIN, lo.1 - MARGIN, hi.0 + MARGIN, hi.1 + MARGIN)
        } else {
            (
                if lo.0 < min_x { lo.0 - MARGIN } else { min_x },
                if lo.1 < min_y { lo.1 - MARGIN } else { min_y },
                if hi.0 > max_x { hi.0 + MARGIN } else { max_x },
                if hi.1 > max_y { hi.1 + MARGIN } else { max_y },
            )
        };
        let (w, h) = (nx1 - nx0 + 1, ny1 - ny0 + 1);
        let fits = |v: i128| i64::try_from(v).is_ok();
        if w * h > MAX_GRID_CELLS || ![nx0, ny0, nx1, ny1].into_iter().all(fits) {
            return false;
        }
        let (nx0, ny0) = (nx0 as i64, ny0 as i64);
        let (w, h) = (w as usize, h as usize);
        let mut cells = vec![0u16; w * h];
        for row in 0..l.height {
            let src = &self.cells[row * l.width..(row + 1) * l.width];
            let y = l.min.y + row as i64;
            let start = (y - ny0) as usize * w + (l.min.x - nx0) as usize;
            cells[start..start + l.width].copy_from_slice(src);
        }
        if let Some(old) = &self.mirror {
            let mut mirror = vec![P_MIN; w * h];
            for row in 0..l.height {
                let y = l.min.y + row as i64;
                let start = (y - ny0) as usize * w + (l.min.x - nx0) as usize;
                mirror[start..start + l.width].copy_from_slice(&old[row * l.width..(row + 1) * l.width]);
            }
            self.mirror = Some(mirror);
        }
        self.cells = cells;
        self.limits = CellLimits { min: CellIndex::new(nx0, ny0), width: w, height: h };
        true
    }

    /// Grows the grid (with a margin) to hold every cell of the box `[lo, hi]`.
    pub(crate) fn ensure_cells(&mut self, lo: (i64, i64), hi: (i64, i64)) {
        let _ = self.grow_to(lo, hi);
    }

    /// The stored value of cell `(x, y)`; `0` when unknown or outside.
    #[inline]
    pub fn value(&self, x: i64, y: i64) -> u16 {
        self.limits.index(x, y).map_or(0, |i| self.cells[i] & !MARK)
    }

    /// Sets the stored value of cell `(x, y)` (inside the grid: see
    /// [`ensure_cells`](Self::ensure_cells)), and its mirror.
    #[inline]
    pub(crate) fn set_value(&mut self, x: i64, y: i64, v: u16) {
        if let Some(i) = self.limits.index(x, y) {
            self.cells[i] = v;
            if let Some(m) = &mut self.mirror {
                m[i] = value_to_probability(v);
            }
        }
    }

    #[inline]
    fn apply(&mut self, x: i64, y: i64, table: &UpdateTable, crossings: &mut Option<&mut Vec<Crossing>>) {
        if let Some(i) = self.limits.index(x, y) {
            let v = self.cells[i];
            if v & MARK == 0 {
                let new = table.table[v as usize];
                self.cells[i] = new;
                self.marked.push(i as u32);
                if let Some(out) = crossings {
                    let occupied = |v: u16| v & !MARK != 0 && value_to_probability(v) > 0.5;
                    if occupied(v) != occupied(new) {
                        out.push(Crossing { cell: CellIndex::new(x, y), occupied: occupied(new) });
                    }
                }
            }
        }
    }

    /// Inserts one scan: `hits` (returns) become more likely occupied, the cells crossed by
    /// the rays from `origin` to every hit and to every `miss` (a free ray without a return)
    /// more likely free. Hits are applied first, so a cell holding a return is never also
    /// cleared by a neighbouring ray in the same scan; every cell changes at most once.
    pub fn insert(
        &mut self,
        origin: Point2,
        hits: &[Point2],
        misses: &[Point2],
        hit: &UpdateTable,
        miss: &UpdateTable,
    ) {
        self.insert_with(origin, hits, misses, hit, miss, None);
    }

    /// [`insert`](Self::insert), and the cells whose occupancy (probability above ½)
    /// changed appended to `crossings`.
    pub fn insert_tracking(
        &mut self,
        origin: Point2,
        hits: &[Point2],
        misses: &[Point2],
        hit: &UpdateTable,
        miss: &UpdateTable,
        crossings: &mut Vec<Crossing>,
    ) {
        self.insert_with(origin, hits, misses, hit, miss, Some(crossings));
    }

    fn insert_with(
        &mut self,
        origin: Point2,
        hits: &[Point2],
        misses: &[Point2],
        hit: &UpdateTable,
        miss: &UpdateTable,
        mut crossings: Option<&mut Vec<Crossing>>,
    ) {
        let o = self.to_cell_units(origin);
        let start = (floor_i64(o.0), floor_i64(o.1));
        let (mut lo, mut hi) = (start, start);
        for p in hits.iter().chain(misses) {
            let c = self.to_cell_units(*p);
            let (cx, cy) = (floor_i64(c.0), floor_i64(c.1));
            lo = (lo.0.min(cx), lo.1.min(cy));
            hi = (hi.0.max(cx), hi.1.max(cy));
        }
        let _ = self.grow_to(lo, hi);
        for p in hits {
            let c = self.to_cell_units(*p);
            self.apply(floor_i64(c.0), floor_i64(c.1), hit, &mut crossings);
        }
        for (p, is_hit) in hits.iter().map(|p| (p, true)).chain(misses.iter().map(|p| (p, false))) {
            let ray = CellRay::new(o, self.to_cell_units(*p));
            let n = ray.len_cells();
            for (k, c) in ray.enumerate() {
                if is_hit && k as u64 + 1 == n {
                    break;
                }
                self.apply(c.x, c.y, miss, &mut crossings);
            }
        }
        for i in self.marked.drain(..) {
            let v = self.cells[i as usize] & !MARK;
            self.cells[i as usize] = v;
            if let Some(m) = &mut self.mirror {
                m[i as usize] = value_to_probability(v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip_probabilities() {
        for p in [0.1f32, 0.25, 0.5, 0.75, 0.9] {
            assert!((value_to_probability(probability_to_value(p)) - p).abs() < 1e-4);
        }
        assert_eq!(value_to_probability(0), P_MIN);
    }

    #[test]
    fn floor_i64_is_floor_everywhere() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.9999,
            -2.0001,
            1e18,
            -1e18,
            1e300,
            -1e300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn blocks_are_inside_or_refused() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(1.0, 1.0)], &[], &hit, &miss);
        let l = g.limits();
        let (x1, y1) = (l.min.x + l.width as i64, l.min.y + l.height as i64);
        assert_eq!(g.block_start(l.min.x, l.min.y, l.width, l.height), Some(0));
        assert_eq!(g.block_start(x1 - 3, y1 - 2, 3, 2), Some((l.height - 2) * l.width + l.width - 3));
        assert_eq!(g.block_start(x1 - 2, y1 - 2, 3, 2), None);
        assert_eq!(g.block_start(l.min.x - 1, l.min.y, 3, 2), None);
        assert_eq!(g.block_start(i64::MAX, i64::MIN, 3, 2), None);
        let i = g.block_start(10, 10, 1, 1).unwrap();
        assert_eq!(value_to_probability(g.values()[i]), g.probability(10, 10));
    }

    #[test]
    fn the_mirror_follows_every_update_and_growth_until_frozen() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        let check = |g: &ProbabilityGrid| {
            let m = g.probabilities().expect("active");
            assert_eq!(m.len(), g.values().len());
            assert!(g.values().iter().zip(m).all(|(&v, &p)| value_to_probability(v) == p));
        };
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(1.0, 1.0)], &[], &hit, &miss);
        check(&g);
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(-30.0, -20.0)], &[Point2::new(25.0, 40.0)], &hit, &miss);
        g.insert(Point2::new(0.5, 0.0), &[Point2::new(1.0, 1.0)], &[Point2::new(-3.0, 2.0)], &hit, &miss);
        check(&g);
        g.freeze();
        assert!(g.probabilities().is_none());
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(2.0, 1.0)], &[], &hit, &miss);
        assert!(g.probabilities().is_none());
    }

    #[test]
    fn freezing_crops_to_the_known_cells_and_keeps_every_lookup() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(1.0, 1.0), Point2::new(-2.0, 0.5)], &[], &hit, &miss);
        g.insert(Point2::new(0.3, 0.0), &[], &[Point2::new(0.3, -1.5)], &hit, &miss);
        let before = g.clone();
        g.freeze();
        let (a, b) = (before.limits(), g.limits());
        assert!(b.width * b.height < a.width * a.height / 4, "{a:?} → {b:?}");
        assert_eq!(g.known_cells(), before.known_cells());
        for y in a.min.y - 2..a.min.y + a.height as i64 + 2 {
            for x in a.min.x - 2..a.min.x + a.width as i64 + 2 {
                assert_eq!(g.value(x, y), before.value(x, y), "({x}, {y})");
                assert_eq!(g.probability(x, y), before.probability(x, y), "({x}, {y})");
            }
        }
        let mut empty = ProbabilityGrid::new(0.1);
        empty.freeze();
        assert_eq!((empty.limits().width, empty.probability(0, 0)), (0, P_MIN));
    }

    #[test]
    fn hits_rise_misses_fall_and_each_cell_changes_once_per_scan() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.05);
        let origin = Point2::new(0.0, 0.0);
        // Two returns in the same cell: one update.
        g.insert(origin, &[Point2::new(1.01, 0.01), Point2::new(1.02, 0.02)], &[], &hit, &miss);
        assert!((g.probability(20, 0) - 0.55).abs() < 1e-3);
        assert!((g.probability(10, 0) - 0.49).abs() < 1e-3);
        assert!(!g.is_known(-5, 3));
        for _ in 0..120 {
            g.insert(origin, &[Point2::new(1.01, 0.01)], &[], &hit, &miss);
        }
        assert!((g.probability(20, 0) - P_MAX).abs() < 1e-3);
        assert!((g.probability(10, 0) - P_MIN).abs() < 1e-3);
    }

    #[test]
    fn the_grid_grows_in_every_direction_and_keeps_its_data() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(1.0, 1.0)], &[], &hit, &miss);
        let before = g.probability(10, 10);
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(-30.0, -20.0)], &[Point2::new(25.0, 40.0)], &hit, &miss);
        assert_eq!(g.probability(10, 10), before);
        assert!(g.probability(-300, -200) > 0.5);
        assert!(g.is_known(201, 322));
        assert!(g.probability(201, 322) < 0.5);
    }

    #[test]
    fn a_grid_never_grows_past_its_cap() {
        let mut g = ProbabilityGrid::new(0.05);
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        g.insert(Point2::new(0.0, 0.0), &[Point2::new(1.0, 0.0)], &[], &hit, &miss);
        let (w, h) = (g.limits().width, g.limits().height);
        // 10¹⁷ m away (2 · 10¹⁸ cells): not grown, nothing written, no overflow.
        g.insert(Point2::new(1e17, 0.0), &[Point2::new(1e17 + 1.0, 0.0)], &[], &hit, &miss);
        assert_eq!((g.limits().width, g.limits().height), (w, h));
        // Near i64's end too.
        g.insert(Point2::new(-4e17, 4e17), &[Point2::new(-4e17, 4e17 + 1.0)], &[], &hit, &miss);
        assert_eq!((g.limits().width, g.limits().height), (w, h));
        assert!(g.known_cells() > 0 && g.bytes() < 1 << 20);
    }
}
