//! A camera frame into the maps: occupancy (weak, geometry-signed), the semantic layer,
//! the dynamic layer, and the camera's weak free evidence along its rays.
//!
//! Per frame and per cell, every layer is updated at most once (the tile's update mark):
//! the pixels of one frame that land in one cell are one look at it. For that cell:
//! * **occupancy**: the mean of its pixels' evidence (see
//!   [`CameraModel::occupancy_evidence`]: an obstacle-band pixel of a static class gives
//!   its class's probability, a floor-band pixel free evidence, each scaled by its depth
//!   weight and `occupancy_weight`); obstacle-band pixels take precedence over floor ones,
//!   as a hit does over a pass (OctoMap's rule). As a member of a correlation group the
//!   cell's evidence is merged with the lidar's (§2.4);
//! * **semantic**: the mean of its pixels' semantic weights, as Dirichlet evidence split
//!   over their static classes (at most one unit per frame while class weights are at
//!   most 1; see [`semantic`]);
//! * **dynamic**: pixels of a dynamic class there write the dynamic layer (never the static
//!   occupancy); floor seen there clears it.
//!
//! Then the cells between the camera and each cell that received an obstacle pixel get the
//! camera's weak free evidence once (§3.4: the camera's free-space evidence is poor),
//! except cells that received pixels themselves.

use super::{InsertContext, MapEntry, MapSet};
use crate::grid::{
    semantic, CellIndex, CellVisitor, DynamicUpdate, FusedUpdate, FusionGrid, FusionLayers, Group, InsertStats,
    LogOddsTable, MapTile,
};
use crate::measurement::{Ray, SensorKind};
use crate::sensor::camera::{Band, CameraModel, CameraObservation};

/// What one camera frame does to one cell, aggregated over its pixels.
#[derive(Clone, Debug, Default)]
pub(super) struct CellEvidence {
    pub cell: CellIndex,
    /// Sum of the obstacle-band static pixels' occupancy increments, and their count.
    obstacle: (f32, u32),
    /// Sum of the floor-band pixels' occupancy increments, and their count.
    floor: (f32, u32),
    /// Mean-weighted dynamic evidence scale (0: none).
    dynamic: f32,
    /// First index of this cell's votes in the frame's vote buffer.
    votes_at: usize,
}

/// A frame's evidence by cell, computed once per map geometry and reused.
#[derive(Default)]
pub(super) struct FrameCells {
    pub cells: Vec<CellEvidence>,
    votes: Vec<f32>,
    keys: Vec<(CellIndex, u32)>,
    rays: Vec<Ray>,
}

impl FrameCells {
    /// Aggregates `obs` per cell of `grid` with `table`'s log-odds.
    pub(super) fn build(&mut self, obs: &CameraObservation, model: &CameraModel, grid: &FusionGrid) {
        let classes = model.classes();
        let k = classes.len();
        let g = grid.geometry();
        let table = grid.table();
        self.keys.clear();
        for (i, p) in obs.points.iter().enumerate() {
            if let Some(c) = g.cell_of(p.end) {
                self.keys.push((c, i as u32));
            }
        }
        self.keys.sort_unstable_by_key(|&(c, _)| (c.y, c.x));
        self.cells.clear();
        self.votes.clear();
        let mut i = 0;
        while i < self.keys.len() {
            let cell = self.keys[i].0;
            let mut e = CellEvidence { cell, votes_at: self.votes.len(), ..Default::default() };
            self.votes.resize(self.votes.len() + k, 0.0);
            let (mut n, mut dyn_sum, mut dyn_n) = (0u32, 0.0f32, 0u32);
            while i < self.keys.len() && self.keys[i].0 == cell {
                let p = &obs.points[self.keys[i].1 as usize];
                let spec = classes.get(p.class);
                n += 1;
                match model.occupancy_evidence(p, classes) {
                    Some((prob, scale)) => {
                        let d = scale * table.increment(prob);
                        match p.band {
                            Band::Obstacle => (e.obstacle.0 += d, e.obstacle.1 += 1),
                            Band::Floor => (e.floor.0 += d, e.floor.1 += 1),
                        };
                    }
                    None => {
                        if spec.dynamic && p.band == Band::Obstacle {
                            dyn_sum += spec.weight as f32 * p.weight;
                            dyn_n += 1;
                        }
                    }
                }
                if !spec.dynamic {
                    self.votes[e.votes_at + p.class as usize] += model.semantic_weight(p, classes);
                }
                i += 1;
            }
            for v in &mut self.votes[e.votes_at..e.votes_at + k] {
                *v /= n as f32;
            }
            if dyn_n > 0 {
                e.dynamic = dyn_sum / dyn_n as f32;
            }
            self.cells.push(e);
        }
        // Free evidence along the rays to the obstacle points only: the floor between the
        // camera and a floor point is seen by the floor pixels themselves (the rows below),
        // and a ray to an obstacle crosses the floor cells a stride skips.
        let origin = obs.origin;
        self.rays.clear();
        self.rays.extend(self.cells.iter().filter(|e| e.obstacle.1 > 0 || e.dynamic > 0.0).map(|e| Ray {
            origin,
            end: g.cell_center(e.cell),
            hit: false,
        }));
    }

