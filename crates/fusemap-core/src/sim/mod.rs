//! Simulated worlds and scanners: the design document's corridor (§3.1) and the larger
//! worlds benchmarks and tests need, with exact ground truth. (The production-line
//! simulator, with every sensor and its faults, is the `fusemap-sim` crate.)

pub mod camera_frame;
mod odometry_drift;
mod rng;
mod scanner;
mod workloads;
mod world;

pub use odometry_drift::OdometryErrorModel;
pub use rng::SplitMix64;
pub use scanner::{simulate_moving_scan, simulate_scan, ScannerSpec, SimulatedRun};
pub use workloads::{workload, workload_prefix, Workload, WORKLOADS};
pub use world::{box_world, corridor, BoxWorld, Segment, World};
