//! The maps' share of the memory budget: `[limits] memory_mib` (and the older cap in cells,
//! `map_cells`) turned into the number of tiles each map may allocate.
//!
//! A tile's cost is counted in bytes with every layer it can come to carry: the occupancy
//! block and its update mark, the semantic counts (4 bytes a class a cell), the dynamic
//! layer (log-odds and stamp a cell), the correlation scratch, and the tile store's own
//! bookkeeping (its index, key and pointer, with the slack of growing vectors). A map whose
//! sensors include a 20-class camera pays 21 times what a lidar-only map pays a cell, and
//! a budget in cells alone let a 1 mm demo reach 7 GB while holding a few hundred million.
//!
//! Every map of one engine gets the same number of tiles, so the whole set holds to the
//! budget whichever map grows first; the tile stores refuse to allocate past it (see
//! [`TileMap`](crate::grid::TileMap)) and the engine stops the run after the observation
//! that met it.
//!
//! The rasters a map is exported as count too: the maps are written one after another
//! while all of them are held, so each tile also reserves what one map's export takes a
//! tile (the largest among the maps, [`export_bytes_per_cell`]). The tiles of a map
//! therefore always fit their export as stored; a dense raster of the observed box, which
//! also covers the cells between the tiles, is written only where the room left
//! ([`Engine::export_room`](super::Engine::export_room)) holds it.

use crate::config::LimitsConfig;
use crate::grid::{DynamicBlock, FusionLayers, GroupBlock, MapTile, TileKey, TILE_CELLS};
use std::mem::size_of;

/// The layers a map's tiles may carry, which set a tile's cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct TileLayers {
    /// Classes of the largest class table among the map's cameras (0: no semantic layer).
    pub semantic_classes: usize,
    /// The engine keeps a dynamic-object layer.
    pub dynamic: bool,
    /// Some sensors are declared correlated (the merge's scratch block).
    pub correlated: bool,
}

impl TileLayers {
    /// Bytes one tile can come to hold with these layers.
    pub fn tile_bytes(&self) -> usize {
        // The tile, and per tile in the store: the index entry (key, slot, control byte),
        // the key and the box pointer, each in a vector or table that may be twice as
        // large as what it holds.
        let store = 2 * (2 * size_of::<TileKey>() + size_of::<u32>() + 1 + size_of::<usize>());
        let semantic = TILE_CELLS * self.semantic_classes * size_of::<f32>();
        let dynamic = if self.dynamic { size_of::<DynamicBlock>() } else { 0 };
        let group = if self.correlated { size_of::<GroupBlock>() } else { 0 };
        size_of::<MapTile<FusionLayers>>() + store + semantic + dynamic + group
    }

    /// Bytes one tile of such a map takes exported.
    pub fn export_bytes(&self) -> usize {
        TILE_CELLS * export_bytes_per_cell(self.semantic_classes)
    }
}

/// Bytes a dense export of one cell takes while it is written: the raster's log-odds and
/// known flag (5), the writers' buffers (4: measured, the corridor world at 1 mm and at
/// 2.5 mm peaked 8–9 bytes a cell of raster above its tiles), and with a semantic layer
/// its best class, probability and per-class probabilities (2 + 4 + 4 a class), the
/// dynamic layer's probability (4) and their pictures' pixels (4).
pub fn export_bytes_per_cell(semantic_classes: usize) -> usize {
    let semantic = if semantic_classes > 0 { 2 + 4 + 4 * semantic_classes + 4 + 4 } else { 0 };
    5 + 4 + semantic
}

/// Which limit bounds the maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetKey {
    /// `limits.memory_mib`.
    MemoryMib,
    /// `limits.map_cells`.
    MapCells,
}

/// The tiles each map may allocate, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct MapBudget {
    pub limits: LimitsConfig,
    /// Tiles each map may hold.
    pub tiles: usize,
    /// Bytes a tile of all the maps together can hold (one tile of each map), with the
    /// largest map's export of a tile.
    pub bytes_per_tile: usize,
    /// The limit that sets `tiles`.
    pub key: BudgetKey,
}

impl MapBudget {
    /// The budget for maps whose tiles carry `layers` (one entry a map).
    pub fn new(limits: LimitsConfig, layers: &[TileLayers]) -> Self {
        let export = layers.iter().map(TileLayers::export_bytes).max().unwrap_or(0);
        let bytes_per_tile = (layers.iter().map(TileLayers::tile_bytes).sum::<usize>() + export).max(1);
        let by_memory = usize::try_from(limits.memory_bytes() / bytes_per_tile as u64).unwrap_or(usize::MAX).max(1);
        let by_cells = limits.map_tiles();
        let (tiles, key) =
            if by_memory < by_cells { (by_memory, BudgetKey::MemoryMib) } else { (by_cells, BudgetKey::MapCells) };
        Self { limits, tiles, bytes_per_tile, key }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layer_adds_to_a_tile_and_the_tightest_limit_wins() {
        let plain = TileLayers::default();
        let full = TileLayers { semantic_classes: 20, dynamic: true, correlated: true };
        let (a, b) = (plain.tile_bytes(), full.tile_bytes());
        // An occupancy tile is 4 bytes a cell and a mark; 20 classes add 80 bytes a cell.
        assert!((4 * TILE_CELLS..5 * TILE_CELLS).contains(&a), "{a}");
        assert!(b > a + 80 * TILE_CELLS + 12 * TILE_CELLS, "{b}");
        let limits = LimitsConfig { memory_mib: 64, ..Default::default() };
        let one = MapBudget::new(limits, &[plain]);
        assert_eq!(one.key, BudgetKey::MemoryMib);
        let export = plain.export_bytes();
        assert_eq!(export, 9 * TILE_CELLS);
        assert_eq!(one.tiles, (64 << 20) / (a + export));
        // Two maps share the budget; they are exported one at a time.
        assert_eq!(MapBudget::new(limits, &[plain, plain]).tiles, (64 << 20) / (2 * a + export));
        assert_eq!(full.export_bytes(), (9 + 14 + 80) * TILE_CELLS);
        // A cell cap below the memory's takes over.
        let cells = MapBudget::new(LimitsConfig { map_cells: 10 * 4096, ..limits }, &[full]);
        assert_eq!((cells.tiles, cells.key), (10, BudgetKey::MapCells));
        // Never less than one tile.
        assert_eq!(MapBudget::new(LimitsConfig { memory_mib: 1, ..limits }, &[full; 8]).tiles, 1);
    }
}
