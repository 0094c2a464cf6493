//! Map quality: entropy (the design document's §5.1 fusion gain) and agreement with
//! ground truth.

mod entropy;
mod scores;

pub use entropy::{binary_entropy, map_entropy, EntropyReport};
pub use scores::{Confusion, TolerantScore};
