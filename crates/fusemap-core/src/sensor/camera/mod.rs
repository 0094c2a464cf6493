//! The semantic camera: a per-pixel class-label image and an aligned depth image, turned
//! into class-labelled points in the map plane.
//!
//! The camera is the semantic sensor of the design document (§2.2, §3.4): its labels
//! build the semantic layer; its depth, whose error grows with the square of the depth,
//! gives only weak geometric evidence.

mod image;

pub use image::{DepthImage, ImageError, LabelImage};
