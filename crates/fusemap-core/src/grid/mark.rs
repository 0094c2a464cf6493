//! The per-tile "already updated in this observation" mark, shared by every layer of a
//! tile.
//!
//! Within one observation each cell is updated at most once (OctoMap `computeUpdate`;
//! Cartographer `ProbabilityGridRangeDataInserter2D`'s update marker). The mark is one bit
//! per cell, tagged with the 64-bit number of the observation that set it: a tile first
//! touched by a newer observation clears its bits. The tag cannot wrap (2^64
//! observations), unlike the 4-bit counter that made Bonxai drop 7.6 % of its updates
//! (Bonxai PR #61).
//!
//! The mark belongs to the tile, not to a layer: when several layers are written from one
//! walk (occupancy and a semantic or dynamic layer), they all agree on which cells this
//! observation already touched, and the bitset is reset once per tile, not once per layer.

use super::TILE_CELLS;

/// Bits per word of the mark.
const WORD_BITS: usize = u64::BITS as usize;

/// One bit per cell of a tile, valid for one observation.
#[derive(Clone, Debug)]
pub struct UpdateMark {
    /// The observation that `bits` belongs to (0: none yet; observations start at 1).
    observation: u64,
    /// Cells already updated by `observation`.
    bits: [u64; TILE_CELLS / WORD_BITS],
}

impl Default for UpdateMark {
    fn default() -> Self {
        Self { observation: 0, bits: [0; TILE_CELLS / WORD_BITS] }
    }
}

impl UpdateMark {
    /// Starts observation `obs` on this tile if it is not the current one.
    #[inline(always)]
    pub fn begin(&mut self, obs: u64) {
        if self.observation != obs {
            self.observation = obs;
            self.bits = [0; TILE_CELLS / WORD_BITS];
        }
    }

    /// Marks the cell at `offset` and returns whether it was unmarked before (the first
    /// visit of this cell in the current observation). Branch-free: whether a cell was
    /// already updated follows no pattern a branch predictor could learn.
    #[inline(always)]
    pub fn test_and_set(&mut self, offset: usize) -> bool {
        let word = &mut self.bits[offset / WORD_BITS];
        let bit = 1u64 << (offset % WORD_BITS);
        let fresh = *word & bit == 0;
        *word |= bit;
        fresh
    }

    /// Whether the cell at `offset` is marked in observation `obs`.
    pub fn is_marked(&self, obs: u64, offset: usize) -> bool {
        self.observation == obs && self.bits[offset / WORD_BITS] & (1u64 << (offset % WORD_BITS)) != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_observation_clears_the_bits() {
        let mut m = UpdateMark::default();
        m.begin(1);
        assert!(m.test_and_set(5));
        assert!(!m.test_and_set(5));
        assert!(m.is_marked(1, 5));
        assert!(!m.is_marked(1, 6));
        // The same observation again keeps the bits.
        m.begin(1);
        assert!(!m.test_and_set(5));
        m.begin(2);
        assert!(!m.is_marked(2, 5));
        assert!(m.test_and_set(5));
        assert!(m.test_and_set(TILE_CELLS - 1));
        assert!(!m.test_and_set(TILE_CELLS - 1));
    }
}
