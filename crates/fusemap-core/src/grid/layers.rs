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
pub trait ExtraLayers: Send {
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

    /// The cell's stored occupancy log-odds (NaN: never observed) and the extra layers,
    /// both writable: for a per-cell update that reads one and writes the other.
    #[inline(always)]
    pub fn parts_mut(&mut self, offset: usize) -> (&mut f32, &mut L) {
        (&mut self.log_odds[offset], &mut self.layers)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::{
        CellIndex, CellRay, CellVisitor, GridGeometry, LayeredGrid, OccupancyGrid, OccupancyParams, TILE_SIZE,
    };
    use crate::measurement::{Evidence, RangeData, Ray, SensorId};
    use crate::time::Stamp;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// A tiny second layer: per cell, how many observations updated it; the block is
    /// allocated on first write.
    struct Visits(Option<Box<[u32; TILE_CELLS]>>);

    impl ExtraLayers for Visits {
        fn empty() -> Self {
            Visits(None)
        }
    }

    /// Counts fresh visits into the `Visits` layer, and every visit (fresh or not).
    #[derive(Default)]
    struct CountVisits {
        all: u64,
    }

    impl CountVisits {
        fn count(&mut self, tile: &mut MapTile<Visits>, offset: usize, fresh: bool) {
            self.all += 1;
            if fresh {
                tile.layers_mut().0.get_or_insert_with(|| Box::new([0; TILE_CELLS]))[offset] += 1;
            }
        }
    }

    impl CellVisitor<MapTile<Visits>> for CountVisits {
        fn hit(&mut self, tile: &mut MapTile<Visits>, offset: usize, fresh: bool) {
            self.count(tile, offset, fresh);
        }
        fn pass(&mut self, tile: &mut MapTile<Visits>, offset: usize, fresh: bool) {
            self.count(tile, offset, fresh);
        }
    }

    fn geometry() -> GridGeometry {
        GridGeometry::centered(1.0).unwrap()
    }

    fn data(rays: Vec<Ray>) -> RangeData {
        RangeData { stamp: Stamp::ZERO, sensor: SensorId(0), rays, evidence: Evidence { p_hit: 0.9, p_miss: 0.4 } }
    }

    fn ray_strategy() -> impl Strategy<Value = Ray> {
        (-150.0..150.0f64, -150.0..150.0f64, -150.0..150.0f64, -150.0..150.0f64, prop::bool::ANY)
            .prop_map(|(ox, oy, ex, ey, hit)| Ray { origin: Point2::new(ox, oy), end: Point2::new(ex, ey), hit })
    }

    fn cell_at(first: CellIndex, off: usize) -> CellIndex {
        CellIndex::new(first.x + (off % TILE_SIZE) as i64, first.y + (off / TILE_SIZE) as i64)
    }

    #[test]
    fn an_extra_layer_block_is_allocated_on_first_write_only() {
        let mut g: LayeredGrid<Visits> = LayeredGrid::new(geometry(), OccupancyParams::default());
        let ray = Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(3.0, 0.0), hit: true };
        // Occupancy alone: the tile exists, the visits block does not.
        g.insert(&data(vec![ray]));
        let (t, _) = g.tile_of(CellIndex::new(0, 0)).unwrap();
        assert!(t.layers().0.is_none());
        let mut v = CountVisits::default();
        g.insert_with(&data(vec![ray]), &mut v);
        let (t, o) = g.tile_of(CellIndex::new(3, 0)).unwrap();
        assert_eq!(t.layers().0.as_ref().map(|b| b[o]), Some(1));
        // Four cells, each visited once by the one ray, the hit cell once more in pass 1.
        assert_eq!(v.all, 5);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100))]
        /// The visits layer reuses the occupancy walk: it is updated in exactly the cells
        /// whose occupancy was updated, once per observation that reached them, and the
        /// occupancy layer of the two-layer map is bit for bit the occupancy-only map's.
        #[test]
        fn a_second_layer_sees_the_cells_occupancy_updated(
            observations in prop::collection::vec(prop::collection::vec(ray_strategy(), 1..10), 1..5)
        ) {
            let mut plain = OccupancyGrid::new(geometry(), OccupancyParams::default());
            let mut layered: LayeredGrid<Visits> = LayeredGrid::new(geometry(), OccupancyParams::default());
            let mut visitor = CountVisits::default();
            let mut updates = 0;
            let mut visits = 0;
            let mut touched: HashMap<CellIndex, u32> = HashMap::new();
            for rays in &observations {
                let a = plain.insert(&data(rays.clone()));
                let b = layered.insert_with(&data(rays.clone()), &mut visitor);
                prop_assert_eq!(a, b);
                updates += a.hit_updates + a.miss_updates;
                visits += a.cell_visits + rays.iter().filter(|r| r.hit).count() as u64;
                // Reference: every cell a ray of this observation reaches, once.
                let mut cells: Vec<CellIndex> = Vec::new();
                for r in rays {
                    let u = |p: Point2| geometry().to_cell_units(p);
                    cells.extend(CellRay::new(u(r.origin), u(r.end)));
                }
                cells.sort();
                cells.dedup();
                for c in cells {
                    *touched.entry(c).or_default() += 1;
                }
            }
            prop_assert_eq!(visitor.all, visits);
            let mut counted = 0u64;
            let mut known = 0usize;
            for ((ka, ta), (kb, tb)) in plain.tiles().zip(layered.tiles()) {
                prop_assert_eq!(ka, kb);
                let first = ka.first_cell();
                for off in 0..TILE_CELLS {
                    prop_assert_eq!(ta.log_odds(off).map(f32::to_bits), tb.log_odds(off).map(f32::to_bits));
                    let n = tb.layers().0.as_ref().map_or(0, |b| b[off]);
                    prop_assert_eq!(n > 0, tb.log_odds(off).is_some(), "cell {:?}", cell_at(first, off));
                    prop_assert_eq!(n, touched.get(&cell_at(first, off)).copied().unwrap_or(0));
                    counted += n as u64;
                    known += tb.log_odds(off).is_some() as usize;
                }
            }
            prop_assert_eq!(plain.tile_count(), layered.tile_count());
            prop_assert_eq!(counted, updates);
            prop_assert_eq!(known, touched.len());
        }
    }
}
