//! One observation's walk spread over the pool's threads by tile, bit-identical to the
//! serial walk ([`walk_observation`](super::walk_observation)).
//!
//! Clamping makes the order of updates matter, and so do the per-observation rules: the
//! first visit of a cell takes the update, and the pass-through rule reads the cells a
//! ray crossed as the rays before it left them. The serial walk defines that order: the
//! hits of every ray, then ray after ray, each from its origin to its end. Two facts let
//! the tiles be updated in parallel in exactly that order:
//!
//! 1. **Each tile's cells are touched by one thread, ray after ray.** A tile's segments
//!    (the part of each ray inside it) run in ray order, so every cell sees the same
//!    sequence of visits as in the serial walk, and reads what the serial walk would read.
//! 2. **A ray's state reaches each tile before the tile is walked.** When every ray starts
//!    in one tile (one sensor position, as for a scan), each step of a walk into another
//!    tile takes it one tile further from the start tile in Manhattan tile distance: the
//!    walk moves monotonically along each axis, away from where it began. So a tile at
//!    distance `d` is walked by every ray at step `d` of its tile sequence and never at
//!    another. The walk goes in *waves*: wave `d` walks all tiles at distance `d` in
//!    parallel, each ray carrying its walker and its visitor state (the pass-through
//!    rule's, for one) from wave `d` to `d + 1`.
//!
//! Tiles that are new to the map are staged and added at the end in the order the serial
//! walk would have allocated them (hits first, then by ray and by distance along it), so
//! the map's tile order, its known box and every count are as serial. An observation that
//! could need more tiles than the map's budget has room for (as many as the tiles of its
//! rays' bounding box) takes the serial walk, which alone decides what a map past its
//! budget holds: which tiles it still gets, and the one scratch tile the rest share.
//!
//! Observations whose rays start in several tiles (a camera's rays, a de-skewed scan
//! straddling a tile border), those of more than `u32::MAX` rays, and small ones, where
//! the waves would cost more than they save, take the serial walk. Cartographer inserts a
//! scan on one thread; OctoMap's OpenMP build casts a scan's rays on several threads and
//! merges their cells into sets before one update per cell, which works because it has no
//! per-ray state (such as the pass-through rule's) that depends on the cells before.

use super::walk::{ray_ends, walk_in_tile};
use super::{CellBox, CellIndex, CellRay, CellVisitor, GridGeometry, InsertStats, MarkedTile, TileKey, TileMap};
use crate::measurement::Ray;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

/// Below this many cell visits an observation takes the serial walk: a wave costs a few
/// microseconds of hand-over between threads, a cell visit a few nanoseconds.
pub const PARALLEL_MIN_CELLS: u64 = 100_000;

/// A visitor whose per-ray state can travel with its ray from one thread to another.
///
/// Each ray is walked by a [`fork`](Self::fork) of the observation's visitor (its
/// parameters, no counts, no ray state), which moves with the ray from tile to tile; when
/// the ray ends, [`join`](Self::join) adds what that copy counted. Counts are integers,
/// so their sum does not depend on the order rays end in.
pub trait RayFork<T>: CellVisitor<T> + Clone + Send + Sync {
    /// A copy with the same parameters, zero counts and no ray begun.
    fn fork(&self) -> Self;
    /// Ends the ray that `ray` (a [`fork`](Self::fork) of this visitor) walked and adds
    /// its counts to this visitor's.
    fn join(&mut self, ray: &Self);
}

/// The whole walk's visitor is `()`: nothing per ray.
impl<T> RayFork<T> for () {
    fn fork(&self) -> Self {}
    fn join(&mut self, _: &Self) {}
}

/// The part of one ray inside one tile, and what the ray carries to the next.
#[derive(Clone)]
struct Segment<V> {
    /// The tile this segment walks.
    key: TileKey,
    /// The ray's index in the observation (segments of a tile run in this order).
    ray: u32,
    walk: CellRay,
    visitor: V,
    /// `Some(first hit of its cell)` for a hit ray.
    end_hit: Option<bool>,
    /// The ray ended in this segment.
    done: bool,
    /// The segment's place among the wave's tiles.
    run: u32,
}

/// Where a tile of this observation lives.
#[derive(Clone, Copy)]
enum Slot {
    /// In the map, at this index.
    Map(usize),
    /// New, staged at this index.
    Staged(usize),
}

/// Position of a tile's first touch in the serial walk: (pass, ray, tile step).
type FirstTouch = (u8, u32, u32);

/// Tiles new to the map, held until the walk ends.
struct Staging<T> {
    index: HashMap<TileKey, usize, BuildHasherDefault<super::TileKeyHasher>>,
    tiles: Vec<(TileKey, Box<T>, FirstTouch)>,
}

