//! The precomputed grids of branch-and-bound scan matching (Hess et al. 2016, §V-C).
//!
//! Level `h` holds, at cell `(x, y)`, the largest probability over the `2^h × 2^h` block
//! of cells `[x, x + 2^h) × [y, y + 2^h)`. A search node at level `h` stands for every
//! integer translation in such a block of offsets, so summing level `h` at the scan's cells
//! bounds from above the score of every translation the node stands for (the paper's
//! equation (15)); at level 0 the bound is the score itself.
//!
//! Values are bytes: `0` is `P_MIN`, `255` is `P_MAX`, and a probability is rounded *up*
//! to the next byte, so a byte score is never below the exact score and the search, done
//! wholly in bytes, cannot lose a match the exact score would have accepted.
//!
//! Storage: each level spans the grid plus `2^h` cells below and one cell above on each
//! axis — every cell outside that span is exactly `0` at that level, and the border
//! cells are `0` too — so a lookup clamps its coordinates into the span and reads the true
//! value without a branch and without padding the grid by the whole search window. For a
//! 400 × 400 grid and 7 levels this is about 1.23 MB.

use crate::grid::CellIndex;
use crate::slam::grid::ProbabilityGrid;

const SOURCE_MAX: u32 = 32767;

/// A stored grid value (`0` unknown, `1..=32767` linear in `[P_MIN, P_MAX]`) as a byte,
/// rounded up: `ceil((v − 1) · 255 / 32766)`, exactly, in integers.
#[inline]
fn value_to_byte(v: u16) -> u8 {
    let v = u32::from(v & 0x7fff).max(1) - 1;
    ((v * 255).div_ceil(SOURCE_MAX - 1)) as u8
}

/// One level: a `width × height` byte array whose cell `(0, 0)` is the grid cell
/// `(min.x − pad, min.y − pad)`.
#[derive(Clone, Debug)]
pub(super) struct Level {
    /// Cells below the grid's first cell on each axis (`2^h`).
    pub(super) pad: i32,
    pub(super) width: i32,
    pub(super) height: i32,
    pub(super) cells: Vec<u8>,
}

impl Level {
    /// The value at `(x, y)`, relative to the grid's first cell; any cell outside the
    /// stored span reads as its nearest border cell, which is `0`, the true value there.
    #[inline]
    pub(super) fn get(&self, x: i32, y: i32) -> u8 {
        let ix = (x.saturating_add(self.pad)).clamp(0, self.width - 1);
        let iy = (y.saturating_add(self.pad)).clamp(0, self.height - 1);
        self.cells[iy as usize * self.width as usize + ix as usize]
    }

    /// The sum over `cells` (relative to the grid's first cell) shifted by `(dx, dy)`:
    /// the hot loop of the search. Stops early once the sum so far plus 255 for every
    /// point left cannot exceed `floor`, and returns that figure: still an upper bound of
    /// the sum, and one the caller discards. A result above `floor` is the exact sum.
    #[inline]
    pub(super) fn sum(&self, cells: &[[i32; 2]], dx: i32, dy: i32, floor: i64) -> u32 {
        const CHUNK: usize = 16;
        let (ox, oy) = (dx + self.pad, dy + self.pad);
        let (xmax, ymax, w) = (self.width - 1, self.height - 1, self.width as usize);
        let data = &self.cells[..];
        let mut sum = 0u32;
        let mut left = 255 * cells.len() as i64;
        for chunk in cells.chunks(CHUNK) {
            for &[x, y] in chunk {
                let ix = (x + ox).clamp(0, xmax) as usize;
                let iy = (y + oy).clamp(0, ymax) as usize;
                sum += u32::from(data[iy * w + ix]);
            }
            left -= 255 * chunk.len() as i64;
            if i64::from(sum) + left <= floor {
                return (i64::from(sum) + left) as u32;
            }
        }
        sum
    }

