//! One module per subcommand.

pub mod bench;
pub mod demo;
pub mod doctor;
pub mod map;
pub mod relations;
pub mod simulate;
pub mod slam_bench;
pub mod world;

/// The validated plan of `--config FILE`, or of the defaults without one: the file is
/// read and validated once (its errors name the file and the line).
pub fn plan_of(config: Option<&std::path::Path>) -> anyhow::Result<fusemap_core::config::Plan> {
    match config {
        Some(p) => Ok(fusemap_io::config_file::load_plan(p)?),
        None => fusemap_core::config::Config::default().validate().map_err(|e| anyhow::anyhow!("configuration: {e}")),
    }
}
