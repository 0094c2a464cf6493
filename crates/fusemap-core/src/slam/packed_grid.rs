//! A finished submap's field, packed: what loop closure keeps of every submap of a long log.
//!
//! A finished submap is only read again when a loop-closure search picks it, and then
//! through the grid cache (`grid_cache.rs`), which unpacks it next to its branch-and-bound
//! grids. Held as plain 16-bit cells, the finished fields grew with the log: 371 MB of the
//! 1.2 GB peak of a 60-minute simulated run.
//!
//! A likelihood field is zero (unknown, read as `P_MIN`) everywhere but within 3σ of a
//! wall (`field.rs`), so it is kept as runs: the zeros counted, the cells near walls
//! copied. Unpacking is then an allocation of zeroed cells and a copy of the rest, which
//! matters because the cache unpacks a submap each time it rebuilds its grids (about
//! twenty times a submap on that run). Packing is lossless: the unpacked grid is the
//! frozen grid, cell for cell, so every search reads what it read before.

use super::grid::{CellLimits, ProbabilityGrid};

/// Zeros shorter than this stay among the copied cells: a run costs as much as this many
/// cells.
const MIN_ZERO_RUN: usize = 4;

/// A frozen [`ProbabilityGrid`], its zeros counted and its other cells copied.
#[derive(Clone, Debug)]
pub struct PackedGrid {
    resolution: f64,
    limits: CellLimits,
    /// `(zeros, copied)`: that many zero cells, then that many cells from `cells`, in
    /// row-major order; the cells after the last run are zero.
    runs: Vec<(u32, u32)>,
    /// The copied cells, in order.
    cells: Vec<u16>,
}

impl PackedGrid {
    /// Packs a frozen grid (one with no `f32` mirror and no marks).
    pub fn pack(grid: &ProbabilityGrid) -> Self {
        debug_assert!(grid.probabilities().is_none(), "only a frozen grid is packed");
        let v = grid.values();
        let (mut runs, mut cells) = (Vec::new(), Vec::new());
        let mut i = 0;
        while i < v.len() {
            let zeros = v[i..].iter().take_while(|&&c| c == 0).count();
            let start = i + zeros;
            if start == v.len() {
                break;
            }
            // Copy up to the next run of at least MIN_ZERO_RUN zeros (or the end).
            let mut end = start;
            while end < v.len() {
                let z = v[end..].iter().take(MIN_ZERO_RUN).take_while(|&&c| c == 0).count();
                if z == MIN_ZERO_RUN || end + z == v.len() {
                    break;
                }
                end += z.max(1);
            }
            // A grid holds at most 2^26 cells (`MAX_GRID_CELLS`), so the counts fit.
            runs.push((zeros as u32, (end - start) as u32));
            cells.extend_from_slice(&v[start..end]);
            i = end;
        }
        runs.shrink_to_fit();
        cells.shrink_to_fit();
        Self { resolution: grid.resolution(), limits: grid.limits(), runs, cells }
    }

    /// The grid it was packed from, cell for cell.
    pub fn unpack(&self) -> ProbabilityGrid {
        let mut out = vec![0u16; self.limits.width * self.limits.height];
        let (mut at, mut from) = (0, 0);
        for &(zeros, copied) in &self.runs {
            at += zeros as usize;
            let n = copied as usize;
            out[at..at + n].copy_from_slice(&self.cells[from..from + n]);
            (at, from) = (at + n, from + n);
        }
        ProbabilityGrid::frozen(self.resolution, self.limits, out)
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.runs.capacity() * std::mem::size_of::<(u32, u32)>()
            + self.cells.capacity() * std::mem::size_of::<u16>()
            + std::mem::size_of::<Self>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::CellIndex;
    use crate::slam::grid::UpdateTable;
    use proptest::prelude::*;

    #[test]
    fn a_field_unpacks_to_the_frozen_grid_and_packs_small() {
        let mut g = ProbabilityGrid::new(0.05);
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let hits: Vec<Point2> =
            (0..360).map(|i| (i as f64).to_radians()).map(|a| Point2::new(8.0 * a.cos(), 5.0 * a.sin())).collect();
        let mut field = ProbabilityGrid::new(0.05);
        let kernel = crate::slam::field::FieldKernel::new(0.1, 0.05);
        let mut crossings = Vec::new();
        for _ in 0..3 {
            crossings.clear();
            g.insert_tracking(Point2::new(0.0, 0.0), &hits, &[], &hit, &miss, &mut crossings);
            crate::slam::field::update(&mut field, &kernel, &crossings, |x, y| g.probability(x, y) > 0.5);
        }
        field.freeze();
        let p = PackedGrid::pack(&field);
        let u = p.unpack();
        assert_eq!((u.resolution(), u.limits(), u.values()), (field.resolution(), field.limits(), field.values()));
        assert_eq!(u.bytes(), field.bytes());
        assert!(u.probabilities().is_none());
        // An ellipse of walls in a 16 × 10 m box: the field is zero but near them.
        assert!(p.bytes() * 4 < field.bytes(), "{} packed of {}", p.bytes(), field.bytes());
        // An empty grid too.
        let mut e = ProbabilityGrid::new(0.1);
        e.freeze();
        assert_eq!(PackedGrid::pack(&e).unpack().values().len(), 0);
    }

    proptest! {
        /// Any cells, runs of zeros of every length included, come back as they went in.
        #[test]
        fn any_cells_unpack_to_themselves(cells in prop::collection::vec(prop_oneof![Just(0u16), Just(0u16), 1u16..40], 0..300), width in 1usize..20) {
            let height = cells.len() / width;
            let cells = cells[..width * height].to_vec();
            let limits = CellLimits { min: CellIndex::new(-3, 7), width, height };
            let g = ProbabilityGrid::frozen(0.05, limits, cells.clone());
            let u = PackedGrid::pack(&g).unpack();
            prop_assert_eq!(u.values(), &cells[..]);
            prop_assert_eq!(u.limits(), limits);
        }
    }
}
