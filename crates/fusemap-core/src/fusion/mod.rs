//! The fusion engine: time-ordered observations from any number of sensors into one or
//! several maps of layers.

mod engine;
mod mapset;
mod sensors;

pub use engine::{Engine, EngineError, EngineStats};
pub use mapset::{MapEntry, MapSet, SensorSelection};
pub use sensors::{SensorModel, SensorStats};
