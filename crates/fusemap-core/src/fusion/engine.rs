//! The engine that feeds time-ordered observations from any number of sensors into one or
//! several maps.
//!
//! Sensors are registered by kind with their models ([`SensorModel`]); each observation
//! names its sensor and, on the `*_observed` paths, carries an [`ObservationId`] the
//! caller supplies. The engine keeps per-sensor counters on every insert path (how many
//! observations, returns of each kind, refusals, shared ids, what the insertions did), and
//! refuses an observation older than the last one it took: updates must be applied in
//! time order for the result not to depend on who delivered first (the role of
//! Cartographer's `OrderedMultiQueue`, which sorts upstream).
//!
//! **One pass, several maps.** The engine writes a [`MapSet`]: each observation is turned
//! into rays once by its sensor's model and inserted into every map whose
//! [`SensorSelection`](super::SensorSelection) takes its sensor. [`Engine::new`] is the
//! single map taking every sensor.
//!
//! **Correlated observations are counted once.** Sensors declared correlated
//! ([`Correlation`]: a lidar and the camera whose frames are taken with its scans) have
//! their observations within the window merged per cell into one equivalent observation
//! ([`MergeRule`](crate::grid::MergeRule)), never summed as independent (design document
//! §2.4). Two observations of the same instant that carry the same id are counted in
//! [`EngineStats::shared_ids`]; ids are compared within one instant only, so the memory
//! this takes is bounded by the observations of one stamp.
//!
//! **Dynamic layer.** With [`Engine::set_dynamic`], the maps carry a dynamic-object layer:
//! lidar hits on cells that hold a dynamic object now go there instead of the static
//! occupancy (when routing is on), and rays through it clear it.

use super::budget::{BudgetKey, MapBudget, TileLayers};
use super::camera::FrameCells;
use super::correlation::Correlator;
use super::sensors::SensorSlot;
use super::{Correlation, HeldOut, InsertContext, MapEntry, MapSet, SensorModel, SensorSelection, SensorStats};
use crate::geometry::Pose2;
use crate::grid::{DynamicParams, DynamicUpdate, FusionGrid, Group, InsertStats};
use crate::measurement::{Evidence, ObservationId, RangeData, SensorId, SensorKind};
use crate::sensor::camera::{CameraModel, CameraObservation, DepthImage, LabelImage};
use crate::sensor::{LaserScan, LidarModel};
use crate::time::Stamp;
use std::collections::HashSet;

/// Why the engine refused a measurement.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
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
    /// A camera frame that does not fit its camera (image sizes).
    #[error("camera {sensor:?}: {error}")]
    Camera {
        /// The sensor.
        sensor: SensorId,
        /// Why.
        error: crate::sensor::camera::CameraError,
    },
    /// The sensor's registered model cannot read this kind of measurement (a lidar scan
    /// for a sensor whose model runs outside the engine).
    #[error("sensor {sensor:?} is a {kind:?} sensor without a lidar model in the engine")]
    WrongModel {
        /// The sensor.
        sensor: SensorId,
        /// Its registered kind.
        kind: SensorKind,
    },
    /// The observation needed more map than `[limits]` allows (`memory_mib`, or the cap in
    /// cells `map_cells`). The maps missed part of it: the run must stop.
    #[error(
        "the maps reached {} at the measurement stamped {:.6} s: {maps} map(s) of at most {tiles} tile(s) of 64 x 64, \
         {tile_bytes} bytes a tile with their layers; raise {}, coarsen map.resolution, or look for poses far from the rest",
        budget_limit(*.key, *.limit), .stamp.as_secs_f64(), budget_key(*.key)
    )]
    MapBudget {
        /// The limit that was met.
        key: BudgetKey,
        /// Its value (MiB or cells).
        limit: u64,
        /// Tiles each map may hold.
        tiles: usize,
        /// Bytes a tile of every map together can hold.
        tile_bytes: usize,
        /// Maps written.
        maps: usize,
        /// The stamp of the observation that met it.
        stamp: Stamp,
    },
}