impl<T: MarkedTile> Staging<T> {
    fn new() -> Self {
        Self { index: HashMap::default(), tiles: Vec::new() }
    }

    /// The slot of tile `key`, first touched (so far) at `touch`.
    fn slot(&mut self, map: &TileMap<T>, key: TileKey, touch: FirstTouch) -> Slot {
        if let Some(i) = map.index_of(key) {
            return Slot::Map(i);
        }
        if let Some(&j) = self.index.get(&key) {
            let t = &mut self.tiles[j].2;
            *t = (*t).min(touch);
            return Slot::Staged(j);
        }
        // The caller made sure the budget has room for every tile the rays can reach.
        debug_assert!(map.len() + self.tiles.len() < map.tile_budget());
        self.index.insert(key, self.tiles.len());
        self.tiles.push((key, Box::new(T::empty()), touch));
        Slot::Staged(self.tiles.len() - 1)
    }

    /// Adds the staged tiles to `map` in the order of their first touch.
    fn commit(mut self, map: &mut TileMap<T>) {
        self.tiles.sort_unstable_by_key(|t| t.2);
        for (key, tile, _) in self.tiles {
            map.adopt(key, tile);
        }
    }
}

/// Walks the rays of observation `obs` as [`walk_observation`](super::walk_observation)
/// does, with the same result to the bit, in waves of tiles over the pool's threads (see
/// the module docs). Returns `None`, having changed nothing, when the rays do not all
/// start in one tile, when they visit fewer than `min_cells` cells in all, when they are
/// more than `u32::MAX`, or when the tiles of their bounding box could outgrow the map's
/// tile budget: the caller then takes the serial walk.
pub fn walk_observation_waves<T: MarkedTile + Send, V: RayFork<T>>(
    tiles: &mut TileMap<T>,
    geometry: &GridGeometry,
    obs: u64,
    rays: &[Ray],
    known: &mut Option<CellBox>,
    visitor: &mut V,
    min_cells: u64,
) -> Option<InsertStats> {
    let ends: Vec<_> = rays.iter().map(ray_ends(geometry)).collect();
    let start = ends.iter().flatten().next()?.2.tile();
    if rays.len() > u32::MAX as usize {
        return None;
    }
    let mut cells = 0u64;
    let (mut lo, mut hi) = (start, start);
    for &(_, _, ca, cb) in ends.iter().flatten() {
        if ca.tile() != start {
            return None;
        }
        cells += ca.x.abs_diff(cb.x) + ca.y.abs_diff(cb.y) + 1;
        let t = cb.tile();
        (lo.x, lo.y, hi.x, hi.y) = (lo.x.min(t.x), lo.y.min(t.y), hi.x.max(t.x), hi.y.max(t.y));
    }
    let box_tiles = (hi.x.abs_diff(lo.x) as u128 + 1) * (hi.y.abs_diff(lo.y) as u128 + 1);
    if cells < min_cells || tiles.len() as u128 + box_tiles > tiles.tile_budget() as u128 {
        return None;
    }

    let mut stats = InsertStats { cell_visits: cells, ..InsertStats::default() };
    let mut staging = Staging::new();
    let mut segments = Vec::with_capacity(rays.len());
    let mut known_box = *known;
    for (i, (ray, end)) in rays.iter().zip(&ends).enumerate() {
        let Some((a, b, ca, cb)) = *end else {
            stats.rays_rejected += 1;
            continue;
        };
        stats.rays += 1;
        let k = CellBox {
            min: CellIndex::new(ca.x.min(cb.x), ca.y.min(cb.y)),
            max: CellIndex::new(ca.x.max(cb.x), ca.y.max(cb.y)),
        };
        known_box = Some(known_box.map_or(k, |kb| kb.union(k)));
        // Pass 1 of the serial walk: every hit's end cell is marked first.
        let end_hit = ray.hit.then(|| mark_hit(tiles, &mut staging, obs, cb, i as u32));
        stats.hit_updates += end_hit.unwrap_or(false) as u64;
        let walk = CellRay::new(a, b);
        let mut v = visitor.fork();
        v.begin_ray(walk.len_cells());
        segments.push(Segment { key: start, ray: i as u32, walk, visitor: v, end_hit, done: false, run: 0 });
    }

    let mut step = 0u32;
    loop {
        stats.miss_updates += wave(tiles, &mut staging, obs, step, &mut segments);
        segments.retain(|s| {
            if s.done {
                visitor.join(&s.visitor);
            }
            !s.done
        });
        if segments.is_empty() {
            break;
        }
        step += 1;
    }
    staging.commit(tiles);
    *known = known_box;
    Some(stats)
}

