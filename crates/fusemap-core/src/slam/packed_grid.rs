//! A finished submap's field, packed: what loop closure keeps of every submap of a long log.
//!
//! A finished submap is only read again when a loop-closure search picks it, and then
//! through the grid cache (`grid_cache.rs`), which unpacks it next to its branch-and-bound
//! grids. Held as plain 16-bit cells, the finished fields grew with the log: 371 MB of the
//! 1.2 GB peak of a 60-minute simulated run. Most of a field is unknown (`0`) or far from
//! any wall (`P_MIN`), long runs that LZ4 shrinks by an order of magnitude and unpacks
//! at gigabytes a second. Packing is lossless: the unpacked grid is the frozen grid, cell
//! for cell, so every search reads what it read before.

use super::grid::{CellLimits, ProbabilityGrid};

/// A frozen [`ProbabilityGrid`], its cells LZ4-compressed.
#[derive(Clone, Debug)]
pub struct PackedGrid {
    resolution: f64,
    limits: CellLimits,
    /// The cells as little-endian `u16`, LZ4 block with the size prepended.
    packed: Vec<u8>,
}

impl PackedGrid {
    /// Packs a frozen grid (one with no `f32` mirror and no marks).
    pub fn pack(grid: &ProbabilityGrid) -> Self {
        debug_assert!(grid.probabilities().is_none(), "only a frozen grid is packed");
        let bytes: Vec<u8> = grid.values().iter().flat_map(|v| v.to_le_bytes()).collect();
        let mut packed = lz4_flex::compress_prepend_size(&bytes);
        packed.shrink_to_fit();
        Self { resolution: grid.resolution(), limits: grid.limits(), packed }
    }

    /// The grid it was packed from, cell for cell.
    pub fn unpack(&self) -> ProbabilityGrid {
        // Packed here from a whole grid, so the block is always well formed.
        let bytes = lz4_flex::decompress_size_prepended(&self.packed).expect("a packed grid unpacks");
        let cells: Vec<u16> = bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect();
        ProbabilityGrid::frozen(self.resolution, self.limits, cells)
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.packed.capacity() + std::mem::size_of::<Self>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::slam::grid::UpdateTable;

    #[test]
    fn a_field_unpacks_to_the_frozen_grid_and_packs_small() {
        let mut g = ProbabilityGrid::new(0.05);
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let hits: Vec<Point2> =
            (0..360).map(|i| (i as f64).to_radians()).map(|a| Point2::new(8.0 * a.cos(), 5.0 * a.sin())).collect();
        for _ in 0..3 {
            g.insert(Point2::new(0.0, 0.0), &hits, &[], &hit, &miss);
        }
        g.freeze();
        let p = PackedGrid::pack(&g);
        let u = p.unpack();
        assert_eq!((u.resolution(), u.limits(), u.values()), (g.resolution(), g.limits(), g.values()));
        assert_eq!(u.bytes(), g.bytes());
        assert!(u.probabilities().is_none());
        // An ellipse of walls in a 16 × 10 m box: mostly free and unknown cells.
        assert!(p.bytes() * 4 < g.bytes(), "{} packed of {}", p.bytes(), g.bytes());
        // An empty grid too.
        let mut e = ProbabilityGrid::new(0.1);
        e.freeze();
        assert_eq!(PackedGrid::pack(&e).unpack().values().len(), 0);
    }
}
