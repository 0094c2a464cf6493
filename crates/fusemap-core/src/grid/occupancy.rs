//! The map: a set of layers on one tile key space, with the occupancy layer always
//! present, and the insertion of one observation's rays.
//!
//! **Per-observation rules** (OctoMap `computeUpdate`: "occupied nodes have a preference
//! over free ones"; Cartographer `ProbabilityGridRangeDataInserter2D`: hits first, then
//! misses, with an update marker):
//! 1. within one observation every cell is updated at most once — many beams of one scan
//!    crossing the same cell near the sensor are one piece of evidence, not fifty
//!    (the design document's "do not count correlated evidence twice", inside a scan);
//! 2. a cell that ends any hit ray of the observation gets the hit update, never the miss
//!    update of another ray that passes through it;
//! 3. (when the map's [`PassThroughParams`] are on) free evidence behind a cell the map
//!    holds as confidently occupied is attenuated — a specular ghost or a beam through
//!    glass must not carve open the object it passed (see [`PassThroughParams`]).
//!
//! The walk that enforces both is [`walk_observation`](super::walk_observation); this
//! module supplies what the occupancy layer does per cell (a clamped log-odds update,
//! Thrun et al., *Probabilistic Robotics*, §9.2) and the map's bookkeeping. The tile
//! layout — occupancy block, shared update mark, extra layers — is in
//! [`MapTile`](super::MapTile).

use super::{
    walk_observation, walk_observation_waves, CellBox, CellIndex, CellRaster, CellVisitor, ExtraLayers, GridGeometry,
    InsertStats, LogOddsTable, MapTile, MarkedTile, OccupancyParams, PassThroughParams, Raster, RayFork, Ternary,
    TileKey, TileMap, PARALLEL_MIN_CELLS, TILE_SIZE,
};
#[cfg(test)]
use super::{CellRay, TILE_CELLS};
use crate::grid::logodds::{logit, probability};
use crate::measurement::RangeData;

/// One tile of a map with occupancy only.
pub type OccupancyTile = MapTile<()>;

/// A probabilistic occupancy grid with no other layer: log-odds cells in sparse tiles.
pub type OccupancyGrid = LayeredGrid<()>;

/// A map: the occupancy layer and the extra layers `L` on one set of sparse tiles.
///
/// The occupancy layer is the one every range observation writes ([`insert`](Self::insert));
/// extra layers are written by their own [`CellVisitor`] in the same walk
/// ([`insert_with`](Self::insert_with)), so they see exactly the cells, and the
/// once-per-observation marks, that the occupancy layer sees.
pub struct LayeredGrid<L = ()> {
    geometry: GridGeometry,
    params: OccupancyParams,
    table: LogOddsTable,
    tiles: TileMap<MapTile<L>>,
    observations: u64,
    known: Option<CellBox>,
}

/// The occupancy layer's per-cell update: the hit or the miss increment, kept on fresh
/// visits only, with the pass-through rule of [`PassThroughParams`] on the misses.
///
/// The rule costs the common path one comparison: a crossed cell goes to the rule's own
/// code only when its log-odds reach `hi` — the confidence threshold while the ray is in
/// the open (`+inf` when the rule is off, so never), `-inf` while it is behind a confident
/// cell (every observed cell then, to find where it comes out into known free space);
/// cells never observed (NaN) always take the common path with `d_cur` (0 behind a
/// confident cell).
#[derive(Clone, Copy, Debug)]
pub struct OccupancyUpdate {
    table: LogOddsTable,
    d_hit: f32,
    d_miss: f32,
    /// The miss increment behind a confidently occupied cell (`weight · d_miss`).
    d_pass: f32,
    /// The miss increment of the common path: `d_miss`, or 0 behind a confident cell
    /// (only never-observed cells take the common path then).
    d_cur: f32,
    /// Log-odds below which a crossed cell is known free: the ray has come out of the
    /// object it passed through into space the map holds free, and is a plain ray again.
    known_free: f32,
    /// Log-odds at or above which a crossed cell is confidently occupied; `+inf` when the
    /// rule is off.
    confident: f32,
    /// The common path's bound (see the type docs).
    hi: f32,
    margin: u64,
    /// The current ray is behind a confident cell; `since` is that cell's distance to the
    /// ray's end, in cells.
    through: bool,
    since: u64,
    attenuated: u64,
    ghost_hits: u64,
}

