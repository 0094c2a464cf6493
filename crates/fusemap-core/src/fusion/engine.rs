//! The engine that feeds time-ordered measurements from any number of sensors into the
//! map's layers.
//!
//! Sensors are registered with their models; each measurement names its sensor. The
//! engine keeps the per-sensor counters a user needs to judge a run (how many returns of
//! each kind, how many scans), and refuses a measurement older than the last one it took:
//! updates must be applied in time order for the result not to depend on who delivered
//! first (the role of Cartographer's `OrderedMultiQueue`, which sorts upstream).

use crate::geometry::Pose2;
use crate::grid::{InsertStats, OccupancyGrid};
use crate::measurement::{RangeData, SensorId};
use crate::sensor::{LaserScan, LidarModel, ReturnCounts};
use crate::time::Stamp;
use serde::Serialize;

/// Why the engine refused a measurement.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EngineError {
    /// No sensor with this id was registered.
    #[error("unknown sensor id {0:?}")]
    UnknownSensor(SensorId),
    /// The measurement is older than one already applied.
    #[error("measurement at {stamp:?} from sensor {sensor:?} is older than the last applied ({last:?})")]
    OutOfOrder {
        /// The sensor.
        sensor: SensorId,
        /// Its stamp.
        stamp: Stamp,
        /// The newest stamp applied so far.
        last: Stamp,
    },
}

/// Per-sensor counters.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SensorStats {
    /// The sensor's name (its frame id).
    pub name: String,
    /// Scans inserted.
    pub scans: u64,
    /// Beams by kind of return.
    pub returns: ReturnCounts,
}

/// Counters of a whole run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EngineStats {
    /// Measurements inserted.
    pub measurements: u64,
    /// Measurements refused for being out of time order.
    pub out_of_order: u64,
    /// What the insertions did.
    pub insert: InsertStats,
}

struct LidarSlot {
    model: LidarModel,
    stats: SensorStats,
}

/// The fusion engine.
pub struct Engine {
    grid: OccupancyGrid,
    lidars: Vec<LidarSlot>,
    scratch: RangeData,
    last: Option<Stamp>,
    stats: EngineStats,
}

impl Engine {
    /// An engine writing into `grid`.
    pub fn new(grid: OccupancyGrid) -> Self {
        let evidence = crate::measurement::Evidence { p_hit: 0.5, p_miss: 0.5 };
        Self {
            grid,
            lidars: Vec::new(),
            scratch: RangeData::empty(SensorId(0), evidence),
            last: None,
            stats: EngineStats::default(),
        }
    }

    /// Registers a lidar and returns its id.
    pub fn add_lidar(&mut self, name: impl Into<String>, model: LidarModel) -> SensorId {
        let id = SensorId(self.lidars.len() as u16);
        self.lidars.push(LidarSlot { model, stats: SensorStats { name: name.into(), ..Default::default() } });
        id
    }

    /// The map.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// Consumes the engine, returning the map.
    pub fn into_grid(self) -> OccupancyGrid {
        self.grid
    }

    /// Run counters.
    pub fn stats(&self) -> &EngineStats {
        &self.stats
    }

    /// Per-sensor counters, in registration order.
    pub fn sensor_stats(&self) -> impl Iterator<Item = &SensorStats> {
        self.lidars.iter().map(|s| &s.stats)
    }

    fn check_order(&mut self, sensor: SensorId, stamp: Stamp) -> Result<(), EngineError> {
        if let Some(last) = self.last {
            if stamp < last {
                self.stats.out_of_order += 1;
                return Err(EngineError::OutOfOrder { sensor, stamp, last });
            }
        }
        self.last = Some(stamp);
        Ok(())
    }

    /// Inserts a lidar scan taken when the robot was at `world_from_base`.
    pub fn insert_scan(
        &mut self,
        sensor: SensorId,
        scan: &LaserScan,
        world_from_base: Pose2,
    ) -> Result<InsertStats, EngineError> {
        self.insert_scan_with(sensor, scan, |_| world_from_base)
    }