/// Marks the end cell `c` of hit ray `ray` (pass 1) and says whether it was its first hit.
fn mark_hit<T: MarkedTile>(tiles: &mut TileMap<T>, staging: &mut Staging<T>, obs: u64, c: CellIndex, ray: u32) -> bool {
    let tile = match staging.slot(tiles, c.tile(), (0, ray, 0)) {
        Slot::Map(i) => tiles.tile_at_mut(i),
        Slot::Staged(j) => &mut *staging.tiles[j].1,
    };
    let mark = tile.mark();
    mark.begin(obs);
    mark.test_and_set(c.offset_in_tile())
}

/// Walks every segment of wave `step` (those of rays not yet done, in ray order), each
/// tile's in ray order on one thread; moves each segment on to the tile its ray enters
/// next or marks it done. Returns the fresh visits.
fn wave<T: MarkedTile + Send, V: RayFork<T>>(
    tiles: &mut TileMap<T>,
    staging: &mut Staging<T>,
    obs: u64,
    step: u32,
    segments: &mut [Segment<V>],
) -> u64 {
    // The wave's tiles in the order of their first ray, each with its segments' count;
    // the segments are in ray order, so the first ray met is the tile's first touch.
    let mut runs: Vec<(Slot, usize)> = Vec::new();
    let mut run_of: HashMap<TileKey, u32, BuildHasherDefault<super::TileKeyHasher>> = HashMap::default();
    for s in segments.iter_mut() {
        let run = *run_of.entry(s.key).or_insert_with(|| {
            runs.push((staging.slot(tiles, s.key, (1, s.ray, step)), 0));
            runs.len() as u32 - 1
        });
        runs[run as usize].1 += 1;
        s.run = run;
    }
    let mut jobs: Vec<(&mut T, Vec<&mut Segment<V>>)> = disjoint_tiles(tiles, staging, &runs)
        .into_iter()
        .zip(&runs)
        .map(|(tile, r)| (tile, Vec::with_capacity(r.1)))
        .collect();
    // Segments are in ray order, so each tile's list is too.
    for s in segments.iter_mut() {
        jobs[s.run as usize].1.push(s);
    }
    // The largest tiles first: the pool's threads take the small ones last, so that they
    // finish the wave together (longest processing time first).
    jobs.sort_by_key(|j| std::cmp::Reverse(j.1.len()));
    let misses = crate::parallel::map_all_mut(&mut jobs, |(tile, run)| {
        tile.mark().begin(obs);
        let mut misses = 0;
        for s in run.iter_mut() {
            match walk_in_tile(&mut **tile, &mut s.walk, &mut s.visitor, s.end_hit, &mut misses) {
                Some(next) => s.key = next.tile(),
                None => s.done = true,
            }
        }
        misses
    });
    misses.iter().sum()
}

/// One `&mut` per run's tile, in the runs' order: map tiles and staged tiles picked apart
/// by index (each tile is one run's).
fn disjoint_tiles<'a, T: MarkedTile>(
    tiles: &'a mut TileMap<T>,
    staging: &'a mut Staging<T>,
    runs: &[(Slot, usize)],
) -> Vec<&'a mut T> {
    let mut in_map: Vec<(usize, usize)> = Vec::new();
    let mut staged: Vec<(usize, usize)> = Vec::new();
    for (r, (slot, _)) in runs.iter().enumerate() {
        match *slot {
            Slot::Map(i) => in_map.push((i, r)),
            Slot::Staged(j) => staged.push((j, r)),
        }
    }
    in_map.sort_unstable();
    staged.sort_unstable();
    let mut out: Vec<Option<&'a mut T>> = (0..runs.len()).map(|_| None).collect();
    for ((_, r), t) in in_map.iter().zip(tiles.tiles_at_mut(in_map.iter().map(|p| p.0))) {
        out[*r] = Some(t);
    }
    let staged_tiles = pick_mut(&mut staging.tiles, staged.iter().map(|p| p.0));
    for ((_, r), t) in staged.iter().zip(staged_tiles) {
        out[*r] = Some(&mut *t.1);
    }
    out.into_iter().map(|t| t.expect("every run has its tile")).collect()
}

/// `&mut` to the items at `indices` (strictly increasing) of `items`.
pub(super) fn pick_mut<T>(items: &mut [T], indices: impl Iterator<Item = usize>) -> Vec<&mut T> {
    let mut out = Vec::new();
    let mut rest = items;
    let mut base = 0;
    for i in indices {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(i - base);
        let (item, tail) = tail.split_first_mut().expect("indices within the items");
        out.push(item);
        rest = tail;
        base = i + 1;
    }
    out
}

#[cfg(test)]
#[path = "tile_waves_tests.rs"]
mod tests;