impl OccupancyUpdate {
    /// The update for evidence `(p_hit, p_miss)` against the layer's `table`, without the
    /// pass-through rule.
    pub fn new(table: LogOddsTable, evidence: crate::measurement::Evidence) -> Self {
        let d_miss = table.increment(evidence.p_miss);
        Self {
            table,
            d_hit: table.increment(evidence.p_hit),
            d_miss,
            d_pass: d_miss,
            d_cur: d_miss,
            known_free: f32::NEG_INFINITY,
            confident: f32::INFINITY,
            hi: f32::INFINITY,
            margin: 0,
            through: false,
            since: 0,
            attenuated: 0,
            ghost_hits: 0,
        }
    }

    /// This update with the pass-through rule `rule` (off when `rule.is_off()`); a cell
    /// below `free_threshold` (probability) ends it.
    pub fn with_pass_through(mut self, rule: &PassThroughParams, free_threshold: f64) -> Self {
        if !rule.is_off() {
            self.confident = logit(rule.threshold) as f32;
            self.hi = self.confident;
            self.known_free = logit(free_threshold) as f32;
            self.d_pass = (rule.weight * self.d_miss as f64) as f32;
            self.margin = rule.margin_cells as u64;
        }
        self
    }

    /// Hits so far whose ray was still behind a confidently occupied cell at its end
    /// (see [`PassThroughParams`]).
    pub fn ghost_hits(&self) -> u64 {
        self.ghost_hits
    }

    /// Whether the current ray is behind a confidently occupied cell.
    #[inline(always)]
    pub fn is_through(&self) -> bool {
        self.through
    }

    /// The miss increment for a crossed cell holding `v` (NaN: never observed) with
    /// `cells_after` cells of the ray still to come, advancing the ray's pass-through
    /// state. Called on every visit of a ray's cells in order, fresh or not.
    #[inline(always)]
    pub fn miss_increment(&mut self, v: f32, cells_after: u64) -> f32 {
        // NaN (never observed) fails the comparison and takes the common path.
        if v >= self.hi {
            self.rule(v, cells_after)
        } else {
            self.d_cur
        }
    }

    /// The hit increment.
    #[inline(always)]
    pub fn hit_increment(&self) -> f32 {
        self.d_hit
    }

    /// The layer's log-odds table.
    #[inline(always)]
    pub fn table(&self) -> &LogOddsTable {
        &self.table
    }

    /// Cell visits so far at which the reduced weight applied (counted like
    /// [`InsertStats::cell_visits`]); call [`finish`](Self::finish) after the last ray.
    pub fn attenuated(&self) -> u64 {
        self.attenuated
    }

    /// Ends the current ray (counts its attenuated visits).
    #[inline(always)]
    pub fn finish(&mut self) {
        if self.through {
            self.attenuated += self.since + 1;
        }
        self.through = false;
        self.hi = self.confident;
        self.d_cur = self.d_miss;
    }

    /// The rule on an observed cell at or above `hi`: updates the ray's state and returns
    /// the miss increment for the cell.
    #[inline(always)]
    fn rule(&mut self, v: f32, cells_after: u64) -> f32 {
        if self.through {
            if v < self.known_free {
                // Out into space the map holds free (the room beyond a corner the ray
                // clipped, beyond a door that opened): a plain ray again from here on,
                // its echo included.
                self.attenuated += self.since - cells_after;
                self.through = false;
                self.hi = self.confident;
                self.d_cur = self.d_miss;
                return self.d_miss;
            }
            self.d_pass
        } else if cells_after > self.margin {
            // A confident cell with more than the margin to go: a probable pass-through or
            // ghost. This cell and the observed cells after it get the reduced miss; the
            // cells after it that the map never observed get nothing.
            self.through = true;
            self.since = cells_after;
            self.hi = f32::NEG_INFINITY;
            self.d_cur = 0.0;
            self.d_pass
        } else {
            self.d_miss
        }
    }
}

impl<L> CellVisitor<MapTile<L>> for OccupancyUpdate {
    #[inline(always)]
    fn hit(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool) {
        tile.update_log_odds(offset, self.d_hit, &self.table, fresh);
    }

    #[inline(always)]
    fn pass(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool) {
        // Without the distance to the ray's end the rule cannot be judged: a plain miss.
        tile.update_log_odds(offset, self.d_miss, &self.table, fresh);
    }

    #[inline(always)]
    fn pass_at(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool, cells_after: u64) {
        let v = tile.log_odds(offset).unwrap_or(f32::NAN);
        let d = self.miss_increment(v, cells_after);
        // A never-observed cell given no evidence stays never observed.
        tile.update_log_odds(offset, d, &self.table, fresh & !(v.is_nan() & (d == 0.0)));
    }