    /// Inserts a lidar scan with the robot pose given per beam (de-skew).
    pub fn insert_scan_with(
        &mut self,
        sensor: SensorId,
        scan: &LaserScan,
        pose_of_beam: impl FnMut(usize) -> Pose2,
    ) -> Result<InsertStats, EngineError> {
        // NaN limits are "not stated": the model's own limits apply.
        self.insert_scan_limited(sensor, scan, f32::NAN, f32::NAN, pose_of_beam)
    }

    /// Inserts a scan with the sensor's own stated range limits (see
    /// [`LidarModel::limited_to`]) and the robot pose per beam.
    pub fn insert_scan_limited(
        &mut self,
        sensor: SensorId,
        scan: &LaserScan,
        range_min: f32,
        range_max: f32,
        pose_of_beam: impl FnMut(usize) -> Pose2,
    ) -> Result<InsertStats, EngineError> {
        if self.lidars.get(sensor.0 as usize).is_none() {
            return Err(EngineError::UnknownSensor(sensor));
        }
        self.check_order(sensor, scan.stamp)?;
        let slot = &mut self.lidars[sensor.0 as usize];
        let model = slot.model.limited_to(range_min, range_max);
        model.scan_to_range_data_with(sensor, scan, pose_of_beam, &mut self.scratch, &mut slot.stats.returns);
        slot.stats.scans += 1;
        Ok(apply(&mut self.grid, &mut self.stats, &self.scratch))
    }

    /// The model registered for `sensor`.
    pub fn lidar_model(&self, sensor: SensorId) -> Option<&LidarModel> {
        self.lidars.get(sensor.0 as usize).map(|s| &s.model)
    }

    /// Inserts range data a sensor model outside the engine produced.
    pub fn insert_range_data(&mut self, data: &RangeData) -> Result<InsertStats, EngineError> {
        self.check_order(data.sensor, data.stamp)?;
        Ok(apply(&mut self.grid, &mut self.stats, data))
    }
}

/// Inserts one observation into the grid and counts it.
fn apply(grid: &mut OccupancyGrid, stats: &mut EngineStats, data: &RangeData) -> InsertStats {
    let s = grid.insert(data);
    stats.measurements += 1;
    stats.insert.add(&s);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::PlanarMount;
    use crate::grid::{GridGeometry, OccupancyParams};
    use crate::sensor::LidarParams;

    fn engine() -> (Engine, SensorId, SensorId) {
        let grid = OccupancyGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let mut e = Engine::new(grid);
        let a = e.add_lidar("front", LidarModel::new(LidarParams::default(), PlanarMount::default()));
        let b = e.add_lidar("rear", LidarModel::new(LidarParams::default(), PlanarMount::default()));
        (e, a, b)
    }

    fn scan(t: i64) -> LaserScan {
        LaserScan { stamp: Stamp(t), angle_min: 0.0, angle_increment: 0.1, ranges: vec![1.0, f32::NAN] }
    }

    #[test]
    fn two_sensors_interleaved_in_time() {
        let (mut e, a, b) = engine();
        e.insert_scan(a, &scan(1), Pose2::IDENTITY).unwrap();
        e.insert_scan(b, &scan(2), Pose2::IDENTITY).unwrap();
        e.insert_scan(a, &scan(2), Pose2::IDENTITY).unwrap();
        let err = e.insert_scan(b, &scan(1), Pose2::IDENTITY).unwrap_err();
        assert!(matches!(err, EngineError::OutOfOrder { .. }));
        assert_eq!(e.stats().measurements, 3);
        assert_eq!(e.stats().out_of_order, 1);
        let s: Vec<_> = e.sensor_stats().cloned().collect();
        assert_eq!(s[0].scans, 2);
        assert_eq!(s[0].returns.nan, 2);
        assert_eq!(s[1].scans, 1);
        assert_eq!(s[1].name, "rear");
        assert!(e.insert_scan(SensorId(9), &scan(5), Pose2::IDENTITY).is_err());
    }
}
