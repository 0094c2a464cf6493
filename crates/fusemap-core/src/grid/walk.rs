//! The walk of one observation's rays over the tiles, separate from what is done to each
//! cell.
//!
//! After Cartographer's `ProbabilityGridRangeDataInserter2D` (hits first, then misses,
//! with an update marker) and OctoMap's `computeUpdate` ("occupied nodes have a preference
//! over free ones"), for one observation:
//! 1. **hits**: the end cell of every hit ray is marked;
//! 2. **passes**: every ray is walked from its origin to its end cell (Amanatides & Woo,
//!    [`CellRay`]), visiting each cell it crosses, and a hit ray's end cell then gets its
//!    hit ([`CellVisitor::end_hit`]), so that the layer has seen the whole ray before it
//!    judges the echo.
//!
//! Each visit says whether it is the first of that cell in this observation (`fresh`,
//! from the tile's shared [`UpdateMark`](super::UpdateMark)). A layer acts only on fresh
//! visits to count one observation once per cell; since hits come first, a cell that
//! ends any hit ray is never also updated as free.
//!
//! What a visit does is a [`CellVisitor`], a generic parameter, so the walk is compiled
//! once per layer combination and the per-cell call inlines into the loop: the occupancy
//! layer, and any later layer, reuse this walk instead of copying it (Bonxai's
//! `RayIterator` calls a closure per cell for the same reason).

use super::{CellBox, CellIndex, CellRay, GridGeometry, MarkedTile, Step, TileMap, TILE_MASK, TILE_SHIFT, TILE_SIZE};
use crate::measurement::Ray;
use serde::Serialize;

/// Longest ray walked, in cells (|Δi| + |Δj|). Longer rays come from corrupt data (a
/// range of 1e9 m) and are rejected and counted instead of walking for minutes.
pub const MAX_RAY_CELLS: u64 = 1 << 22;

/// What a layer does to each cell a walk visits.
///
/// `tile` is the tile holding the cell, `offset` the cell's row-major offset in it, and
/// `fresh` whether this is the cell's first visit in the current observation (the visit
/// has already marked it).
pub trait CellVisitor<T> {
    /// The end cell of a hit ray (called by the default [`end_hit`](Self::end_hit)).
    fn hit(&mut self, tile: &mut T, offset: usize, fresh: bool);
    /// A cell a ray crosses, its end cell included (pass 2).
    fn pass(&mut self, tile: &mut T, offset: usize, fresh: bool);
    /// Called in pass 2 before the first visit of each ray, with the number of cells the
    /// ray will visit (its end cell included). The default does nothing.
    #[inline(always)]
    fn begin_ray(&mut self, cells: u64) {
        let _ = cells;
    }
    /// The end cell of a hit ray, after the ray's walk (pass 2), with whether it is the
    /// cell's first hit of the observation. The default is [`hit`](Self::hit); a visitor
    /// that judges the ray on the way (the pass-through rule counts echoes from behind a
    /// confidently occupied cell) overrides it.
    #[inline(always)]
    fn end_hit(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        self.hit(tile, offset, fresh)
    }
    /// [`pass`](Self::pass) with the number of cells the ray still visits after this one
    /// (0 at its end cell), which the walk knows for free; what pass 2 calls. A visitor that
    /// needs to know how far each cell lies from the ray's end (the occupancy layer's
    /// pass-through rule) overrides this; the default forgets it and calls `pass`.
    #[inline(always)]
    fn pass_at(&mut self, tile: &mut T, offset: usize, fresh: bool, cells_after: u64) {
        let _ = cells_after;
        self.pass(tile, offset, fresh)
    }
}

/// No layer: the walk alone (its counts and marks).
impl<T> CellVisitor<T> for () {
    #[inline(always)]
    fn hit(&mut self, _: &mut T, _: usize, _: bool) {}
    #[inline(always)]
    fn pass(&mut self, _: &mut T, _: usize, _: bool) {}
}

impl<T, V: CellVisitor<T> + ?Sized> CellVisitor<T> for &mut V {
    #[inline(always)]
    fn hit(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        (**self).hit(tile, offset, fresh)
    }
    #[inline(always)]
    fn pass(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        (**self).pass(tile, offset, fresh)
    }
    #[inline(always)]
    fn begin_ray(&mut self, cells: u64) {
        (**self).begin_ray(cells)
    }
    #[inline(always)]
    fn pass_at(&mut self, tile: &mut T, offset: usize, fresh: bool, cells_after: u64) {
        (**self).pass_at(tile, offset, fresh, cells_after)
    }
    #[inline(always)]
    fn end_hit(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        (**self).end_hit(tile, offset, fresh)
    }
}