    #[inline(always)]
    fn begin_ray(&mut self, _cells: u64) {
        self.finish();
    }

    #[inline(always)]
    fn end_hit(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool) {
        // An echo from behind a confidently occupied cell may be a ghost (a specular
        // bounce) or a pass-through, or a real wall seen past a clipped corner: counted,
        // and applied (dropping them loses 3-8 % of the walls of real CARMEN logs).
        self.ghost_hits += (self.through & fresh) as u64;
        tile.update_log_odds(offset, self.d_hit, &self.table, fresh);
    }
}

/// The occupancy update with the rule off: `pass_at` is the default (a plain miss), so a
/// map without the rule runs exactly the walk it ran before the rule existed, at its cost.
#[derive(Clone, Copy)]
struct PlainUpdate(OccupancyUpdate);

impl<L> CellVisitor<MapTile<L>> for PlainUpdate {
    #[inline(always)]
    fn hit(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool) {
        self.0.hit(tile, offset, fresh);
    }

    #[inline(always)]
    fn pass(&mut self, tile: &mut MapTile<L>, offset: usize, fresh: bool) {
        CellVisitor::<MapTile<L>>::pass(&mut self.0, tile, offset, fresh);
    }
}

impl<L: ExtraLayers> RayFork<MapTile<L>> for OccupancyUpdate {
    fn fork(&self) -> Self {
        Self { through: false, since: 0, hi: self.confident, d_cur: self.d_miss, attenuated: 0, ghost_hits: 0, ..*self }
    }

    fn join(&mut self, ray: &Self) {
        let mut ray = *ray;
        ray.finish();
        self.attenuated += ray.attenuated;
        self.ghost_hits += ray.ghost_hits;
    }
}

impl<L: ExtraLayers> RayFork<MapTile<L>> for PlainUpdate {
    fn fork(&self) -> Self {
        Self(RayFork::<MapTile<L>>::fork(&self.0))
    }

    fn join(&mut self, _: &Self) {}
}

/// The size from which [`LayeredGrid::insert`] walks an observation in waves: never on a
/// pool of one thread, where the waves would only add their hand-overs.
pub fn waves_threshold() -> u64 {
    if crate::parallel::threads() > 1 {
        PARALLEL_MIN_CELLS
    } else {
        u64::MAX
    }
}

impl<L: ExtraLayers> LayeredGrid<L> {
    /// An empty grid. `params` must be valid (see `config::validate`).
    pub fn new(geometry: GridGeometry, params: OccupancyParams) -> Self {
        Self {
            geometry,
            params,
            table: LogOddsTable::new(&params),
            tiles: TileMap::new(),
            observations: 0,
            known: None,
        }
    }

    /// The grid's placement.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The probabilistic parameters.
    pub fn params(&self) -> &OccupancyParams {
        &self.params
    }

    /// The log-odds form of the parameters.
    pub fn table(&self) -> &LogOddsTable {
        &self.table
    }

    /// Observations inserted so far.
    pub fn observations(&self) -> u64 {
        self.observations
    }

    /// Allocated tiles.
    pub fn tile_count(&self) -> usize {
        self.tiles.len()
    }

    /// Bytes held by tiles (the blocks inline in a tile; an extra layer's boxed blocks are
    /// not counted).
    pub fn tile_bytes(&self) -> usize {
        self.tiles.tile_bytes()
    }

    /// Allocates at most `tiles` tiles (`[limits] map_cells`); see [`TileMap`]'s budget.
    pub fn set_tile_budget(&mut self, tiles: usize) {
        self.tiles.set_tile_budget(tiles);
    }

    /// True once a write needed a tile past the budget: the grid has missed writes and
    /// must not be exported as a map.
    pub fn over_budget(&self) -> bool {
        self.tiles.over_budget()
    }

    /// The bounding box of every cell any ray has reached, `None` before the first.
    pub fn known_box(&self) -> Option<CellBox> {
        self.known
    }

    /// The tile holding `cell`, if allocated, and the cell's offset in it (for reading the
    /// extra layers).
    pub fn tile_of(&self, cell: CellIndex) -> Option<(&MapTile<L>, usize)> {
        self.tiles.get_cell(cell)
    }

