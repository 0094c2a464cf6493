//! Grids: geometry, log-odds cells, sparse tiles of layers, exact ray traversal, and the
//! walk of an observation's rays that every layer shares.

mod correlated;
pub mod dynamic;
mod fused_update;
mod fusion_layers;
mod geometry;
mod layers;
pub mod logodds;
mod mark;
mod occupancy;
mod overview;
mod pass_through;
mod raster;
mod raycast;
pub mod semantic;
mod tile_waves;
mod tiles;
mod walk;

pub use correlated::{Group, GroupBlock, MergeRule};
pub use dynamic::{DynamicBlock, DynamicParams, DynamicUpdate};
pub use fused_update::FusedUpdate;
pub use fusion_layers::{FusionGrid, FusionLayers};
pub use geometry::{
    CellBox, CellIndex, GeometryError, GridGeometry, TileKey, TILE_CELLS, TILE_MASK, TILE_SHIFT, TILE_SIZE,
};
pub use layers::{ExtraLayers, MapTile, MarkedTile};
pub use logodds::{LogOddsTable, OccupancyParams, Ternary};
pub use mark::UpdateMark;
pub use occupancy::{waves_threshold, LayeredGrid, OccupancyGrid, OccupancyTile, OccupancyUpdate};
pub use overview::SparseTiles;
pub use pass_through::PassThroughParams;
pub use raster::{CellRaster, Raster};
pub use raycast::{CellRay, Step};
pub use tile_waves::{walk_observation_waves, RayFork, PARALLEL_MIN_CELLS};
pub use tiles::{Tile, TileKeyHasher, TileMap};
pub use walk::{walk_observation, CellVisitor, InsertStats, MAX_RAY_CELLS};
