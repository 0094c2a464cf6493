//! What the camera model produces: class-labelled points in the map plane, and the count
//! of every pixel it looked at.

use crate::geometry::Point2;
use crate::measurement::SensorId;
use crate::time::Stamp;
use serde::Serialize;

/// Where a back-projected point lies in height (base-frame `z`, floor at `z = 0`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Band {
    /// Within `±floor_band_m` of the floor plane: the floor.
    Floor,
    /// From `floor_band_m` up to `obstacle_max_z_m`: something the robot could hit.
    Obstacle,
}

/// One used pixel, projected into the map plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPoint {
    /// Map frame: where the pixel's 3D point lies (x, y).
    pub end: Point2,
    /// Index into the model's [`ClassTable`](super::ClassTable) (never an ignored class).
    pub class: u8,
    /// Depth weight in (0, 1]: the probability that the true point lies in the cell it
    /// was measured in, under `σ = k·d²` (see [`depth_weight`](super::depth_weight)).
    pub weight: f32,
    /// Its height band.
    pub band: Band,
    /// Its height above the floor (base-frame `z`), metres: how far inside its band it
    /// lies, which a calibration needs (near a band's edge, depth noise decides the band,
    /// so the points kept there are biased towards the camera).
    pub height: f32,
}

/// One camera frame's evidence, map frame.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraObservation {
    /// When the frame was taken (set by the caller: the image's offset-corrected stamp).
    pub stamp: Stamp,
    /// Which sensor took it (set by the caller).
    pub sensor: SensorId,
    /// The optical centre projected on the floor plane, map frame: where the camera's
    /// free-evidence rays start in the plane.
    pub origin: Point2,
    /// The used pixels.
    pub points: Vec<CameraPoint>,
}

impl CameraObservation {
    /// An empty observation, for reuse as a scratch buffer.
    pub fn empty(sensor: SensorId) -> Self {
        Self { stamp: Stamp::ZERO, sensor, origin: Point2::new(0.0, 0.0), points: Vec::new() }
    }
}

/// What became of the pixels the model looked at (those at the stride). Every pixel seen
/// lands in exactly one other field, tested in this order: class, depth, height.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PixelCounts {
    /// Pixels looked at (every `stride`-th of every `stride`-th row).
    pub seen: u64,
    /// Projected into a [`CameraPoint`].
    pub used: u64,
    /// Label id not in the class table: counted and ignored (a segmenter with more classes
    /// than configured, or a corrupt image).
    pub unknown_class: u64,
    /// Label of a class marked `ignore` (unlabelled, ceiling, sky).
    pub ignored_class: u64,
    /// Depth NaN, ±inf, 0 or negative: the camera measured nothing there.
    pub no_depth: u64,
    /// Depth below `min_depth_m` or beyond `max_depth_m`.
    pub out_of_depth_range: u64,
    /// Above `obstacle_max_z_m` (ceiling, lamps, ducts).
    pub above_band: u64,
    /// Below `-floor_band_m`: under the floor, so a depth or mount error.
    pub below_floor: u64,
}

impl PixelCounts {
    /// Pixels seen but not used.
    pub fn skipped(&self) -> u64 {
        self.unknown_class
            + self.ignored_class
            + self.no_depth
            + self.out_of_depth_range
            + self.above_band
            + self.below_floor
    }

    /// Adds another frame's counts.
    pub fn add(&mut self, o: &PixelCounts) {
        self.seen += o.seen;
        self.used += o.used;
        self.unknown_class += o.unknown_class;
        self.ignored_class += o.ignored_class;
        self.no_depth += o.no_depth;
        self.out_of_depth_range += o.out_of_depth_range;
        self.above_band += o.above_band;
        self.below_floor += o.below_floor;
    }
}