    /// The stored log-odds of a cell, `None` if never observed.
    pub fn log_odds(&self, cell: CellIndex) -> Option<f32> {
        self.tiles.get_cell(cell).and_then(|(t, o)| t.log_odds(o))
    }

    /// The occupancy probability of a cell (the prior if never observed).
    pub fn probability(&self, cell: CellIndex) -> f64 {
        self.log_odds(cell).map_or(self.params.prior, |l| probability(l as f64))
    }

    /// Free / occupied / unknown by the thresholds; never-observed cells are unknown.
    pub fn ternary(&self, cell: CellIndex) -> Ternary {
        match self.log_odds(cell) {
            Some(l) => self.table.classify(probability(l as f64)),
            None => Ternary::Unknown,
        }
    }

    /// Inserts one observation into the occupancy layer (see the module docs for the
    /// per-observation rules). A large observation from one sensor position is walked in
    /// waves of tiles on the pool's threads, with the serial walk's result to the bit (see
    /// [`walk_observation_waves`]).
    pub fn insert(&mut self, data: &RangeData) -> InsertStats {
        self.insert_in_waves(data, waves_threshold())
    }

    /// [`insert`](Self::insert) with the size from which an observation is walked in waves
    /// (in cell visits; `u64::MAX`: never, 0: whenever its rays start in one tile).
    pub fn insert_in_waves(&mut self, data: &RangeData, min_cells: u64) -> InsertStats {
        let obs = self.begin_observation();
        let update = OccupancyUpdate::new(self.table, data.evidence);
        if self.params.pass_through.is_off() {
            return self.walk_forked(obs, &data.rays, &mut PlainUpdate(update), min_cells);
        }
        let mut rule = update.with_pass_through(&self.params.pass_through, self.params.free_threshold);
        let mut stats = self.walk_forked(obs, &data.rays, &mut rule, min_cells);
        rule.finish();
        stats.cell_visits_attenuated = rule.attenuated();
        stats.ghost_hits = rule.ghost_hits();
        stats
    }

    /// Walks `rays` as observation `obs` with `visitor`, in waves of tiles when the
    /// observation has at least `min_cells` cell visits and its rays start in one tile,
    /// else serially; the result is the same.
    pub fn walk_forked<V: RayFork<MapTile<L>>>(
        &mut self,
        obs: u64,
        rays: &[crate::measurement::Ray],
        visitor: &mut V,
        min_cells: u64,
    ) -> InsertStats {
        let (tiles, known) = (&mut self.tiles, &mut self.known);
        if min_cells != u64::MAX {
            if let Some(s) = walk_observation_waves(tiles, &self.geometry, obs, rays, known, visitor, min_cells) {
                return s;
            }
        }
        walk_observation(tiles, &self.geometry, obs, rays, known, visitor)
    }

    /// Inserts one observation into the occupancy layer and, in the same walk, into the
    /// extra layers `layers` writes (occupancy first on each cell, then `layers`).
    pub fn insert_with<V: CellVisitor<MapTile<L>>>(&mut self, data: &RangeData, layers: &mut V) -> InsertStats {
        self.observations += 1;
        let update = OccupancyUpdate::new(self.table, data.evidence);
        let (tiles, known, obs) = (&mut self.tiles, &mut self.known, self.observations);
        if self.params.pass_through.is_off() {
            let mut visitor = (PlainUpdate(update), layers);
            return walk_observation(tiles, &self.geometry, obs, &data.rays, known, &mut visitor);
        }
        let rule = update.with_pass_through(&self.params.pass_through, self.params.free_threshold);
        let mut visitor = (rule, layers);
        let mut stats = walk_observation(tiles, &self.geometry, obs, &data.rays, known, &mut visitor);
        visitor.0.finish();
        stats.cell_visits_attenuated = visitor.0.attenuated();
        stats.ghost_hits = visitor.0.ghost_hits();
        stats
    }

    /// Starts a new observation and returns its number, for an insertion that writes cells
    /// directly ([`cell_mut`](Self::cell_mut)) and then walks rays
    /// ([`walk_observation_rays`](Self::walk_observation_rays)) under the same
    /// once-per-observation marks.
    pub fn begin_observation(&mut self) -> u64 {
        self.observations += 1;
        self.observations
    }

