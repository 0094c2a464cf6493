//! Grids: geometry, log-odds cells, sparse tiles, exact ray traversal.

mod geometry;
pub mod logodds;
mod occupancy;
mod raster;
mod raycast;
mod tiles;

pub use geometry::{
    CellBox, CellIndex, GeometryError, GridGeometry, TileKey, TILE_CELLS, TILE_MASK, TILE_SHIFT, TILE_SIZE,
};
pub use logodds::{LogOddsTable, OccupancyParams, Ternary};
pub use occupancy::{InsertStats, OccupancyGrid, OccupancyTile, MAX_RAY_CELLS};
pub use raster::Raster;
pub use raycast::{CellRay, Step};
pub use tiles::{Tile, TileKeyHasher, TileMap};
