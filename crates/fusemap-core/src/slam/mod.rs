//! 2D SLAM back end: pose-graph optimisation (Grisetti et al. 2010, "A tutorial on graph-based SLAM").

pub mod pose_graph;
