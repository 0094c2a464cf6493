//! One tile of the map: the blocks of every layer over the same `TILE_SIZE × TILE_SIZE`
//! cells, and the update mark they share.
//!
//! The map is a set of layers on one tile key space (grid_map's "one geometry, many
//! layers"; OctoMap keeps one value per node instead and needs a new tree class per kind
//! of value). The occupancy block is always there: every range observation writes it.
//! Other layers — a semantic class distribution, a dynamic-object layer, the visit counter
//! of the tests — are the tile's [`ExtraLayers`], chosen by the map's type parameter, so
//! a map that does not carry them pays nothing, and their visitors are monomorphised with
//! the walk (no dynamic dispatch per cell). An extra layer whose values are costly
//! allocates its block on first write (an `Option<Box<…>>` inside its `ExtraLayers`), so
//! tiles it never touched cost one pointer.
//!
//! One tile-key lookup gives every layer's block: a walk that feeds two layers does not
//! hash twice.

use super::{LogOddsTable, Tile, UpdateMark, TILE_CELLS};

/// The blocks of a map's layers beyond occupancy, one value per tile.
///
/// `()` is the map with occupancy only.
pub trait ExtraLayers {
    /// The blocks of a tile that no layer has written yet.
    fn empty() -> Self;
}

impl ExtraLayers for () {
    #[inline(always)]
    fn empty() -> Self {}
}

/// One tile: the shared update mark, the occupancy block, and the extra layers' blocks.
pub struct MapTile<L = ()> {
    /// Which cells the current observation has already updated (all layers).
    mark: UpdateMark,
    /// Occupancy log-odds per cell, row-major; NaN for a cell never observed.
    log_odds: [f32; TILE_CELLS],
    /// The extra layers' blocks.
    layers: L,
}

impl<L: ExtraLayers> Tile for MapTile<L> {
    fn empty() -> Self {
        Self { mark: UpdateMark::default(), log_odds: [f32::NAN; TILE_CELLS], layers: L::empty() }
    }
}

/// A tile a ray walk can mark: the walk needs the mark and nothing else of the tile.
pub trait MarkedTile: Tile {
    /// The tile's update mark.
    fn mark(&mut self) -> &mut UpdateMark;
}

impl<L: ExtraLayers> MarkedTile for MapTile<L> {
    #[inline(always)]
    fn mark(&mut self) -> &mut UpdateMark {
        &mut self.mark
    }
}

impl<L> MapTile<L> {
    /// The stored occupancy log-odds of the cell at `offset`, `None` if never observed.
    #[inline]
    pub fn log_odds(&self, offset: usize) -> Option<f32> {
        let v = self.log_odds[offset];
        (!v.is_nan()).then_some(v)
    }

    /// One Bayesian log-odds update of the cell at `offset` by `delta`, kept only when
    /// `fresh` (the first update of the cell in this observation). Branch-free: the update
    /// is always computed and the old value kept by a select.
    #[inline(always)]
    pub fn update_log_odds(&mut self, offset: usize, delta: f32, table: &LogOddsTable, fresh: bool) {
        let v = self.log_odds[offset];
        let base = if v.is_nan() { table.prior } else { v };
        let updated = table.update(base, delta);
        self.log_odds[offset] = if fresh { updated } else { v };
    }

    /// The extra layers' blocks.
    pub fn layers(&self) -> &L {
        &self.layers
    }

    /// The extra layers' blocks, for a layer's visitor to write.
    #[inline(always)]
    pub fn layers_mut(&mut self) -> &mut L {
        &mut self.layers
    }
}