/// Two layers fed by one walk, first `A` then `B` on each cell.
impl<T, A: CellVisitor<T>, B: CellVisitor<T>> CellVisitor<T> for (A, B) {
    #[inline(always)]
    fn hit(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        self.0.hit(tile, offset, fresh);
        self.1.hit(tile, offset, fresh);
    }
    #[inline(always)]
    fn pass(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        self.0.pass(tile, offset, fresh);
        self.1.pass(tile, offset, fresh);
    }
    #[inline(always)]
    fn begin_ray(&mut self, cells: u64) {
        self.0.begin_ray(cells);
        self.1.begin_ray(cells);
    }
    #[inline(always)]
    fn pass_at(&mut self, tile: &mut T, offset: usize, fresh: bool, cells_after: u64) {
        self.0.pass_at(tile, offset, fresh, cells_after);
        self.1.pass_at(tile, offset, fresh, cells_after);
    }
    #[inline(always)]
    fn end_hit(&mut self, tile: &mut T, offset: usize, fresh: bool) {
        self.0.end_hit(tile, offset, fresh);
        self.1.end_hit(tile, offset, fresh);
    }
}

/// What one insertion did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct InsertStats {
    /// Rays walked.
    pub rays: u64,
    /// Rays refused: a non-finite point, a cell beyond the index range, or longer than
    /// [`MAX_RAY_CELLS`].
    pub rays_rejected: u64,
    /// Cells visited by the walks, counting a cell again for every ray that crosses it.
    pub cell_visits: u64,
    /// Cells updated as occupied (once per observation).
    pub hit_updates: u64,
    /// Cells updated as free (once per observation).
    pub miss_updates: u64,
    /// Cells whose dynamic layer took evidence of a moving object (a camera's dynamic
    /// class, or a lidar hit routed there).
    pub dynamic_updates: u64,
    /// Of those, lidar hits routed from the static layer to the dynamic one.
    pub routed_to_dynamic: u64,
    /// Hits whose ray was still behind a confidently occupied cell at its end (see
    /// [`PassThroughParams`](super::PassThroughParams)): suspected ghost echoes. They are
    /// applied — on real logs a wall seen past a clipped corner looks the same — and
    /// counted.
    pub ghost_hits: u64,
    /// Of `cell_visits`, those at which the occupancy layer's free evidence had the
    /// reduced weight of the pass-through rule: the ray had passed through a cell the map
    /// held as confidently occupied (see [`PassThroughParams`](super::PassThroughParams)).
    pub cell_visits_attenuated: u64,
}

impl InsertStats {
    /// Adds another insertion's counts.
    pub fn add(&mut self, o: &InsertStats) {
        self.rays += o.rays;
        self.rays_rejected += o.rays_rejected;
        self.cell_visits += o.cell_visits;
        self.hit_updates += o.hit_updates;
        self.miss_updates += o.miss_updates;
        self.dynamic_updates += o.dynamic_updates;
        self.routed_to_dynamic += o.routed_to_dynamic;
        self.ghost_hits += o.ghost_hits;
        self.cell_visits_attenuated += o.cell_visits_attenuated;
    }
}

/// Walks the rays of observation number `obs` over `tiles` (allocating tiles as needed),
/// calling `visitor` per cell by the two-pass rule of the module docs, and grows `known`
/// to hold every cell reached. `obs` must differ from every earlier observation's number
/// on these tiles (the mark is reset by a change of number).
#[inline]
pub fn walk_observation<T: MarkedTile, V: CellVisitor<T>>(
    tiles: &mut TileMap<T>,
    geometry: &GridGeometry,
    obs: u64,
    rays: &[Ray],
    known: &mut Option<CellBox>,
    visitor: &mut V,
) -> InsertStats {
    let ends = ray_ends(geometry);
    let mut stats = InsertStats::default();

    // Pass 1: hits. Each end cell is marked, so the walks of pass 2 never give it a miss;
    // the hit itself is applied at the end of its ray's walk (`end_hit`), when the ray is
    // known, with whether it is the cell's first hit of the observation.
    let mut first_hit = vec![false; rays.len()];
    for (i, ray) in rays.iter().enumerate().filter(|(_, r)| r.hit) {
        let Some((_, _, _, c)) = ends(ray) else {
            continue;
        };
        let tile = tiles.get_or_insert(c.tile());
        let mark = tile.mark();
        mark.begin(obs);
        let fresh = mark.test_and_set(c.offset_in_tile());
        stats.hit_updates += fresh as u64;
        first_hit[i] = fresh;
    }

    // Pass 2: walk every ray from its origin to its end.
    let mut known_box = *known;
    for (i, ray) in rays.iter().enumerate() {
        let Some((a, b, ca, cb)) = ends(ray) else {
            stats.rays_rejected += 1;
            continue;
        };
        let mut walk = CellRay::new(a, b);
        let n = walk.len_cells();
        stats.rays += 1;
        stats.cell_visits += n;
        visitor.begin_ray(n);
        // The union with the known box, written out so that it inlines into the loop.
        let (lo, hi) = known_box.map_or((ca, ca), |k| (k.min, k.max));
        known_box = Some(CellBox {
            min: CellIndex::new(lo.x.min(ca.x).min(cb.x), lo.y.min(ca.y).min(cb.y)),
            max: CellIndex::new(hi.x.max(ca.x).max(cb.x), hi.y.max(ca.y).max(cb.y)),
        });

        // Walk inside one tile with a local offset; resolve a tile (one hash lookup)
        // only when the walk crosses into the next one.
        let end_hit = ray.hit.then(|| first_hit[i]);
        let mut cell = ca;
        loop {
            let tile = tiles.get_or_insert(cell.tile());
            tile.mark().begin(obs);
            match walk_in_tile(tile, &mut walk, visitor, end_hit, &mut stats.miss_updates) {
                Some(next) => cell = next,
                None => break,
            }
        }
    }
    *known = known_box;
    stats
}

