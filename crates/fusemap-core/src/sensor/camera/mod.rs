//! The semantic camera: a per-pixel class-label image and an aligned depth image, turned
//! into class-labelled points in the map plane.
//!
//! The camera is the semantic sensor of the design document (§2.2, §3.4): its labels
//! build the semantic layer; its depth, whose error grows with the square of the depth,
//! gives only weak geometric evidence.
//!
//! | piece | where |
//! |---|---|
//! | decoded label and depth images | [`LabelImage`], [`DepthImage`] |
//! | intrinsics from `CameraInfo` (rectified images only: fusemap does not undistort) | [`Pinhole`] |
//! | the classes label ids stand for | [`ClassTable`], [`ClassSpec`] |
//! | parameters | [`CameraParams`] |
//! | projection, depth weight, the evidence rule | [`CameraModel`] |
//! | its output | [`CameraObservation`], [`CameraPoint`], [`Band`], [`PixelCounts`] |

mod classes;
mod error;
mod image;
mod model;
mod observation;
mod params;
mod pinhole;

pub use classes::{ClassSpec, ClassTable, MAX_CLASSES};
pub use error::CameraError;
pub use image::{DepthImage, ImageError, LabelImage};
pub use model::{depth_weight, optical_mount, CameraModel};
pub use observation::{Band, CameraObservation, CameraPoint, PixelCounts};
pub use params::{CameraParams, MAX_DEPTH_LIMIT_M, MAX_STRIDE};
pub use pinhole::{Pinhole, MAX_CAMERA_PIXELS};

#[cfg(test)]
mod tests;
