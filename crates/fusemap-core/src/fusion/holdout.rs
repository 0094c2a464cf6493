//! The held-out period of the design document's leave-one-out validation (§5.2): the
//! observations of the log's later part are not inserted into any map; their endpoints
//! are counted instead, per sensor and cell, so that after the pass each sensor's hit
//! rate on each map (built from the earlier part alone) can be read.
//!
//! An endpoint is what a sensor claims is an obstacle: a lidar beam's return (a hit, not
//! a max-range pass), a camera pixel in the obstacle band of a class that is obstacle
//! evidence. Dynamic classes, floor-like classes and floor pixels claim no static
//! obstacle and are not counted.
//!
//! Counting per cell instead of keeping the points bounds the memory by the cells the
//! later period sees, not by its length; the hit rate is the same, since a map's verdict
//! on a point depends only on the cell it lands in.

use crate::grid::{logodds::logit, CellIndex, FusionGrid, GridGeometry};
use crate::measurement::{RangeData, SensorId};
use crate::sensor::camera::{Band, CameraObservation, ClassTable};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};

/// The occupancy above which a map cell is an obstacle hypothesis (§5.2: "cells with
/// occupancy > 0.8").
pub const OBSTACLE_PROBABILITY: f64 = 0.8;

/// Endpoints of the held-out observations, counted per sensor and cell.
#[derive(Clone, Debug, Default)]
pub struct HeldOut {
    counts: BTreeMap<SensorId, HashMap<CellIndex, u32>>,
    observations: BTreeMap<SensorId, u64>,
}

/// One sensor's held-out endpoints against one map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct HitRate {
    /// Endpoints of the held-out period.
    pub endpoints: u64,
    /// Those within one cell (8-neighbourhood) of one of the map's obstacle cells.
    pub hits: u64,
    /// `hits / endpoints`; `None` without endpoints.
    pub rate: Option<f64>,
}

impl HeldOut {
    /// Counts a lidar observation's returns (its rays that end in a hit).
    pub fn add_range_data(&mut self, data: &RangeData, geometry: &GridGeometry) {
        let cells = self.counts.entry(data.sensor).or_default();
        for r in data.rays.iter().filter(|r| r.hit) {
            if let Some(c) = geometry.cell_of(r.end) {
                let n = cells.entry(c).or_insert(0);
                *n = n.saturating_add(1);
            }
        }
        *self.observations.entry(data.sensor).or_insert(0) += 1;
    }

    /// Counts a camera frame's obstacle-band pixels of the classes that are obstacle
    /// evidence ([`ClassTable::is_static_obstacle`]).
    pub fn add_camera(&mut self, obs: &CameraObservation, classes: &ClassTable, geometry: &GridGeometry) {
        let cells = self.counts.entry(obs.sensor).or_default();
        for p in obs.points.iter().filter(|p| p.band == Band::Obstacle && classes.is_static_obstacle(p.class)) {
            if let Some(c) = geometry.cell_of(p.end) {
                let n = cells.entry(c).or_insert(0);
                *n = n.saturating_add(1);
            }
        }
        *self.observations.entry(obs.sensor).or_insert(0) += 1;
    }

    /// The sensors with held-out observations.
    pub fn sensors(&self) -> impl Iterator<Item = SensorId> + '_ {
        self.observations.keys().copied()
    }

    /// The held-out observations (scans, frames) of `sensor`.
    pub fn observations(&self, sensor: SensorId) -> u64 {
        self.observations.get(&sensor).copied().unwrap_or(0)
    }

    /// `sensor`'s hit rate on `map`: the share of its held-out endpoints that land within
    /// one cell of a cell of `map` with occupancy above [`OBSTACLE_PROBABILITY`]. Integer
    /// counts summed, so the result does not depend on the order of the cells.
    pub fn hit_rate(&self, sensor: SensorId, map: &FusionGrid) -> HitRate {
        let Some(cells) = self.counts.get(&sensor) else { return HitRate::default() };
        let threshold = logit(OBSTACLE_PROBABILITY) as f32;
        let obstacle = |c: CellIndex| map.log_odds(c).is_some_and(|l| l > threshold);
        let near = |c: CellIndex| (-1..=1).any(|dy| (-1..=1).any(|dx| obstacle(CellIndex::new(c.x + dx, c.y + dy))));
        let (mut endpoints, mut hits) = (0u64, 0u64);
        for (&c, &n) in cells {
            endpoints += n as u64;
            if near(c) {
                hits += n as u64;
            }
        }
        HitRate { endpoints, hits, rate: (endpoints > 0).then(|| hits as f64 / endpoints as f64) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::{GridGeometry, OccupancyParams};
    use crate::measurement::{Evidence, Ray};

    fn grid() -> FusionGrid {
        FusionGrid::new(GridGeometry::new(0.1, Point2::new(0.0, 0.0)).unwrap(), OccupancyParams::default())
    }

    fn data(ends: &[(f64, f64, bool)]) -> RangeData {
        RangeData {
            stamp: crate::time::Stamp::ZERO,
            sensor: SensorId(0),
            rays: ends
                .iter()
                .map(|&(x, y, hit)| Ray { origin: Point2::new(0.05, 0.05), end: Point2::new(x, y), hit })
                .collect(),
            evidence: Evidence { p_hit: 0.9, p_miss: 0.4 },
        }
    }

    #[test]
    fn counts_hits_within_one_cell_of_an_obstacle() {
        let mut map = grid();
        // A wall cell at (10, 0), made occupied by repeated hits.
        let mut wall = data(&[(1.05, 0.05, true)]);
        for k in 0..10 {
            wall.stamp = crate::time::Stamp(k);
            map.insert(&wall);
        }
        assert!(map.probability(CellIndex::new(10, 0)) > OBSTACLE_PROBABILITY);
        let g = *map.geometry();
        let mut held = HeldOut::default();
        // On the wall, one cell beside it, two cells beside it, and a pass (not counted).
        held.add_range_data(
            &data(&[(1.05, 0.05, true), (1.15, 0.15, true), (1.25, 0.05, true), (1.05, 0.05, false)]),
            &g,
        );
        let r = held.hit_rate(SensorId(0), &map);
        assert_eq!((r.endpoints, r.hits), (3, 2));
        assert_eq!(r.rate, Some(2.0 / 3.0));
        assert_eq!(held.observations(SensorId(0)), 1);
        assert_eq!(held.hit_rate(SensorId(1), &map), HitRate::default());
    }
}