/// Walks `walk` from its current cell through the cells of `tile` (the tile holding that
/// cell, its mark begun for this observation), marking each and calling the visitor, until
/// the walk steps out of the tile or ends. Returns the first cell outside the tile (the
/// walk is at it, not yet visited), or `None` once the ray's last cell is done, its end
/// hit applied when `end_hit` is `Some(first)`. Each fresh visit adds one to `misses`.
///
/// Inside a tile the cell's offset follows the walk's steps, so the tile is resolved (one
/// hash lookup) only when the walk crosses into the next one.
#[inline(always)]
pub(super) fn walk_in_tile<T: MarkedTile, V: CellVisitor<T>>(
    tile: &mut T,
    walk: &mut CellRay,
    visitor: &mut V,
    end_hit: Option<bool>,
    misses: &mut u64,
) -> Option<CellIndex> {
    let c = walk.cell();
    let (sx, sy) = (walk.step_x(), walk.step_y() * TILE_SIZE as i64);
    let (mut lx, mut ly) = (c.x & TILE_MASK, c.y & TILE_MASK);
    let mut offset = c.offset_in_tile() as i64;
    loop {
        let fresh = tile.mark().test_and_set(offset as usize);
        *misses += fresh as u64;
        // Before the step, the walk's own count says how many cells follow this one.
        visitor.pass_at(tile, offset as usize, fresh, walk.cells_after());
        match walk.step() {
            Step::Done => {
                if let Some(first) = end_hit {
                    visitor.end_hit(tile, offset as usize, first);
                }
                return None;
            }
            Step::X => {
                lx += sx;
                offset += sx;
            }
            Step::Y => {
                ly += sy >> TILE_SHIFT;
                offset += sy;
            }
        }
        if (lx | ly) & !TILE_MASK != 0 {
            // Left the tile: `lx` or `ly` is -1 or TILE_SIZE.
            return Some(walk.cell());
        }
    }
}

/// The ends of a ray in cell units with their cells, or `None` when it must not be
/// walked ([`checked`]): the conversion every walk uses (the inverse resolution, once).
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(super) fn ray_ends(
    geometry: &GridGeometry,
) -> impl Fn(&Ray) -> Option<((f64, f64), (f64, f64), CellIndex, CellIndex)> {
    let (ox, oy) = (geometry.origin().x, geometry.origin().y);
    let inv = 1.0 / geometry.resolution();
    let units = move |p: crate::geometry::Point2| ((p.x - ox) * inv, (p.y - oy) * inv);
    move |ray: &Ray| checked(units(ray.origin), units(ray.end))
}

#[inline(always)]
fn cell_of_units((u, v): (f64, f64)) -> Option<CellIndex> {
    const LIMIT: f64 = 4.611_686_018_427_388e18;
    let (fx, fy) = (u.floor(), v.floor());
    // `abs() < LIMIT` is false for NaN and ±inf too.
    (fx.abs() < LIMIT && fy.abs() < LIMIT).then(|| CellIndex::new(fx as i64, fy as i64))
}

/// The cells of a ray's two ends, or `None` when the ray must not be walked (non-finite,
/// beyond the index range, or longer than [`MAX_RAY_CELLS`]).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn checked(a: (f64, f64), b: (f64, f64)) -> Option<((f64, f64), (f64, f64), CellIndex, CellIndex)> {
    let ca = cell_of_units(a)?;
    let cb = cell_of_units(b)?;
    let n = ca.x.abs_diff(cb.x) + ca.y.abs_diff(cb.y);
    (n <= MAX_RAY_CELLS).then_some((a, b, ca, cb))
}
