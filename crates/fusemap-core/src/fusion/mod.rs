//! The fusion engine: time-ordered observations from any number of sensors into one or
//! several maps of layers.

mod budget;
pub mod camera;
#[cfg(test)]
mod camera_tests;
mod correlation;
mod engine;
mod holdout;
mod mapset;
#[cfg(test)]
mod merge_tests;
pub mod rasters;
mod sensors;

pub use budget::{export_bytes_per_cell, BudgetKey};
pub use correlation::Correlation;
pub use engine::{Engine, EngineError, EngineStats};
pub use holdout::{HeldOut, HitRate, OBSTACLE_PROBABILITY};
pub use mapset::{InsertContext, MapEntry, MapSet, SensorSelection};
pub use sensors::{SensorModel, SensorStats};