    /// The four sums of the quadrants of a node: [`sum`](Self::sum) at `(dx, dy)`,
    /// `(dx + s, dy)`, `(dx, dy + s)` and `(dx + s, dy + s)`, in one pass over the points
    /// (each point's clamped rows and columns serve all four). Stops early once none of the
    /// four can exceed `floor`, returning upper bounds as [`sum`](Self::sum) does.
    #[inline]
    pub(super) fn sum4(&self, cells: &[[i32; 2]], dx: i32, dy: i32, s: i32, floor: i64) -> [u32; 4] {
        const CHUNK: usize = 16;
        let (ox, oy) = (dx + self.pad, dy + self.pad);
        let (xmax, ymax, w) = (self.width - 1, self.height - 1, self.width as usize);
        let data = &self.cells[..];
        let mut sums = [0u32; 4];
        let mut left = 255 * cells.len() as i64;
        for chunk in cells.chunks(CHUNK) {
            for &[x, y] in chunk {
                let x0 = (x + ox).clamp(0, xmax) as usize;
                let x1 = (x + ox + s).clamp(0, xmax) as usize;
                let r0 = (y + oy).clamp(0, ymax) as usize * w;
                let r1 = (y + oy + s).clamp(0, ymax) as usize * w;
                sums[0] += u32::from(data[r0 + x0]);
                sums[1] += u32::from(data[r0 + x1]);
                sums[2] += u32::from(data[r1 + x0]);
                sums[3] += u32::from(data[r1 + x1]);
            }
            left -= 255 * chunk.len() as i64;
            let top = sums.iter().copied().max().unwrap_or(0);
            if i64::from(top) + left <= floor {
                return sums.map(|v| (i64::from(v) + left) as u32);
            }
        }
        sums
    }
}

/// Precomputed max-filtered grids of one submap, levels `0..depth` (level `h`: each cell
/// holds the max probability over the `2^h × 2^h` block starting at it), stored as bytes
/// (`0..=255` mapping `[P_MIN, P_MAX]`, rounded up so the bound stays an upper bound).
///
/// Built once per finished submap; every loop-closure search against the submap reads it.
/// Level 0 is the probability grid itself at byte precision, which is what the search
/// scores its final candidates with.
#[derive(Clone, Debug)]
pub struct PrecomputedGrids {
    resolution: f64,
    min: CellIndex,
    width: i32,
    height: i32,
    levels: Vec<Level>,
}

impl PrecomputedGrids {
    /// The `depth` levels of `grid` (at least one; level `depth − 1` is the coarsest).
    ///
    /// Level `h` is built from level `h − 1` by the doubling identity
    /// `L_h(x, y) = max L_{h−1}` over `(x, y)`, `(x + s, y)`, `(x, y + s)`, `(x + s, y + s)`
    /// with `s = 2^(h−1)`, applied one axis at a time: linear time per level.
    pub fn new(grid: &ProbabilityGrid, depth: usize) -> Self {
        assert!((1..=16).contains(&depth), "precomputed grid depth must be 1..=16, got {depth}");
        let limits = grid.limits();
        let (width, height) =
            (i32::try_from(limits.width).expect("grid too wide"), i32::try_from(limits.height).expect("grid too tall"));
        let values = grid.values();
        let mut level0 = Level { pad: 1, width: width + 2, height: height + 2, cells: Vec::new() };
        level0.cells = vec![0u8; level0.width as usize * level0.height as usize];
        for row in 0..height as usize {
            let src = &values[row * width as usize..(row + 1) * width as usize];
            let start = (row + 1) * level0.width as usize + 1;
            for (dst, &v) in level0.cells[start..start + width as usize].iter_mut().zip(src) {
                *dst = value_to_byte(v);
            }
        }
        let mut levels = vec![level0];
        for h in 1..depth {
            let next = coarser(levels.last().expect("level 0 exists"), width, height, h);
            levels.push(next);
        }
        Self { resolution: grid.resolution(), min: limits.min, width, height, levels }
    }

    /// Heap and inline bytes held: what a submap's loop-closure data costs.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.levels.iter().map(|l| l.cells.capacity() + std::mem::size_of::<Level>()).sum::<usize>()
    }

    /// The number of levels.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// Cell size of the source grid, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The source grid's first cell.
    pub(super) fn min(&self) -> CellIndex {
        self.min
    }

    /// The source grid's size in cells.
    pub(super) fn size(&self) -> (i32, i32) {
        (self.width, self.height)
    }

    /// Level `h`.
    pub(super) fn level(&self, h: usize) -> &Level {
        &self.levels[h]
    }

    /// Level `h` at grid cell `(x, y)` (absolute cell coordinates), as a byte.
    pub fn value(&self, h: usize, x: i64, y: i64) -> u8 {
        let rel = |v: i64, m: i64| (v - m).clamp(i32::MIN as i64 / 2, i32::MAX as i64 / 2) as i32;
        self.levels[h].get(rel(x, self.min.x), rel(y, self.min.y))
    }
}

