//! # fusemap-io
//!
//! Every file format fusemap reads or writes. The maths lives in `fusemap-core`; this
//! crate only turns bytes into its types and back.

#![warn(missing_docs)]

pub mod atomic;
pub mod bounded;
pub mod camera;
pub mod comparison;
pub mod config_file;
pub mod error;
pub mod input_file;
pub mod log;
pub mod map_mcap;
pub mod map_server;
pub mod npz;
pub mod output_set;
pub mod picture;
pub mod point_cloud;
pub mod read_ahead;
pub mod relations;
pub mod scanfile;
pub mod semantic;
pub mod slam_picture;
pub mod text;
pub mod trajectory;
pub mod world_file;
pub mod yaml;

pub use error::{Error, Location, Result};
#[doc(hidden)]
pub mod testdata;
