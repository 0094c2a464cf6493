//! One module per subcommand.

pub mod bench;
pub mod demo;
pub mod doctor;
pub mod map;
pub mod relations;
pub mod simulate;
pub mod slam_bench;

/// The validated plan of `--config FILE`, or of the defaults without one
/// ([`fusemap_pipeline::job::plan_of`]).
pub fn plan_of(config: Option<&std::path::Path>) -> anyhow::Result<fusemap_core::config::Plan> {
    Ok(fusemap_pipeline::job::plan_of(config)?)
}
