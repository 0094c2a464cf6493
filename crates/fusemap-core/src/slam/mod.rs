//! 2D SLAM: scan-to-submap matching, submaps, loop closure and a pose graph.
//!
//! | step | module |
//! |---|---|
//! | a submap's probability grid | `grid.rs` |
//! | the likelihood field scans are matched against | `field.rs` |
//! | its smooth (bicubic) interpolation | `interpolation.rs` |
//! | correlative search + Gauss–Newton refinement + information | `local_match.rs` |
//! | two active submaps, finished ones kept | `submap.rs` |
//! | a finished submap's field, packed | `packed_grid.rs` |
//! | branch-and-bound loop-closure search | `global_match.rs` |
//! | its precomputed grids within a memory budget | `grid_cache.rs` |
//! | which pairs are searched, in parallel batches, and which matches are kept | `loop_closure.rs` |
//! | sparse pose-graph optimisation | `pose_graph.rs` |
//! | GNSS fixes as position priors on nodes | `fixes.rs` |
//! | the loop over scans | `mapper.rs` |
//! | the corrected pose track | `corrected_track.rs` |
//! | the matcher's exact two-way parallelism | `crate::parallel` |
#[cfg(test)]
mod bad_input_tests;
mod corrected_track;
pub mod field;
mod fixes;
pub mod global_match;
pub mod grid;
mod grid_cache;
pub mod interpolation;
pub mod local_match;
mod loop_closure;
mod mapper;
mod node_edges;
mod odometry;
mod optimisation;
mod packed_grid;
mod params;
pub mod pose_graph;
mod report;
pub mod submap;
#[cfg(test)]
mod test_world;

pub use crate::parallel::adopt_calling_thread;
pub use corrected_track::CorrectedTrack;
pub use fixes::PositionFix;
pub use local_match::{search_candidates, LocalMatchParams};
pub use loop_closure::{OpenReason, OpenSearch};
pub use mapper::{ScanInput, ScanOutcome, Slam, SlamResult};
pub use params::SlamParams;
pub use report::SlamReport;
pub use submap::SubmapBounds;
