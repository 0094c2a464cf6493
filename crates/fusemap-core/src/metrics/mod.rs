//! Map quality: entropy (the design document's §5.1 fusion gain) and agreement with
//! ground truth.

mod entropy;
mod scores;
mod semantic;

pub use entropy::{binary_entropy, map_entropy, EntropyReport};
pub use scores::{Confusion, TolerantScore};
pub use semantic::{ClassAccuracy, SemanticAccuracy};
