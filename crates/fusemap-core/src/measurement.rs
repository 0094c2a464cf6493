//! The one measurement type every range sensor model produces.
//!
//! After Cartographer's `RangeData { origin, returns, misses }`
//! (`cartographer/sensor/range_data.h`): once a sensor model has turned a reading into
//! rays in the map frame, the grid needs nothing else to know about the sensor. A 2D
//! lidar scan, a CARMEN `FLASER` line, a depth-camera column or a simulated scan all
//! become a [`RangeData`] before they touch the grid.
//!
//! Every observation is named by an [`ObservationId`] the caller supplies: a lidar scan
//! and a camera frame of the same instant may carry the same id, so that the engine can
//! tell they are one instant of the world (it counts such reuse today, so that their
//! evidence can be counted once later) rather than two independent observations.

use crate::geometry::Point2;
use crate::time::Stamp;

/// Identifies the sensor a measurement came from (an index into the engine's sensors).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct SensorId(pub u16);

/// The kind of a sensor, which decides its model and which maps take its observations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    /// A 2D range scanner ([`LidarModel`](crate::sensor::LidarModel)).
    #[default]
    Lidar,
    /// A camera: label + depth frames become a
    /// [`CameraObservation`](crate::sensor::CameraObservation) through its
    /// [`CameraModel`](crate::sensor::CameraModel).
    Camera,
}

/// Names one observation of the world, supplied by the caller (a message sequence number,
/// a frame counter, the stamp in nanoseconds). Observations of the same instant by
/// different sensors may share one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default, serde::Serialize, serde::Deserialize)]
pub struct ObservationId(pub u64);

/// One ray in the map frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (the sensor's position when the beam was fired).
    pub origin: Point2,
    /// Where the ray ends.
    pub end: Point2,
    /// `true`: an obstacle was seen at `end` (free space up to it, occupied at it).
    /// `false`: free space up to and including `end`, no obstacle (a cleared no-return).
    pub hit: bool,
}

/// The inverse-model probabilities a measurement's evidence carries. The grid turns them
/// into log-odds increments against its own prior, so sensors and maps with different
/// priors stay consistent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Evidence {
    /// Probability that a ray's end cell is occupied, given a hit there (`p_occ`).
    pub p_hit: f64,
    /// Probability that a cell the ray crossed is occupied (`p_free`).
    pub p_miss: f64,
}

/// The geometric evidence of one observation (one scan) in the map frame.
///
/// All rays of one `RangeData` are one observation: the grid updates each cell at most
/// once for it, and a cell that ends any hit ray is updated as occupied, never as free.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeData {
    /// When the observation was taken.
    pub stamp: Stamp,
    /// Which sensor produced it.
    pub sensor: SensorId,
    /// The rays, map frame.
    pub rays: Vec<Ray>,
    /// The probabilities its rays carry.
    pub evidence: Evidence,
}

impl RangeData {
    /// An empty observation, for reuse as a scratch buffer.
    pub fn empty(sensor: SensorId, evidence: Evidence) -> Self {
        Self { stamp: Stamp::ZERO, sensor, rays: Vec::new(), evidence }
    }
}
