//! A run's outputs, as a robotics user loads them: the view of the map to write
//! ([`view`]), the output set staged and committed whole ([`set`]), the writers and the
//! summary ([`write`](mod@write), [`summary`]). Every command that writes a map (`map`, `demo`, the
//! validation and calibration runs to come) goes through [`finish`], so the files and
//! `summary.json`'s schema are the same whichever command made them.

pub mod map_formats;
mod report_page;
mod report_tables;
pub mod set;
pub mod summary;
mod svg_plot;
pub mod view;
pub mod write;

pub use report_page::SECTIONS as REPORT_SECTIONS;
pub use set::{prepare, OutputFiles, Outputs};
pub use summary::{Seconds, Summary};
pub use view::{crop_area, parse_crop, view_of, Crop, ExportOptions, ExportRoom, MapView};
pub use write::{finish, layers_of, Layers, RunRecord, REPORT_HTML};

use std::path::PathBuf;

/// Why a run's outputs could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Writing a file failed, or an output would overwrite an input (the error names the
    /// file).
    #[error(transparent)]
    Io(#[from] fusemap_io::Error),
    /// The output directory cannot be made or locked.
    #[error("cannot write into the output directory {}", dir.display())]
    Directory {
        /// The output directory.
        dir: PathBuf,
        /// Why.
        #[source]
        source: fusemap_io::Error,
    },
    /// `--crop` names no region that can be exported.
    #[error("{0}")]
    Crop(String),
}
