//! The fixed synthetic workloads of `fusemap bench`, shaped like the baselines in the
//! project's anchors so that figures stay comparable:
//!
//! | | scans × beams | resolution | range | world |
//! |---|---|---|---|---|
//! | a | 40 × 181 over 180° | 0.05 m | 10 m | the document's corridor |
//! | b | 20,000 × 181 | 0.05 m | 10 m | the corridor, poses cycling |
//! | c | 5,000 × 1,081 over 270° | 0.02 m | 30 m | 39 m box, 8 rectangles, random poses |

use super::{box_world, corridor, ScannerSpec, SimulatedRun, SplitMix64};
use crate::geometry::{PlanarMount, Point2, Pose2};
use crate::sensor::LidarParams;

/// A benchmark workload: the scans and what to map them with.
pub struct Workload {
    /// `a`, `b` or `c`.
    pub name: char,
    /// One-line description.
    pub description: &'static str,
    /// Cell side, metres.
    pub resolution: f64,
    /// The lidar model's parameters.
    pub lidar: LidarParams,
    /// Poses and scans.
    pub run: SimulatedRun,
}

/// The names of the workloads.
pub const WORKLOADS: [char; 3] = ['a', 'b', 'c'];

/// Builds workload `name` (`'a'`, `'b'`, `'c'`); `None` for another name.
pub fn workload(name: char) -> Option<Workload> {
    workload_prefix(name, usize::MAX)
}

/// Workload `name` with only its first `scans` scans (for tests: the same poses and
/// scans as the whole workload's first ones, without simulating the rest).
pub fn workload_prefix(name: char, scans: usize) -> Option<Workload> {
    let corridor_poses = |n: usize| (0..n.min(scans)).map(|i| Pose2::new(0.1 * (i % 40) as f64, 0.0, 0.0)).collect();
    let mount = PlanarMount::default();
    match name {
        'a' | 'b' => {
            let n = if name == 'a' { 40 } else { 20_000 };
            Some(Workload {
                name,
                description: if name == 'a' {
                    "corridor, 40 scans x 181 beams, 0.05 m"
                } else {
                    "corridor x500, 20,000 scans x 181 beams, 0.05 m"
                },
                resolution: 0.05,
                lidar: LidarParams::default(),
                run: SimulatedRun::new(&corridor(), &ScannerSpec::document(), &mount, corridor_poses(n)),
            })
        }
        'c' => {
            let b = box_world(19.5, 8, 12345);
            let mut rng = SplitMix64::new(12346);
            let mut poses = Vec::with_capacity(5000);
            while poses.len() < 5000.min(scans) {
                let p = Point2::new(rng.uniform(-19.0, 19.0), rng.uniform(-19.0, 19.0));
                let theta = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI);
                if b.is_free(p, 0.5) {
                    poses.push(Pose2::new(p.x, p.y, theta));
                }
            }
            let half_fov = 135f64.to_radians();
            let spec =
                ScannerSpec { beams: 1081, angle_min: -half_fov, angle_max: half_fov, range_max: 30.0, rate_hz: 40.0 };
            Some(Workload {
                name,
                description: "39 m box, 5,000 scans x 1,081 beams over 270 deg, 0.02 m, 30 m range",
                resolution: 0.02,
                lidar: LidarParams { max_range: 30.0, ..LidarParams::default() },
                run: SimulatedRun::new(&b.world, &spec, &mount, poses),
            })
        }
        _ => None,
    }
}
