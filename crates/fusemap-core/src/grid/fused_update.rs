//! What one range observation does to each cell of a fusion map: the occupancy update
//! (merged with its correlation group's, when it belongs to one), and the dynamic layer's
//! routing and clearing.

use super::{
    CellVisitor, DynamicUpdate, FusionLayers, Group, LogOddsTable, MapTile, OccupancyUpdate, PassThroughParams, RayFork,
};
use crate::measurement::Evidence;

/// The per-cell update of a range observation into a [`FusionGrid`](super::FusionGrid).
///
/// * Occupancy: the hit or miss increment of the evidence, once per observation, with the
///   pass-through rule of [`PassThroughParams`] on the misses ([`OccupancyUpdate`]); as a
///   member of a correlation [`Group`], merged with the group's other members.
/// * Dynamic layer (when given): a hit on a cell that holds a dynamic object now goes to
///   the dynamic layer instead of the static one (a lidar return from a person the camera
///   labelled, §2.4), when routing is on; a ray crossing a cell the dynamic layer holds
///   clears it there (the object has left).
///
/// An observation with neither a group nor a dynamic layer does not need it: it takes the
/// plain occupancy insertion ([`LayeredGrid::insert`](super::LayeredGrid::insert)).
#[derive(Clone, Debug)]
pub struct FusedUpdate {
    /// The occupancy update with the pass-through rule: its increments and its ray state.
    occ: OccupancyUpdate,
    group: Option<Group>,
    dynamic: Option<DynamicUpdate>,
    route_hits: bool,
    /// Hits routed to the dynamic layer so far.
    pub routed: u64,
    /// Hits whose ray was still behind a confidently occupied cell at its end.
    ghosts: u64,
}

impl FusedUpdate {
    /// The update for `evidence` against the map's `table`, with the pass-through rule
    /// `pass_through` (cells below the free threshold it gives end it).
    pub fn new(
        table: LogOddsTable,
        evidence: Evidence,
        pass_through: (&PassThroughParams, f64),
        group: Option<Group>,
        dynamic: Option<DynamicUpdate>,
        route_hits: bool,
    ) -> Self {
        let occ = OccupancyUpdate::new(table, evidence).with_pass_through(pass_through.0, pass_through.1);
        Self { occ, group, dynamic, route_hits, routed: 0, ghosts: 0 }
    }

    /// Applies an occupancy increment to a cell on its first visit of the observation.
    #[inline(always)]
    pub fn occupancy(
        table: &LogOddsTable,
        group: Option<Group>,
        tile: &mut MapTile<FusionLayers>,
        offset: usize,
        delta: f32,
    ) {
        match group {
            None => tile.update_log_odds(offset, delta, table, true),
            Some(g) => {
                let (l, layers) = tile.parts_mut(offset);
                g.update(&mut layers.group, l, offset, delta, table);
            }
        }
    }
}

impl FusedUpdate {
    /// Ends the last ray; call after the walk.
    pub fn finish(&mut self) {
        self.occ.finish();
    }

    /// Cell visits at which the pass-through rule's reduced weight applied.
    pub fn attenuated(&self) -> u64 {
        self.occ.attenuated()
    }

    /// Hits whose ray had passed through a confidently occupied cell (see
    /// [`InsertStats::ghost_hits`](super::InsertStats::ghost_hits)).
    pub fn ghost_hits(&self) -> u64 {
        self.ghosts
    }
}

impl CellVisitor<MapTile<FusionLayers>> for FusedUpdate {
    #[inline(always)]
    fn hit(&mut self, tile: &mut MapTile<FusionLayers>, offset: usize, fresh: bool) {
        if !fresh {
            return;
        }
        if let Some(dy) = &self.dynamic {
            if self.route_hits && dy.is_dynamic(tile.layers().dynamic(), offset) {
                dy.apply(&mut tile.layers_mut().dynamic, offset, dy.d_hit());
                self.routed += 1;
                return;
            }
        }
        Self::occupancy(self.occ.table(), self.group, tile, offset, self.occ.hit_increment());
    }

    #[inline(always)]
    fn pass(&mut self, tile: &mut MapTile<FusionLayers>, offset: usize, fresh: bool) {
        // The walk calls `pass_at`; without the distance to the ray's end, a plain miss.
        self.pass_at(tile, offset, fresh, u64::MAX);
    }

    #[inline(always)]
    fn pass_at(&mut self, tile: &mut MapTile<FusionLayers>, offset: usize, fresh: bool, cells_after: u64) {
        // The rule's state follows every visit of the ray, fresh or not.
        let v = tile.log_odds(offset).unwrap_or(f32::NAN);
        let d = self.occ.miss_increment(v, cells_after);
        // No evidence (behind a confident cell) is not a zero vote: the cell, its group
        // merge and the dynamic layer are left alone.
        if !fresh || d == 0.0 {
            return;
        }
        Self::occupancy(self.occ.table(), self.group, tile, offset, d);
        if let Some(dy) = &self.dynamic {
            dy.clear(&mut tile.layers_mut().dynamic, offset);
        }
    }

    #[inline(always)]
    fn end_hit(&mut self, tile: &mut MapTile<FusionLayers>, offset: usize, fresh: bool) {
        self.ghosts += (self.occ.is_through() && fresh) as u64;
        self.hit(tile, offset, fresh);
    }

    #[inline(always)]
    fn begin_ray(&mut self, cells: u64) {
        CellVisitor::<MapTile<FusionLayers>>::begin_ray(&mut self.occ, cells);
    }
}

/// A ray's copy carries the pass-through state; the group merge and the dynamic layer keep
/// theirs in the cells, which one thread at a time updates in ray order.
impl RayFork<MapTile<FusionLayers>> for FusedUpdate {
    fn fork(&self) -> Self {
        Self { occ: RayFork::<MapTile<FusionLayers>>::fork(&self.occ), routed: 0, ghosts: 0, ..self.clone() }
    }

    fn join(&mut self, ray: &Self) {
        RayFork::<MapTile<FusionLayers>>::join(&mut self.occ, &ray.occ);
        self.routed += ray.routed;
        self.ghosts += ray.ghosts;
    }
}
