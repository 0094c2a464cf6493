//! 2D SLAM: scan-to-submap matching, submaps, loop closure and a pose graph.
pub mod grid;
