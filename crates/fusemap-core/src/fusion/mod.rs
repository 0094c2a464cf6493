//! The fusion engine: time-ordered measurements from any number of sensors into layers.

mod engine;

pub use engine::{Engine, EngineError, EngineStats, SensorStats};
