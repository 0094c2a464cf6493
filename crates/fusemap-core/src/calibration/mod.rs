//! Self-calibration from the data alone: what the design document's §4.3 tells a user to
//! check by hand (mounts, clock offsets, odometry), estimated with an interval, and left
//! undetermined, with the reason, where the log cannot fix it.

mod camera_floor;
mod camera_lidar;
mod distance_field;
mod lidar_odometry;

pub use camera_floor::{camera_floor, FloorFit, FloorPoints};
pub use camera_lidar::{camera_against_map, CameraLidarFit, CameraSample, CameraSearch};
pub use distance_field::{DistanceField, SurfaceHits};
pub use lidar_odometry::{lidar_odometry, steps_of, turn_agreement, LidarOdometry, MotionStep};

use crate::geometry::normalize_angle;
use serde::Serialize;

/// The delete-a-group jackknife's standard error of an estimate from its `n` estimates
/// with one group left out each: `√((n − 1)/n · Σ (θᵢ − θ̄)²)`; deviations of an angle
/// (`angle`) wrapped to (−π, π]. 0 without estimates.
pub fn jackknife_sigma(estimates: &[f64], angle: bool) -> f64 {
    let n = estimates.len();
    if n == 0 {
        return 0.0;
    }
    let mean = estimates.iter().sum::<f64>() / n as f64;
    let wrap = |d: f64| if angle { normalize_angle(d) } else { d };
    let ss: f64 = estimates.iter().map(|e| wrap(e - mean).powi(2)).sum();
    ((n - 1) as f64 / n as f64 * ss).sqrt()
}

/// An estimated parameter: its value and a 95 % interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Interval {
    /// The estimate.
    pub value: f64,
    /// The interval's lower end.
    pub low: f64,
    /// The interval's upper end.
    pub high: f64,
}

impl Interval {
    /// `value ± 1.96 σ`.
    pub fn of(value: f64, sigma: f64) -> Self {
        Self { value, low: value - 1.96 * sigma, high: value + 1.96 * sigma }
    }

    /// Whether `x` lies inside.
    pub fn contains(&self, x: f64) -> bool {
        self.low <= x && x <= self.high
    }

    /// Half the interval's width.
    pub fn half_width(&self) -> f64 {
        0.5 * (self.high - self.low)
    }
}
