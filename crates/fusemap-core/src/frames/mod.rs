//! The TF frame tree a mapper needs (REP 105: `map → odom → base_link → sensor`):
//! static transforms from `/tf_static`, stamped ones from `/tf`, and the transform
//! between any two frames at a stamp — interpolated between samples, never extrapolated
//! (tf2's `ExtrapolationException` rule; Cartographer's `TransformInterpolationBuffer`).
//!
//! Real logs are untidy: a latched `/tf_static` repeated in every bag split, two drivers
//! both claiming `base_link → laser`, a `/tf` publisher also sending the static mount,
//! a NaN from a driver before its first fix. Each is refused or absorbed with a typed,
//! counted outcome ([`AddOutcome`], [`FrameError`]) and summarised in [`FrameReport`].

mod check;
mod error;
mod lookup;
mod report;
mod samples;
mod tree;

pub use error::{AddOutcome, EdgeKind, FrameError, LookupError};
pub use report::{
    Acceptances, ConflictEntry, EdgeEntry, FrameEntry, FrameReport, KindClashEntry, LoopEntry, Rejections,
    SecondParentEntry,
};
pub use tree::{FrameTree, FrameTreeLimits};

#[cfg(test)]
mod tests;
