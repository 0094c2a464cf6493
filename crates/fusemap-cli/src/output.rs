//! Writing a run's outputs: `map.npz`, `map.pgm` + `map.yaml`, `map.png`, `summary.json`.
//! Every file is written atomically (temp file + rename) and never over an input.

use crate::summary::Summary;
use anyhow::{Context, Result};
use fusemap_core::grid::Raster;
use fusemap_io::atomic::{ensure_not_input, write_atomic};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files of a run, in `dir`.
pub struct OutputFiles {
    /// `map.npz`.
    pub npz: PathBuf,
    /// `map.yaml` (its `map.pgm` beside it).
    pub yaml: PathBuf,
    /// `map.pgm`.
    pub pgm: PathBuf,
    /// `map.png`.
    pub png: PathBuf,
    /// `summary.json`.
    pub summary: PathBuf,
}

impl OutputFiles {
    /// The output paths in `dir`.
    pub fn in_dir(dir: &Path) -> Self {
        Self {
            npz: dir.join("map.npz"),
            yaml: dir.join("map.yaml"),
            pgm: dir.join("map.pgm"),
            png: dir.join("map.png"),
            summary: dir.join("summary.json"),
        }
    }

    fn all(&self) -> [&PathBuf; 5] {
        [&self.npz, &self.yaml, &self.pgm, &self.png, &self.summary]
    }
}

/// Creates `dir` and checks that no output would overwrite one of `inputs`.
pub fn prepare(dir: &Path, inputs: &[PathBuf]) -> Result<OutputFiles> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create output directory {}", dir.display()))?;
    let files = OutputFiles::in_dir(dir);
    for f in files.all() {
        ensure_not_input(f, inputs)?;
    }
    Ok(files)
}

/// Writes the map files (if anything is known) and the summary.
pub fn write(files: &OutputFiles, raster: Option<&Raster>, summary: &Summary) -> Result<()> {
    if let Some(r) = raster {
        fusemap_io::npz::write_map_npz(&files.npz, r)?;
        fusemap_io::map_server::write_map_server(&files.yaml, r)?;
        fusemap_io::picture::write_map_png(&files.png, r)?;
    }
    let json = serde_json::to_vec_pretty(summary)?;
    write_atomic(&files.summary, |w| w.write_all(&json))?;
    Ok(())
}