    /// The tile holding `cell` (allocated if needed), the cell's offset, and whether this
    /// is the cell's first visit in observation `obs` (the visit marks it). `None` for a
    /// cell beyond the index range. Grows the known box.
    pub fn cell_mut(&mut self, cell: CellIndex, obs: u64) -> Option<(&mut MapTile<L>, usize, bool)> {
        const LIMIT: i64 = 1 << 60;
        if cell.x.abs() >= LIMIT || cell.y.abs() >= LIMIT {
            return None;
        }
        let b = CellBox { min: cell, max: cell };
        self.known = Some(self.known.map_or(b, |k| k.union(b)));
        let tile = self.tiles.get_or_insert(cell.tile());
        let offset = cell.offset_in_tile();
        let mark = tile.mark();
        mark.begin(obs);
        let fresh = mark.test_and_set(offset);
        Some((tile, offset, fresh))
    }

    /// Walks `rays` as part of observation `obs` (begun with
    /// [`begin_observation`](Self::begin_observation)) with `visitor` alone: no built-in
    /// occupancy update, the visitor decides what every layer does.
    pub fn walk_observation_rays<V: CellVisitor<MapTile<L>>>(
        &mut self,
        obs: u64,
        rays: &[crate::measurement::Ray],
        visitor: &mut V,
    ) -> InsertStats {
        walk_observation(&mut self.tiles, &self.geometry, obs, rays, &mut self.known, visitor)
    }

    /// Inserts one observation's rays with `visitor` alone (see
    /// [`walk_observation_rays`](Self::walk_observation_rays)).
    pub fn insert_visited<V: CellVisitor<MapTile<L>>>(
        &mut self,
        rays: &[crate::measurement::Ray],
        visitor: &mut V,
    ) -> InsertStats {
        let obs = self.begin_observation();
        self.walk_observation_rays(obs, rays, visitor)
    }

    /// A dense copy of one layer's cells over `area` (row 0 = lowest y): `cell` reads a
    /// cell from its tile and offset, `None` meaning "never observed", shown as `fill`.
    /// This is the raster view every layer gives its exporters.
    pub fn cell_raster<T: Clone>(
        &self,
        area: CellBox,
        fill: T,
        cell: impl Fn(&MapTile<L>, usize) -> Option<T>,
    ) -> CellRaster<T> {
        let (w, h) = (area.width(), area.height());
        let mut cells = vec![fill; w * h];
        let mut known = vec![false; w * h];
        for (key, tile) in self.tiles.iter() {
            let first = key.first_cell();
            let tile_box = CellBox {
                min: first,
                max: CellIndex::new(first.x + TILE_SIZE as i64 - 1, first.y + TILE_SIZE as i64 - 1),
            };
            let Some(ov) = intersect(area, tile_box) else {
                continue;
            };
            for y in ov.min.y..=ov.max.y {
                for x in ov.min.x..=ov.max.x {
                    if let Some(v) = cell(tile, CellIndex::new(x, y).offset_in_tile()) {
                        let i = (y - area.min.y) as usize * w + (x - area.min.x) as usize;
                        cells[i] = v;
                        known[i] = true;
                    }
                }
            }
        }
        CellRaster {
            width: w,
            height: h,
            resolution: self.geometry.resolution(),
            origin: self.geometry.cell_corner(area.min),
            first_cell: area.min,
            cells,
            known,
        }
    }

    /// The occupancy layer's cells of `area` as a raster (row 0 = lowest y). Unobserved
    /// cells hold the prior's log-odds and are marked unknown.
    pub fn raster(&self, area: CellBox) -> Raster {
        let r = self.cell_raster(area, self.table.prior, |t, o| t.log_odds(o));
        Raster {
            width: r.width,
            height: r.height,
            resolution: r.resolution,
            origin: r.origin,
            first_cell: r.first_cell,
            log_odds: r.cells,
            known: r.known,
            params: self.params,
        }
    }

    /// The occupancy raster of the known bounding box, `None` while nothing is known.
    pub fn known_raster(&self) -> Option<Raster> {
        self.known.map(|b| self.raster(b))
    }

    /// Iterates over allocated tiles (for exporters that stream tile by tile).
    pub fn tiles(&self) -> impl Iterator<Item = (TileKey, &MapTile<L>)> {
        self.tiles.iter()
    }
}

fn intersect(a: CellBox, b: CellBox) -> Option<CellBox> {
    let min = CellIndex::new(a.min.x.max(b.min.x), a.min.y.max(b.min.y));
    let max = CellIndex::new(a.max.x.min(b.max.x), a.max.y.min(b.max.y));
    (min.x <= max.x && min.y <= max.y).then_some(CellBox { min, max })
}

#[cfg(test)]
#[path = "occupancy_tests.rs"]
mod tests;