fn budget_key(key: BudgetKey) -> &'static str {
    match key {
        BudgetKey::MemoryMib => "limits.memory_mib",
        BudgetKey::MapCells => "limits.map_cells",
    }
}

fn budget_limit(key: BudgetKey, limit: u64) -> String {
    match key {
        BudgetKey::MemoryMib => format!("limits.memory_mib = {limit} MiB"),
        BudgetKey::MapCells => format!("limits.map_cells = {limit} cells"),
    }
}

/// Counters of a whole run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EngineStats {
    /// Measurements inserted.
    pub measurements: u64,
    /// Measurements refused for being out of time order.
    pub out_of_order: u64,
    /// Measurements refused because their sensor was not registered (or its model cannot
    /// read them).
    pub unknown_sensor: u64,
    /// Measurements whose observation id an earlier measurement of the same instant
    /// already carried.
    pub shared_ids: u64,
    /// Observations merged into a correlation group another observation had opened.
    pub correlated_merged: u64,
    /// What the insertions did, summed over the maps that took them (with one map, that
    /// map's counts).
    pub insert: InsertStats,
}

/// The fusion engine.
pub struct Engine {
    pub(super) maps: MapSet,
    sensors: Vec<SensorSlot>,
    scratch: RangeData,
    camera_scratch: CameraObservation,
    frame_cells: FrameCells,
    last: Option<Stamp>,
    /// Observation ids applied at stamp `last`.
    ids_at_last: HashSet<ObservationId>,
    correlator: Correlator,
    dynamic: Option<(DynamicParams, bool)>,
    stats: EngineStats,
    /// `[limits]` as tiles per map, once set (the grids hold it).
    budget: Option<MapBudget>,
    /// Once [`Engine::hold_out`] is called: the later period's endpoints, counted instead
    /// of inserted.
    held_out: Option<HeldOut>,
}

impl Engine {
    /// An engine writing into `grid`, which takes every sensor.
    pub fn new(grid: FusionGrid) -> Self {
        Self::with_maps(MapSet::new("map", SensorSelection::All, grid))
    }

    /// An engine writing into several maps in one pass (see the module docs).
    pub fn with_maps(maps: MapSet) -> Self {
        let evidence = Evidence { p_hit: 0.5, p_miss: 0.5 };
        Self {
            maps,
            sensors: Vec::new(),
            scratch: RangeData::empty(SensorId(0), evidence),
            camera_scratch: CameraObservation::empty(SensorId(0)),
            frame_cells: FrameCells::default(),
            last: None,
            ids_at_last: HashSet::new(),
            correlator: Correlator::default(),
            dynamic: None,
            stats: EngineStats::default(),
            budget: None,
            held_out: None,
        }
    }

    /// From now on, observations are not inserted: their endpoints are counted in a
    /// [`HeldOut`] (the later period of §5.2's validation). The maps keep what the earlier
    /// period made of them.
    pub fn hold_out(&mut self) {
        self.held_out.get_or_insert_with(HeldOut::default);
    }

    /// The held-out period's endpoints, if [`Engine::hold_out`] was called.
    pub fn held_out(&self) -> Option<&HeldOut> {
        self.held_out.as_ref()
    }

    /// Holds the maps to `[limits] memory_mib` and `map_cells` (see
    /// [`LimitsConfig`](crate::config::LimitsConfig) and `budget.rs`): the observation that
    /// would need more tiles is refused with [`EngineError::MapBudget`], after which the
    /// maps are incomplete. Sensors, correlation and the dynamic layer set afterwards are
    /// counted too.
    pub fn set_limits(&mut self, limits: &crate::config::LimitsConfig) {
        self.budget = Some(MapBudget::new(*limits, &[]));
        self.apply_budget();
    }

