//! Sensor models: each turns one sensor's raw reading into evidence in the map frame —
//! the lidar into the sensor-agnostic [`RangeData`](crate::measurement::RangeData), the
//! semantic camera into a [`CameraObservation`] of class-labelled points. The model, not
//! the grid, holds the sensor's parameters, so one map can take many sensors.

pub mod camera;
pub mod lidar;
pub mod lidar_filters;

pub use camera::{
    Band, CameraError, CameraModel, CameraObservation, CameraParams, CameraPoint, ClassSpec, ClassTable, DepthImage,
    ImageError, LabelImage, Pinhole, PixelCounts,
};
pub use lidar::{LaserScan, LidarModel, LidarParams, MaxRangePolicy, ReturnCounts};
pub use lidar_filters::{AngularBounds, ScanFilters, SelfBox, ShadowFilter, SpeckleFilter};
