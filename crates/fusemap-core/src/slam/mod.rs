//! 2D SLAM: scan-to-submap matching, submaps, loop closure and a pose graph.
pub mod global_match;
pub mod grid;