    /// Recomputes the tiles each map may hold from the layers its tiles may carry.
    fn apply_budget(&mut self) {
        let Some(b) = self.budget else { return };
        let layers: Vec<TileLayers> = self.maps.iter().map(|m| self.tile_layers(m)).collect();
        let budget = MapBudget::new(b.limits, &layers);
        self.budget = Some(budget);
        for m in self.maps.entries_mut() {
            m.grid_mut().set_tile_budget(budget.tiles);
        }
    }

    /// Bytes `[limits] memory_mib` leaves for exporting one map beside the tiles all the
    /// maps hold now, and the bytes a cell of `map`'s dense export takes (see `budget.rs`);
    /// `None` without limits. A map's tiles always fit it; a dense raster of its observed
    /// box may not.
    pub fn export_room(&self, map: &MapEntry) -> Option<(u64, usize)> {
        let b = self.budget?;
        let per_cell = super::budget::export_bytes_per_cell(self.tile_layers(map).semantic_classes);
        Some((b.limits.memory_bytes().saturating_sub(self.tile_bytes()), per_cell))
    }

    /// The bytes the maps take now, their tiles with what exporting them as stored
    /// reserves (the largest map's, as they are written one at a time; see `budget.rs`),
    /// and `[limits] memory_mib` in bytes; `None` without limits. What a run keeps beside
    /// the maps, such as the lidar returns for endpoint clouds, must fit in the difference.
    pub fn memory_use(&self) -> Option<(u64, u64)> {
        let b = self.budget?;
        let export = self.maps.iter().map(|m| (m.grid().tile_count() * self.tile_layers(m).export_bytes()) as u64);
        Some((self.tile_bytes() + export.max().unwrap_or(0), b.limits.memory_bytes()))
    }

    /// Bytes every map's tiles take now, with every layer they can come to carry.
    fn tile_bytes(&self) -> u64 {
        self.maps.iter().map(|m| (m.grid().tile_count() * self.tile_layers(m).tile_bytes()) as u64).sum()
    }

    /// The layers `map`'s tiles may come to carry.
    fn tile_layers(&self, map: &MapEntry) -> TileLayers {
        let semantic_classes = (self.sensors.iter().enumerate())
            .filter_map(|(i, s)| match &s.model {
                SensorModel::Camera(m) if map.sensors().includes(SensorId(i as u16), SensorKind::Camera) => {
                    Some(m.classes().len())
                }
                _ => None,
            })
            .max()
            .unwrap_or(0);
        TileLayers { semantic_classes, dynamic: self.dynamic.is_some(), correlated: !self.correlator.is_empty() }
    }

    /// The error for a map past its budget after the observation at `stamp`, if any.
    fn check_budget(&self, stamp: Stamp) -> Result<(), EngineError> {
        match (self.budget, self.maps.iter().any(|m| m.grid().over_budget())) {
            (Some(b), true) => Err(EngineError::MapBudget {
                key: b.key,
                limit: match b.key {
                    BudgetKey::MemoryMib => b.limits.memory_mib,
                    BudgetKey::MapCells => b.limits.map_cells,
                },
                tiles: b.tiles,
                tile_bytes: b.bytes_per_tile,
                maps: self.maps.iter().count(),
                stamp,
            }),
            _ => Ok(()),
        }
    }

    /// Declares correlated sensors (see the module docs). Call before inserting.
    pub fn set_correlation(&mut self, correlation: Correlation) {
        self.correlator = Correlator::new(correlation);
        self.apply_budget();
    }

    /// Walks range observations of at least `min_cells` cell visits in waves of tiles on
    /// the pool's threads (see [`MapSet::set_waves_min_cells`]); the maps are the same.
    pub fn set_waves_min_cells(&mut self, min_cells: u64) {
        self.maps.set_waves_min_cells(min_cells);
    }

    /// Gives the maps a dynamic-object layer with `params`; `route_hits`: lidar hits on
    /// cells holding a dynamic object go there instead of the static layer.
    pub fn set_dynamic(&mut self, params: DynamicParams, route_hits: bool) {
        self.dynamic = Some((params, route_hits));
        self.apply_budget();
    }

