//! # fusemap-io
//!
//! Every file format fusemap reads or writes. The maths lives in `fusemap-core`; this
//! crate only turns bytes into its types and back.

#![warn(missing_docs)]

pub mod error;
pub mod log;

pub use error::{Error, Location, Result};
#[doc(hidden)]
pub mod testdata;
