//! The sensors an engine knows: registered by kind with their model, each with the
//! counters a user needs to judge its contribution to a run.

use crate::grid::InsertStats;
use crate::measurement::SensorKind;
use crate::sensor::camera::{CameraModel, PixelCounts};
use crate::sensor::{LidarModel, ReturnCounts};
use serde::Serialize;

/// A sensor's model, by kind.
///
/// A model held by the engine turns the sensor's raw readings into observations
/// ([`Engine::insert_scan_observed`](super::Engine::insert_scan_observed) for a lidar). A
/// sensor whose model runs outside the engine is registered by kind alone and delivers
/// [`RangeData`](crate::measurement::RangeData) through
/// [`Engine::insert_range_data_observed`](super::Engine::insert_range_data_observed): the
/// kind still decides which maps of a [`MapSet`](super::MapSet) take it.
#[derive(Clone, Debug)]
pub enum SensorModel {
    /// A 2D lidar and its inverse model.
    Lidar(LidarModel),
    /// A semantic camera (label + depth images) and its model.
    Camera(Box<CameraModel>),
    /// A sensor of this kind whose model runs outside the engine.
    External(SensorKind),
}

impl SensorModel {
    /// The sensor's kind.
    pub fn kind(&self) -> SensorKind {
        match self {
            SensorModel::Lidar(_) => SensorKind::Lidar,
            SensorModel::Camera(_) => SensorKind::Camera,
            SensorModel::External(k) => *k,
        }
    }
}

/// Per-sensor counters, kept on every insert path.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SensorStats {
    /// The sensor's name (its frame id).
    pub name: String,
    /// The sensor's kind.
    pub kind: SensorKind,
    /// Observations inserted (scans, for a lidar).
    pub scans: u64,
    /// Beams by kind of return (lidar scans only).
    pub returns: ReturnCounts,
    /// Pixels by what became of them (cameras only).
    pub pixels: PixelCounts,
    /// Frames refused (images that do not fit the camera).
    pub frames_refused: u64,
    /// Observations refused for being older than one already applied.
    pub out_of_order: u64,
    /// Observations whose id an earlier observation of the same instant already carried.
    pub shared_ids: u64,
    /// Observations of the held-out period (§5.2), counted, not inserted.
    pub held_out: u64,
    /// Map insertions: each observation counts once per map that took it.
    pub maps_fed: u64,
    /// What its observations did, summed over the maps that took them.
    pub insert: InsertStats,
}

/// A registered sensor.
pub(super) struct SensorSlot {
    pub(super) model: SensorModel,
    pub(super) stats: SensorStats,
}

impl SensorSlot {
    pub(super) fn new(name: String, model: SensorModel) -> Self {
        let kind = model.kind();
        Self { model, stats: SensorStats { name, kind, ..Default::default() } }
    }
}