    /// The dynamic layer's parameters, if the maps carry one.
    pub fn dynamic_params(&self) -> Option<&DynamicParams> {
        self.dynamic.as_ref().map(|(p, _)| p)
    }

    /// How an observation at `stamp` in correlation `group` is inserted.
    fn context(&self, stamp: Stamp, group: Option<Group>) -> InsertContext {
        InsertContext {
            group,
            dynamic: self.dynamic.map(|(p, _)| DynamicUpdate::new(&p, stamp)),
            route_hits: self.dynamic.is_some_and(|(_, r)| r),
        }
    }

    /// Registers a sensor with its model and returns its id.
    pub fn add_sensor(&mut self, name: impl Into<String>, model: SensorModel) -> SensorId {
        let id = SensorId(self.sensors.len() as u16);
        let name = name.into();
        self.maps.register(id, &name);
        self.sensors.push(SensorSlot::new(name, model));
        self.apply_budget();
        id
    }

    /// Registers a lidar and returns its id.
    pub fn add_lidar(&mut self, name: impl Into<String>, model: LidarModel) -> SensorId {
        self.add_sensor(name, SensorModel::Lidar(model))
    }

    /// The primary map.
    pub fn grid(&self) -> &FusionGrid {
        self.maps.primary().grid()
    }

    /// Consumes the engine, returning the primary map.
    pub fn into_grid(self) -> FusionGrid {
        self.maps.into_primary()
    }

    /// Every map the engine writes, primary first.
    pub fn maps(&self) -> &MapSet {
        &self.maps
    }

    /// Consumes the engine, returning its maps.
    pub fn into_maps(self) -> MapSet {
        self.maps
    }

    /// The stamp of the newest observation applied, `None` before the first.
    pub fn last_stamp(&self) -> Option<Stamp> {
        self.last
    }

    /// Run counters.
    pub fn stats(&self) -> &EngineStats {
        &self.stats
    }

    /// Per-sensor counters, in registration order.
    pub fn sensor_stats(&self) -> impl Iterator<Item = &SensorStats> {
        self.sensors.iter().map(|s| &s.stats)
    }

    /// The model registered for `sensor`, if it is a lidar.
    pub fn lidar_model(&self, sensor: SensorId) -> Option<&LidarModel> {
        match self.sensors.get(sensor.0 as usize).map(|s| &s.model) {
            Some(SensorModel::Lidar(m)) => Some(m),
            _ => None,
        }
    }

    /// Registers a semantic camera and returns its id.
    pub fn add_camera(&mut self, name: impl Into<String>, model: CameraModel) -> SensorId {
        self.add_sensor(name, SensorModel::Camera(Box::new(model)))
    }

    /// The model registered for `sensor`, if it is a camera.
    pub fn camera_model(&self, sensor: SensorId) -> Option<&CameraModel> {
        match self.sensors.get(sensor.0 as usize).map(|s| &s.model) {
            Some(SensorModel::Camera(m)) => Some(m),
            _ => None,
        }
    }

