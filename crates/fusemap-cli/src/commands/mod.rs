//! One module per subcommand.

pub mod bench;
pub mod demo;
pub mod doctor;
pub mod map;
pub mod relations;
pub mod simulate;
pub mod slam_bench;
