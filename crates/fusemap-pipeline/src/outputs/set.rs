//! A run's output set: the files it writes and where, staged while the run holds the
//! output directory's lock and moved into place together at the end ([`OutputSet`]).

use super::OutputError;
use fusemap_io::atomic::ensure_not_input;
use fusemap_io::output_set::OutputSet;
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
    /// `trajectory.tum`.
    pub trajectory: PathBuf,
    /// `semantic.yaml` (its `semantic.png` beside it), for a run with a camera.
    pub semantic: PathBuf,
    /// `semantic.png`.
    pub semantic_png: PathBuf,
    /// `dynamic.png`, for a run with a camera.
    pub dynamic: PathBuf,
    /// `slam.png`: the optimised trajectory and its loop closures over the map, for a run
    /// SLAM corrected.
    pub slam: PathBuf,
    /// `map.mcap`: the map as ROS 2 messages.
    pub mcap: PathBuf,
    /// `map.pcd`: the occupied cells as a PCL point cloud.
    pub pcd: PathBuf,
    /// `map.ply`: the same points as PLY.
    pub ply: PathBuf,
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
            semantic: dir.join("semantic.yaml"),
            semantic_png: dir.join("semantic.png"),
            dynamic: dir.join("dynamic.png"),
            slam: dir.join("slam.png"),
            mcap: dir.join("map.mcap"),
            pcd: dir.join("map.pcd"),
            ply: dir.join("map.ply"),
        }
    }

    /// The file names of a run's set, for removing an earlier run's files this run does
    /// not write.
    pub const NAMES: [&'static str; 16] = [
        "map.npz",
        "map.yaml",
        "map.pgm",
        "map.png",
        "summary.json",
        "trajectory.tum",
        "semantic.yaml",
        "semantic.png",
        "dynamic.png",
        "slam.png",
        "fusion_validate.npz",
        "calibration.toml",
        "report.html",
        "map.mcap",
        "map.pcd",
        "map.ply",
    ];

    pub(crate) fn all(&self) -> [&PathBuf; 13] {
        [
            &self.npz,
            &self.yaml,
            &self.pgm,
            &self.png,
            &self.summary,
            &self.trajectory,
            &self.semantic,
            &self.semantic_png,
            &self.dynamic,
            &self.slam,
            &self.mcap,
            &self.pcd,
            &self.ply,
        ]
    }
}

/// A run's outputs: the paths its writers use (inside the set's staging directory) and
/// the set that moves them into the output directory at the end.
pub struct Outputs {
    /// Where each file is written until the commit.
    pub files: OutputFiles,
    pub(crate) set: OutputSet,
    /// Subdirectories the set owns (`lidar/`), see [`Outputs::own_dir`].
    pub(crate) owned: Vec<String>,
}

impl Outputs {
    /// Declares the subdirectory `name` of the output directory the set's own: at the
    /// commit, files under it that this run did not write are removed with the other
    /// stale files.
    pub fn own_dir(&mut self, name: &str) {
        self.owned.push(format!("{name}/"));
    }

    /// Where a writer puts `name` (which may hold a subdirectory, `lidar/map.npz`) so that
    /// it moves into the output directory with the rest of the set.
    pub fn staged(&self, name: &str) -> PathBuf {
        self.set.staged(name)
    }
}

/// Checks that no output would overwrite one of `inputs`, creates `dir`, takes its lock
/// (a second run into it is refused while this one lives) and opens the set.
pub fn prepare(dir: &Path, inputs: &[PathBuf]) -> Result<Outputs, OutputError> {
    // Every name the set may write or remove at its commit, not only the map's files: a
    // config passed as `--config out/calibration.toml` must survive a run into `out`.
    for f in OutputFiles::in_dir(dir).all() {
        ensure_not_input(f, inputs)?;
    }
    for name in OutputFiles::NAMES {
        ensure_not_input(&dir.join(name), inputs)?;
    }
    let set = OutputSet::begin(dir).map_err(|source| OutputError::Directory { dir: dir.to_path_buf(), source })?;
    Ok(Outputs { files: OutputFiles::in_dir(set.staging()), set, owned: Vec::new() })
}
