//! A simulated 2D lidar.

use super::World;
use crate::geometry::{PlanarMount, Pose2};
use crate::sensor::LaserScan;
use crate::time::Stamp;
use serde::{Deserialize, Serialize};

/// The simulated scanner: beam layout and the range it reports.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScannerSpec {
    /// Beams per scan.
    pub beams: usize,
    /// Angle of the first beam, radians.
    pub angle_min: f64,
    /// Angle of the last beam, radians.
    pub angle_max: f64,
    /// Longest range the scanner measures; farther or no wall gives exactly this value,
    /// as the document's simulator does (§3.1).
    pub range_max: f64,
    /// Scans per second (stamps are `i / rate`).
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
}

fn default_rate() -> f64 {
    10.0
}

impl ScannerSpec {
    /// The document's scanner: 181 beams over [-π/2, π/2], 10 m, 10 Hz.
    pub fn document() -> Self {
        use std::f64::consts::FRAC_PI_2;
        Self { beams: 181, angle_min: -FRAC_PI_2, angle_max: FRAC_PI_2, range_max: 10.0, rate_hz: 10.0 }
    }

    /// Angle between beams.
    pub fn angle_increment(&self) -> f64 {
        if self.beams > 1 {
            (self.angle_max - self.angle_min) / (self.beams - 1) as f64
        } else {
            0.0
        }
    }
}

/// Simulates one scan from `world_from_base` with the sensor at `mount`. Ranges are
/// `f32`, as in `sensor_msgs/LaserScan`.
pub fn simulate_scan(
    world: &World,
    spec: &ScannerSpec,
    mount: &PlanarMount,
    world_from_base: Pose2,
    stamp: Stamp,
) -> LaserScan {
    let inc = spec.angle_increment();
    let origin = world_from_base * mount.origin_in_base();
    let ranges = (0..spec.beams)
        .map(|i| {
            let a = world_from_base.theta + mount.beam_angle_in_base(spec.angle_min + i as f64 * inc);
            match world.cast(origin, a) {
                Some(d) if d < spec.range_max => d as f32,
                _ => spec.range_max as f32,
            }
        })
        .collect();
    LaserScan { stamp, angle_min: spec.angle_min, angle_increment: inc, ranges }
}

/// Simulates one scan taken while the robot moves: beam `i` is fired at
/// `t0 + i · time_increment` seconds from the pose `world_from_base_at(t)`, as a rotating
/// lidar does (the motion distortion de-skewing removes).
pub fn simulate_moving_scan(
    world: &World,
    spec: &ScannerSpec,
    mount: &PlanarMount,
    world_from_base_at: impl Fn(f64) -> Pose2,
    t0: f64,
    time_increment: f64,
) -> LaserScan {
    let inc = spec.angle_increment();
    let ranges = (0..spec.beams)
        .map(|i| {
            let pose = world_from_base_at(t0 + i as f64 * time_increment);
            let origin = pose * mount.origin_in_base();
            let a = pose.theta + mount.beam_angle_in_base(spec.angle_min + i as f64 * inc);
            match world.cast(origin, a) {
                Some(d) if d < spec.range_max => d as f32,
                _ => spec.range_max as f32,
            }
        })
        .collect();
    LaserScan {
        stamp: Stamp::from_secs_f64(t0).unwrap_or(Stamp::ZERO),
        angle_min: spec.angle_min,
        angle_increment: inc,
        ranges,
    }
}

/// A whole simulated run: a trajectory of base poses, one scan at each.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedRun {
    /// `world_from_base` of each scan.
    pub poses: Vec<Pose2>,
    /// The scans, in time order.
    pub scans: Vec<LaserScan>,
}

impl SimulatedRun {
    /// Simulates `poses` in `world`.
    pub fn new(world: &World, spec: &ScannerSpec, mount: &PlanarMount, poses: Vec<Pose2>) -> Self {
        let scans = poses
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let stamp = Stamp::from_secs_f64(i as f64 / spec.rate_hz).unwrap_or(Stamp::ZERO);
                simulate_scan(world, spec, mount, p, stamp)
            })
            .collect();
        Self { poses, scans }
    }

    /// The document's corridor run: poses (0.1·i, 0, 0), i = 0..40.
    pub fn document_corridor() -> Self {
        let poses = (0..40).map(|i| Pose2::new(0.1 * i as f64, 0.0, 0.0)).collect();
        Self::new(&super::corridor(), &ScannerSpec::document(), &PlanarMount::default(), poses)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corridor_run_shape() {
        let run = SimulatedRun::document_corridor();
        assert_eq!(run.scans.len(), 40);
        assert!(run.scans.iter().all(|s| s.ranges.len() == 181));
        // Beam 90 looks straight ahead at the end wall 4 m away from the first pose.
        assert!((run.scans[0].ranges[90] - 4.0).abs() < 1e-6);
        // Beam 0 looks right (-90°) at the wall y = -2.
        assert!((run.scans[0].ranges[0] - 2.0).abs() < 1e-6);
        assert_eq!(run.scans[3].stamp, Stamp(300_000_000));
    }
}