    /// Inserts a camera frame (a label image and its aligned depth image) taken at `stamp`
    /// when the robot was at `world_from_base`, named by the caller's observation id.
    /// See [`camera`](super::camera) for what it writes. A frame whose images do not fit
    /// the camera is refused and counted.
    pub fn insert_camera_frame(
        &mut self,
        sensor: SensorId,
        id: Option<ObservationId>,
        stamp: Stamp,
        labels: &LabelImage,
        depth: &DepthImage,
        world_from_base: Pose2,
    ) -> Result<InsertStats, EngineError> {
        let Some(slot) = self.sensors.get_mut(sensor.0 as usize) else {
            self.stats.unknown_sensor += 1;
            return Err(EngineError::UnknownSensor(sensor));
        };
        let SensorModel::Camera(model) = &slot.model else {
            self.stats.unknown_sensor += 1;
            return Err(EngineError::WrongModel { sensor, kind: slot.model.kind() });
        };
        let mut counts = crate::sensor::camera::PixelCounts::default();
        if let Err(error) = model.project(labels, depth, world_from_base, &mut self.camera_scratch, &mut counts) {
            slot.stats.frames_refused += 1;
            return Err(EngineError::Camera { sensor, error });
        }
        self.camera_scratch.stamp = stamp;
        self.camera_scratch.sensor = sensor;
        if let Some(held) = &mut self.held_out {
            held.add_camera(&self.camera_scratch, model.classes(), self.maps.primary().grid().geometry());
            slot.stats.held_out += 1;
            return Ok(InsertStats::default());
        }
        let group = self.admit(sensor, stamp, id)?;
        let ctx = self.context(stamp, group);
        let slot = &mut self.sensors[sensor.0 as usize];
        slot.stats.pixels.add(&counts);
        let SensorModel::Camera(model) = &slot.model else { unreachable!("checked above") };
        let each =
            super::camera::insert_frame(&mut self.maps, &mut self.frame_cells, &self.camera_scratch, model, &ctx);
        let mut total = InsertStats::default();
        each.iter().for_each(|s| total.add(s));
        let fed = each.len() as u64;
        self.stats.measurements += 1;
        self.stats.insert.add(&total);
        slot.stats.scans += 1;
        slot.stats.maps_fed += fed;
        slot.stats.insert.add(&total);
        self.check_budget(stamp)?;
        Ok(total)
    }

    /// The last lidar observation turned into rays (inserted or held out), map frame.
    pub fn last_range_data(&self) -> &RangeData {
        &self.scratch
    }

    /// The last camera frame projected (by [`Engine::insert_camera_frame`], inserted or
    /// held out), map frame: what a calibration reads back of the pass.
    pub fn last_camera_frame(&self) -> &CameraObservation {
        &self.camera_scratch
    }

    /// The kind of a registered sensor.
    pub fn sensor_kind(&self, sensor: SensorId) -> Option<SensorKind> {
        self.sensors.get(sensor.0 as usize).map(|s| s.model.kind())
    }

    /// Checks that `sensor` is registered and `stamp` is not older than the last applied,
    /// and records the observation id. Counts every refusal.
    fn admit(
        &mut self,
        sensor: SensorId,
        stamp: Stamp,
        id: Option<ObservationId>,
    ) -> Result<Option<Group>, EngineError> {
        let Some(slot) = self.sensors.get_mut(sensor.0 as usize) else {
            self.stats.unknown_sensor += 1;
            return Err(EngineError::UnknownSensor(sensor));
        };
        if let Some(last) = self.last {
            if stamp < last {
                self.stats.out_of_order += 1;
                slot.stats.out_of_order += 1;
                return Err(EngineError::OutOfOrder { sensor, stamp, last });
            }
            if stamp > last {
                self.ids_at_last.clear();
            }
        }
        self.last = Some(stamp);
        if let Some(id) = id {
            if !self.ids_at_last.insert(id) {
                self.stats.shared_ids += 1;
                slot.stats.shared_ids += 1;
            }
        }
        let before = self.correlator.merged;
        let group = self.correlator.assign(sensor, stamp);
        self.stats.correlated_merged += self.correlator.merged - before;
        Ok(group)
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
        self.scan(sensor, None, scan, range_min, range_max, pose_of_beam)
    }

    /// Inserts a lidar scan named by the caller's observation id, with the sensor's stated
    /// range limits (NaN: not stated) and the robot pose per beam.
    pub fn insert_scan_observed(
        &mut self,
        sensor: SensorId,
        id: ObservationId,
        scan: &LaserScan,
        range_min: f32,
        range_max: f32,
        pose_of_beam: impl FnMut(usize) -> Pose2,
    ) -> Result<InsertStats, EngineError> {
        self.scan(sensor, Some(id), scan, range_min, range_max, pose_of_beam)
    }

