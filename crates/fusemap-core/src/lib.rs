//! # fusemap-core
//!
//! The pure computation of fusemap: no files, no network, no ROS types. Formats live in
//! `fusemap-io`, the command line in `fusemap-cli`.
//!
//! | concept | module |
//! |---|---|
//! | SE(2)/SE(3) poses, sensor mounts, WGS84 ↔ ENU | [`geometry`] |
//! | the frame tree of `/tf_static` and `/tf` (`map ← odom ← base_link ← sensor`) | [`frames`] |
//! | time stamps, pose buffers and the pose-track trait | [`time`] |
//! | grid geometry, log-odds, tiles, ray traversal | [`grid`] |
//! | the measurement every sensor model produces | [`measurement`] |
//! | sensor models (lidar inverse model, semantic camera) | [`sensor`] |
//! | the engine taking time-ordered measurements | [`fusion`] |
//! | the `map → base_link` track from odometry, gyro, GNSS (EKF + RTS smoother) | [`estimator`] |
//! | entropy, precision / recall, SLAM-benchmark relations (Kümmerle et al. 2009) | [`metrics`] |
//! | simulated worlds and scanners (the production-line simulator is `fusemap-sim`) | [`sim`] |
//! | the validated run configuration | [`config`] |
//!
//! ```
//! use fusemap_core::{config::Config, fusion::Engine, grid::FusionGrid, sim::SimulatedRun};
//! let plan = Config::default().validate().unwrap();
//! let mut engine = Engine::new(FusionGrid::new(plan.geometry, plan.occupancy));
//! let lidar = plan.lidars[0].clone();
//! let laser = engine.add_lidar(lidar.name, lidar.model);
//! let run = SimulatedRun::document_corridor();
//! for (scan, pose) in run.scans.iter().zip(&run.poses) {
//!     engine.insert_scan(laser, scan, *pose).unwrap();
//! }
//! assert!(engine.grid().known_box().is_some());
//! ```

#![warn(missing_docs)]

pub mod calibration;
pub mod config;
pub mod estimator;
pub mod field_error;
pub mod frames;
pub mod fusion;
pub mod geometry;
pub mod grid;
pub mod measurement;
pub mod metrics;
pub mod parallel;
pub mod sensor;
pub mod sim;
pub mod slam;
pub mod time;
