//! One module per subcommand.

pub mod bench;
pub mod calibrate;
pub mod demo;
pub mod doctor;
pub mod map;
pub mod relations;
pub mod simulate;
pub mod slam_bench;
pub mod validate;

/// The validated plan of `--config FILE`, or of the defaults without one
/// ([`fusemap_pipeline::job::plan_of`]).
pub fn plan_of(config: Option<&std::path::Path>) -> anyhow::Result<fusemap_core::config::Plan> {
    Ok(fusemap_pipeline::job::plan_of(config)?)
}

/// A path as printed to a terminal: control characters in it (a name holding an escape
/// sequence or a newline) shown as visible escapes, as every string from a log is.
pub fn shown(path: &std::path::Path) -> String {
    fusemap_io::text::printable(&path.display().to_string()).into_owned()
}

/// A run that observed no cell wrote only its summary: that is a failure a script must
/// see, with the reason (for `map` and `demo --corridor` alike).
pub fn fail_without_map(summary: &fusemap_pipeline::outputs::Summary, out: &std::path::Path) -> anyhow::Result<()> {
    if summary.entropy.is_none() {
        anyhow::bail!(
            "no map was written: no cell was observed in {} scans ({} valid returns); {} says what was skipped and why",
            summary.scans,
            summary.returns.valid,
            out.join("summary.json").display()
        );
    }
    Ok(())
}