    fn scan(
        &mut self,
        sensor: SensorId,
        id: Option<ObservationId>,
        scan: &LaserScan,
        range_min: f32,
        range_max: f32,
        pose_of_beam: impl FnMut(usize) -> Pose2,
    ) -> Result<InsertStats, EngineError> {
        let model = match self.sensors.get(sensor.0 as usize).map(|s| &s.model) {
            Some(SensorModel::Lidar(m)) => *m,
            Some(other) => {
                self.stats.unknown_sensor += 1;
                return Err(EngineError::WrongModel { sensor, kind: other.kind() });
            }
            None => {
                self.stats.unknown_sensor += 1;
                return Err(EngineError::UnknownSensor(sensor));
            }
        };
        let model = model.limited_to(range_min, range_max);
        if let Some(held) = &mut self.held_out {
            let slot = &mut self.sensors[sensor.0 as usize];
            model.scan_to_range_data_with(sensor, scan, pose_of_beam, &mut self.scratch, &mut slot.stats.returns);
            held.add_range_data(&self.scratch, self.maps.primary().grid().geometry());
            slot.stats.held_out += 1;
            return Ok(InsertStats::default());
        }
        let group = self.admit(sensor, scan.stamp, id)?;
        let ctx = self.context(scan.stamp, group);
        let slot = &mut self.sensors[sensor.0 as usize];
        model.scan_to_range_data_with(sensor, scan, pose_of_beam, &mut self.scratch, &mut slot.stats.returns);
        let (maps, stats, slot) = (&mut self.maps, &mut self.stats, &mut slot.stats);
        let s = apply(maps, stats, slot, SensorKind::Lidar, &self.scratch, &ctx);
        self.check_budget(scan.stamp)?;
        Ok(s)
    }

    /// Inserts range data a sensor model outside the engine produced. Its sensor must be
    /// registered (its kind decides which maps take it).
    pub fn insert_range_data(&mut self, data: &RangeData) -> Result<InsertStats, EngineError> {
        self.range_data(None, data)
    }

    /// Inserts range data named by the caller's observation id.
    pub fn insert_range_data_observed(
        &mut self,
        id: ObservationId,
        data: &RangeData,
    ) -> Result<InsertStats, EngineError> {
        self.range_data(Some(id), data)
    }

    fn range_data(&mut self, id: Option<ObservationId>, data: &RangeData) -> Result<InsertStats, EngineError> {
        if let Some(held) = &mut self.held_out {
            let Some(slot) = self.sensors.get_mut(data.sensor.0 as usize) else {
                self.stats.unknown_sensor += 1;
                return Err(EngineError::UnknownSensor(data.sensor));
            };
            held.add_range_data(data, self.maps.primary().grid().geometry());
            slot.stats.held_out += 1;
            return Ok(InsertStats::default());
        }
        let group = self.admit(data.sensor, data.stamp, id)?;
        let ctx = self.context(data.stamp, group);
        let slot = &mut self.sensors[data.sensor.0 as usize];
        let kind = slot.model.kind();
        let s = apply(&mut self.maps, &mut self.stats, &mut slot.stats, kind, data, &ctx);
        self.check_budget(data.stamp)?;
        Ok(s)
    }
}

/// Inserts one observation into every map that takes it and counts it.
fn apply(
    maps: &mut MapSet,
    stats: &mut EngineStats,
    sensor: &mut SensorStats,
    kind: SensorKind,
    data: &RangeData,
    ctx: &InsertContext,
) -> InsertStats {
    let (s, fed) = maps.insert_fused(kind, data, ctx);
    stats.measurements += 1;
    stats.insert.add(&s);
    sensor.scans += 1;
    sensor.maps_fed += fed;
    sensor.insert.add(&s);
    s
}

#[cfg(test)]
#[path = "engine_tests.rs"]
mod tests;
