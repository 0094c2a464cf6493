//! Writing a run's outputs: `map.npz`, `map.pgm` + `map.yaml`, `map.png`, `summary.json`.
//! Every file is written atomically (temp file + rename) and never over an input.

use crate::summary::{CellsUpdated, MapInfo, Summary};
use anyhow::{Context, Result};
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::Raster;
use fusemap_core::metrics::map_entropy;
use fusemap_core::sensor::ReturnCounts;
use fusemap_core::time::Stamp;
use fusemap_io::atomic::{ensure_not_input, write_atomic};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// `trajectory.tum`.
    pub trajectory: PathBuf,
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
            trajectory: dir.join("trajectory.tum"),
        }
    }

    fn all(&self) -> [&PathBuf; 6] {
        [&self.npz, &self.yaml, &self.pgm, &self.png, &self.summary, &self.trajectory]
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

/// Writes the map files (if anything is known), the trajectory (when there is one) and
/// the summary.
pub fn write(
    files: &OutputFiles,
    raster: Option<&Raster>,
    summary: &Summary,
    trajectory: Option<&[(Stamp, Pose2)]>,
) -> Result<()> {
    if let Some(t) = trajectory {
        fusemap_io::trajectory::write_tum(&files.trajectory, t)?;
    }
    if let Some(r) = raster {
        fusemap_io::npz::write_map_npz(&files.npz, r)?;
        fusemap_io::map_server::write_map_server(&files.yaml, r)?;
        fusemap_io::picture::write_map_png(&files.png, r)?;
    }
    let json = serde_json::to_vec_pretty(summary)?;
    write_atomic(&files.summary, |w| w.write_all(&json))?;
    Ok(())
}

/// Builds the summary of a finished engine and writes every output.
#[allow(clippy::too_many_arguments)]
pub fn finish(
    engine: &Engine,
    files: &OutputFiles,
    source_kind: &str,
    source: &str,
    started: Instant,
    notes: Vec<String>,
    log: Option<serde_json::Value>,
    trajectory: Option<&[(Stamp, Pose2)]>,
) -> Result<Summary> {
    let grid = engine.grid();
    let raster = grid.known_raster();
    let st = engine.stats();
    let mut returns = ReturnCounts::default();
    let mut scans = 0;
    for s in engine.sensor_stats() {
        returns.add(&s.returns);
        scans += s.scans;
    }
    let mut summary = Summary {
        fusemap_version: env!("CARGO_PKG_VERSION"),
        source_kind: source_kind.to_string(),
        source: source.to_string(),
        scans,
        beams: returns.total(),
        returns,
        rays_walked: st.insert.rays,
        rays_rejected: st.insert.rays_rejected,
        cell_visits: st.insert.cell_visits,
        cell_visits_attenuated: st.insert.cell_visits_attenuated,
        cells_updated: CellsUpdated::from(&st.insert),
        map: MapInfo::new(raster.as_ref(), grid.geometry().resolution(), grid.tile_count()),
        entropy: raster.as_ref().map(map_entropy),
        wall_time_s: 0.0,
        notes,
        log,
    };
    if raster.is_none() {
        summary.notes.push("no cell was observed: only summary.json was written".into());
    }
    summary.wall_time_s = started.elapsed().as_secs_f64();
    write(files, raster.as_ref(), &summary, trajectory)?;
    summary.wall_time_s = started.elapsed().as_secs_f64();
    Ok(summary)
}