/// Level `h` from level `h − 1` (`prev`), over the span `[−2^h, size]` on each axis.
///
/// Both passes are a maximum of two shifted rows, slice against slice (which the compiler
/// turns into vector instructions): each row of `prev` is first laid into a zeroed row of
/// the new span, so the cells beyond what `prev` stores read as the `0` they are.
fn coarser(prev: &Level, width: i32, height: i32, h: usize) -> Level {
    let s = 1usize << (h - 1);
    let pad = 1i32 << h;
    let (w, ht) = ((width + pad + 1) as usize, (height + pad + 1) as usize);
    let (pw, ph) = (prev.width as usize, prev.height as usize);
    // Column (and row) `j` of `prev` is column (row) `j + shift` of the new span.
    let shift = (pad - prev.pad) as usize;
    // Along x first, over the previous level's rows.
    let mut ext = vec![0u8; w + s];
    let mut tmp = vec![0u8; w * ph];
    for (src, out) in prev.cells.chunks_exact(pw).zip(tmp.chunks_exact_mut(w)) {
        ext[shift..shift + pw].copy_from_slice(src);
        for ((o, &a), &b) in out.iter_mut().zip(&ext[..w]).zip(&ext[s..s + w]) {
            *o = a.max(b);
        }
    }
    // Then along y: row `r` of the new span is the maximum of rows `r` and `r + s`.
    let zero = vec![0u8; w];
    let tmp_row = |r: usize| match r.checked_sub(shift) {
        Some(k) if k < ph => &tmp[k * w..(k + 1) * w],
        _ => &zero[..],
    };
    let mut cells = vec![0u8; w * ht];
    for (row, out) in cells.chunks_exact_mut(w).enumerate() {
        for ((o, &a), &b) in out.iter_mut().zip(tmp_row(row)).zip(tmp_row(row + s)) {
            *o = a.max(b);
        }
    }
    Level { pad, width: w as i32, height: ht as i32, cells }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::sim::SplitMix64;
    use crate::slam::grid::{value_to_probability, UpdateTable, P_MAX, P_MIN};

    fn random_grid(seed: u64, n: usize) -> ProbabilityGrid {
        let mut rng = SplitMix64::new(seed);
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        for _ in 0..n {
            let o = Point2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
            let hits: Vec<_> = (0..5).map(|_| Point2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0))).collect();
            g.insert(o, &hits, &[], &hit, &miss);
        }
        g
    }

    #[test]
    fn bytes_round_up_and_span_the_probability_range() {
        assert_eq!(value_to_byte(0), 0);
        assert_eq!(value_to_byte(1), 0);
        assert_eq!(value_to_byte(32767), 255);
        for v in (1..=32767u16).step_by(97) {
            let b = value_to_byte(v);
            let p_byte = P_MIN + (P_MAX - P_MIN) * f32::from(b) / 255.0;
            assert!(p_byte >= value_to_probability(v) - 1e-6, "v={v}");
            assert!(p_byte - value_to_probability(v) < (P_MAX - P_MIN) / 255.0 + 1e-6, "v={v}");
        }
    }

    #[test]
    fn every_level_is_the_block_maximum_of_level_zero_everywhere() {
        for seed in 0..4 {
            let g = random_grid(seed, 40);
            let pre = PrecomputedGrids::new(&g, 4);
            let l = g.limits();
            let (x0, y0) = (l.min.x, l.min.y);
            let (x1, y1) = (x0 + l.width as i64, y0 + l.height as i64);
            for h in 0..4 {
                let b = 1i64 << h;
                for y in y0 - 12..y1 + 12 {
                    for x in x0 - 12..x1 + 12 {
                        let mut m = 0u8;
                        for yy in y..y + b {
                            for xx in x..x + b {
                                let v = l.index(xx, yy).map_or(0, |i| value_to_byte(g.values()[i]));
                                m = m.max(v);
                            }
                        }
                        assert_eq!(pre.value(h, x, y), m, "seed {seed} level {h} cell ({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn an_empty_grid_reads_zero() {
        let pre = PrecomputedGrids::new(&ProbabilityGrid::new(0.05), 3);
        assert_eq!(pre.depth(), 3);
        assert_eq!(pre.value(2, 5, -7), 0);
    }
}
