//! Sensor models: each turns one sensor's raw reading into the sensor-agnostic
//! [`RangeData`](crate::measurement::RangeData) the grid consumes. The model, not the
//! grid, holds the sensor's parameters, so one map can take many sensors.

pub mod camera;
pub mod lidar;
pub mod lidar_filters;

pub use camera::{DepthImage, ImageError, LabelImage};
pub use lidar::{LaserScan, LidarModel, LidarParams, MaxRangePolicy, ReturnCounts};
pub use lidar_filters::{AngularBounds, ScanFilters, SelfBox, ShadowFilter, SpeckleFilter};
