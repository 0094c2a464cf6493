//! One module per subcommand.

pub mod bench;
pub mod doctor;
pub mod log_map;
pub mod map;
