//! Views of a map too large for one dense raster: its tiles as they are, and an overview.
//!
//! A dense export covers the bounding box of every cell any ray reached. Two places
//! kilometres apart (a robot moved between sites, a pose the glitch filter let through)
//! make that box huge and almost all unknown, while the map itself holds a few tiles. Past
//! `[limits] export_cells` the exporters therefore write the map as it is stored — its
//! tiles with their keys ([`SparseTiles`]) — and a picture of the populated region at a
//! coarser scale ([`LayeredGrid::overview`]).

use super::{CellBox, CellIndex, ExtraLayers, LayeredGrid, Raster, TileKey, TILE_CELLS};
use crate::geometry::Point2;

/// The occupancy layer's tiles, as stored: each tile covers the cells
/// `key · TILE_SIZE … key · TILE_SIZE + TILE_SIZE − 1` in x and y.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseTiles {
    /// Tile keys, in the map's allocation order.
    pub keys: Vec<TileKey>,
    /// `TILE_CELLS` log-odds per tile, row-major inside the tile (row 0 the lowest y); NaN
    /// where never observed.
    pub log_odds: Vec<f32>,
    /// Cell side, metres.
    pub resolution: f64,
    /// World coordinates of the lower-left corner of grid cell (0, 0).
    pub origin: Point2,
}

impl<L: ExtraLayers> LayeredGrid<L> {
    /// The occupancy layer's tiles (see [`SparseTiles`]). Memory: 16 KiB per tile, the
    /// size of the map itself.
    pub fn sparse_tiles(&self) -> SparseTiles {
        let mut keys = Vec::with_capacity(self.tile_count());
        let mut log_odds = Vec::with_capacity(self.tile_count() * TILE_CELLS);
        for (key, tile) in self.tiles() {
            keys.push(key);
            log_odds.extend((0..TILE_CELLS).map(|o| tile.log_odds(o).unwrap_or(f32::NAN)));
        }
        SparseTiles {
            keys,
            log_odds,
            resolution: self.geometry().resolution(),
            origin: self.geometry().cell_corner(CellIndex::new(0, 0)),
        }
    }

    /// The known bounding box drawn at one cell per `factor × factor` block of map cells,
    /// `factor` the smallest that keeps both sides within `max_side` cells. A block's value
    /// is its most occupied observed cell (a wall one cell thick survives the reduction,
    /// as in the max-filtered grids of Cartographer's branch-and-bound matcher); a block
    /// with no observed cell is unknown. The raster's resolution is `factor` cells, its
    /// `first_cell` the box's first map cell. `None` while nothing is known.
    pub fn overview(&self, max_side: usize) -> Option<(Raster, usize)> {
        let area = self.known_box()?;
        let max_side = max_side.max(1) as u64;
        let (w, h) = (area.width() as u64, area.height() as u64);
        let factor = w.max(h).div_ceil(max_side).max(1);
        let (cw, ch) = (w.div_ceil(factor) as usize, h.div_ceil(factor) as usize);
        let mut log_odds = vec![f32::NEG_INFINITY; cw * ch];
        let mut known = vec![false; cw * ch];
        for (key, tile) in self.tiles() {
            let first = key.first_cell();
            for o in 0..TILE_CELLS {
                let Some(l) = tile.log_odds(o) else { continue };
                let c =
                    CellIndex::new(first.x + (o % super::TILE_SIZE) as i64, first.y + (o / super::TILE_SIZE) as i64);
                if !contains(area, c) {
                    continue;
                }
                let bx = ((c.x - area.min.x) as u64 / factor) as usize;
                let by = ((c.y - area.min.y) as u64 / factor) as usize;
                let i = by * cw + bx;
                log_odds[i] = log_odds[i].max(l);
                known[i] = true;
            }
        }
        let prior = self.table().prior;
        for (l, &k) in log_odds.iter_mut().zip(&known) {
            if !k {
                *l = prior;
            }
        }
        let raster = Raster {
            width: cw,
            height: ch,
            resolution: self.geometry().resolution() * factor as f64,
            origin: self.geometry().cell_corner(area.min),
            first_cell: area.min,
            log_odds,
            known,
            params: *self.params(),
        };
        Some((raster, factor as usize))
    }
}

fn contains(b: CellBox, c: CellIndex) -> bool {
    c.x >= b.min.x && c.x <= b.max.x && c.y >= b.min.y && c.y <= b.max.y
}

#[cfg(test)]
mod tests {
    use crate::geometry::Point2;
    use crate::grid::{CellIndex, GridGeometry, OccupancyGrid, OccupancyParams, TILE_CELLS, TILE_SIZE};
    use crate::measurement::{Evidence, RangeData, Ray, SensorId};

    fn grid_with_two_sites(distance_m: f64) -> OccupancyGrid {
        let mut g = OccupancyGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let evidence = Evidence { p_hit: 0.7, p_miss: 0.4 };
        for x0 in [0.0, distance_m] {
            let mut d = RangeData::empty(SensorId(0), evidence);
            d.rays.push(Ray { origin: Point2::new(x0, 0.0), end: Point2::new(x0 + 2.0, 0.0), hit: true });
            g.insert(&d);
        }
        g
    }

    #[test]
    fn the_tiles_are_the_map_as_stored() {
        let g = grid_with_two_sites(1000.0);
        let s = g.sparse_tiles();
        assert_eq!(s.keys.len(), g.tile_count());
        assert_eq!(s.log_odds.len(), g.tile_count() * TILE_CELLS);
        for (i, key) in s.keys.iter().enumerate() {
            let first = key.first_cell();
            for o in 0..TILE_CELLS {
                let c = CellIndex::new(first.x + (o % TILE_SIZE) as i64, first.y + (o / TILE_SIZE) as i64);
                let v = s.log_odds[i * TILE_CELLS + o];
                match g.log_odds(c) {
                    Some(l) => assert_eq!(l, v),
                    None => assert!(v.is_nan()),
                }
            }
        }
        // Cell (0, 0)'s corner: the cell centred on the origin starts half a cell before.
        assert_eq!((s.origin.x, s.origin.y), (-0.05, -0.05));
    }

    #[test]
    fn the_overview_fits_the_side_and_keeps_every_wall() {
        let g = grid_with_two_sites(1000.0);
        let (r, factor) = g.overview(500).unwrap();
        let b = g.known_box().unwrap();
        assert!(r.width <= 500 && r.height <= 500, "{} x {}", r.width, r.height);
        assert_eq!(factor, b.width().div_ceil(500));
        assert!((r.resolution - 0.1 * factor as f64).abs() < 1e-12);
        // Both hits survive as occupied blocks, and the space between the sites is unknown.
        let occupied = r.ternary().iter().filter(|t| **t == crate::grid::Ternary::Occupied).count();
        assert_eq!(occupied, 2);
        assert!(r.known_count() <= 4, "{}", r.known_count());
        // A small map is its own overview.
        let small = grid_with_two_sites(3.0);
        let (r, f) = small.overview(10_000).unwrap();
        assert_eq!(f, 1);
        assert_eq!(r.log_odds, small.known_raster().unwrap().log_odds);
    }
}