    /// Writes the frame into `grid` as observation number `obs` (begun by the caller).
    pub(super) fn apply(
        &self,
        grid: &mut FusionGrid,
        k: usize,
        free_delta: f32,
        group: Option<Group>,
        dynamic: Option<DynamicUpdate>,
    ) -> InsertStats {
        let table = *grid.table();
        let obs = grid.begin_observation();
        let mut stats = InsertStats::default();
        for e in &self.cells {
            let Some((tile, offset, fresh)) = grid.cell_mut(e.cell, obs) else { continue };
            if !fresh {
                continue;
            }
            let delta = if e.obstacle.1 > 0 {
                stats.hit_updates += 1;
                Some(e.obstacle.0 / e.obstacle.1 as f32)
            } else if e.floor.1 > 0 {
                stats.miss_updates += 1;
                Some(e.floor.0 / e.floor.1 as f32)
            } else {
                None
            };
            if let Some(d) = delta {
                FusedUpdate::occupancy(&table, group, tile, offset, d);
            }
            let votes = &self.votes[e.votes_at..e.votes_at + k];
            if votes.iter().any(|&v| v > 0.0) {
                tile.layers_mut().add_semantic(offset, votes);
            }
            if let Some(dy) = &dynamic {
                if e.dynamic > 0.0 {
                    dy.apply(&mut tile.layers_mut().dynamic, offset, e.dynamic * dy.d_hit());
                    stats.dynamic_updates += 1;
                } else if e.floor.1 > 0 {
                    dy.clear(&mut tile.layers_mut().dynamic, offset);
                }
            }
        }
        let mut free = CameraFree { table, delta: free_delta, group, dynamic };
        let walk = grid.walk_observation_rays(obs, &self.rays, &mut free);
        stats.rays += walk.rays;
        stats.rays_rejected += walk.rays_rejected;
        stats.cell_visits += walk.cell_visits;
        stats.miss_updates += walk.miss_updates;
        stats
    }
}

/// Writes a projected frame `obs` of camera `model` into every map of `maps` that takes
/// it, and returns each fed map's counts. The frame's cells are built once for each grid
/// geometry and log-odds table among those maps (one in practice), and applied to that
/// group's maps on the pool's threads (see [`MapSet::each_taking`]).
pub(super) fn insert_frame(
    maps: &mut MapSet,
    cells: &mut FrameCells,
    obs: &CameraObservation,
    model: &CameraModel,
    ctx: &InsertContext,
) -> Vec<InsertStats> {
    let takes = |m: &MapEntry| m.sensors().includes(obs.sensor, SensorKind::Camera);
    let key = |m: &MapEntry| (*m.grid().geometry(), *m.grid().table());
    let mut groups = Vec::new();
    for m in maps.iter().filter(|m| takes(m)) {
        if !groups.contains(&key(m)) {
            groups.push(key(m));
        }
    }
    let k = model.classes().len();
    let (p_free, weight) = (model.params().p_free, model.params().occupancy_weight as f32);
    let mut each = Vec::new();
    for group in groups {
        let Some(first) = maps.iter().find(|m| takes(m) && key(m) == group) else { continue };
        cells.build(obs, model, first.grid());
        let cells = &*cells;
        each.extend(maps.each_taking(
            |m| takes(m) && key(m) == group,
            |m| {
                let free = weight * m.grid().table().increment(p_free);
                let s = cells.apply(m.grid_mut(), k, free, ctx.group, ctx.dynamic);
                m.add_stats(&s);
                s
            },
        ));
    }
    each
}

/// The camera's weak free evidence along its rays, on cells no pixel landed in.
struct CameraFree {
    table: LogOddsTable,
    delta: f32,
    group: Option<Group>,
    dynamic: Option<DynamicUpdate>,
}

impl CellVisitor<MapTile<FusionLayers>> for CameraFree {
    #[inline]
    fn hit(&mut self, _: &mut MapTile<FusionLayers>, _: usize, _: bool) {}

    #[inline]
    fn pass(&mut self, tile: &mut MapTile<FusionLayers>, offset: usize, fresh: bool) {
        if fresh {
            FusedUpdate::occupancy(&self.table, self.group, tile, offset, self.delta);
            if let Some(dy) = &self.dynamic {
                dy.clear(&mut tile.layers_mut().dynamic, offset);
            }
        }
    }
}

/// The semantic distribution of a cell (see [`semantic::distribution`]): `eligible` has one
/// entry per class of the table, false for ignored classes.
pub fn cell_semantics(
    tile: &MapTile<FusionLayers>,
    offset: usize,
    eligible: &[bool],
    out: &mut [f32],
) -> Option<(usize, f32)> {
    let counts = tile.layers().semantic_counts(offset, eligible.len())?;
    semantic::distribution(counts, eligible, out)
}
