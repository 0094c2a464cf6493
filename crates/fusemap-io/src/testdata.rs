//! Locating the shared datasets for tests and benchmarks.
//!
//! Tests that need `../shared` (the real logs beside the checkout) call [`shared_dir`]:
//! on a user's fresh clone without it they print a notice and skip; with
//! `FUSEMAP_NO_SKIP=1` (set by `.ci/run`) a missing directory is a failure, so CI can
//! never pass by skipping.

use std::path::{Path, PathBuf};

/// The environment variable that turns skips into failures.
pub const NO_SKIP_ENV: &str = "FUSEMAP_NO_SKIP";

/// True when skips must fail (`FUSEMAP_NO_SKIP=1`).
pub fn no_skip() -> bool {
    std::env::var(NO_SKIP_ENV).is_ok_and(|v| v == "1")
}

/// The shared data directory: `$FUSEMAP_SHARED`, or `shared/` beside the workspace
/// checkout. `None` (after printing why) when absent and skipping is allowed; panics
/// when absent under `FUSEMAP_NO_SKIP=1`.
pub fn shared_dir() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("FUSEMAP_SHARED").map(PathBuf::from),
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared")),
    ];
    for c in candidates.into_iter().flatten() {
        if c.join("datasets").is_dir() {
            return Some(c);
        }
    }
    skip("the shared datasets (../shared beside the checkout, or $FUSEMAP_SHARED) are not present");
    None
}

/// A file under `shared/datasets/`, or `None` (after the notice) when absent.
pub fn dataset(relative: &str) -> Option<PathBuf> {
    let p = shared_dir()?.join("datasets").join(relative);
    if p.exists() {
        Some(p)
    } else {
        skip(&format!("dataset {} is missing", p.display()));
        None
    }
}

/// Prints a skip notice, or panics with it under `FUSEMAP_NO_SKIP=1`.
pub fn skip(reason: &str) {
    if no_skip() {
        panic!("{reason}, and {NO_SKIP_ENV}=1 forbids skipping");
    }
    eprintln!("SKIPPED: {reason}");
}

/// `$FUSEMAP_PYTHON`, else `python3`, when it imports every module of `modules`; else a
/// skip notice (a failure under `FUSEMAP_NO_SKIP=1`) and `None`.
pub fn python_with(modules: &[&str]) -> Option<String> {
    let python = std::env::var("FUSEMAP_PYTHON").unwrap_or_else(|_| "python3".into());
    let code: String = modules.iter().map(|m| format!("import {m}\n")).collect();
    let ok = std::process::Command::new(&python).args(["-c", &code]).output().is_ok_and(|o| o.status.success());
    if ok {
        Some(python)
    } else {
        skip(&format!(
            "`{python}` cannot import {} (pip install -r tests/fixtures/requirements.txt)",
            modules.join(", ")
        ));
        None
    }
}

/// The environment variable that keeps every test directory for a look afterwards.
pub const KEEP_DIRS_ENV: &str = "FUSEMAP_KEEP_TEST_DIRS";

/// A test's own directory under the system temp dir, removed with everything in it when
/// the value is dropped. Tests write bags and maps of up to a few hundred megabytes; a
/// directory that outlived its test filled the disk after a few dozen runs, so the
/// directory's life is the value's. `FUSEMAP_KEEP_TEST_DIRS=1` keeps them all.
///
/// It dereferences to its [`Path`], so `dir.join("x")` and `&dir` work as with a path;
/// bind it to a name that lives as long as the files are used (`temp_dir(t).join("x")`
/// alone would remove the directory at the end of the statement).
#[derive(Debug)]
#[must_use = "the directory is removed when this value is dropped"]
pub struct TestDir {
    path: PathBuf,
}

impl TestDir {
    /// The directory's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `name` inside this directory, as a value that keeps the directory alive: for a
    /// helper that writes a bag or an output set and hands back its path.
    pub fn into_child(self, name: &str) -> TestPath {
        TestPath { path: self.path.join(name), _dir: self }
    }
}

/// A path inside a [`TestDir`] that owns the directory ([`TestDir::into_child`]).
#[derive(Debug)]
pub struct TestPath {
    path: PathBuf,
    _dir: TestDir,
}

impl std::ops::Deref for TestPath {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TestPath {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::env::var(KEEP_DIRS_ENV).is_ok_and(|v| v == "1") {
            eprintln!("kept {}", self.path.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// A fresh empty directory for one test: `fusemap-{tag}-{pid}-{n}` under the system temp
/// dir, unique per call within the process, removed when the returned value is dropped.
pub fn temp_dir(tag: &str) -> TestDir {
    static N: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let path = std::env::temp_dir().join(format!(
        "fusemap-{tag}-{}-{}",
        std::process::id(),
        N.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&path);
    std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("cannot create {}: {e}", path.display()));
    TestDir { path }
}

/// A directory for a fixture that several tests of one test binary share through a
/// static (a static is never dropped, so a [`TestDir`] there would outlive the run):
/// `{base}/{tag}`, emptied and made afresh. Pass `env!("CARGO_TARGET_TMPDIR")` as `base`,
/// cargo's scratch directory for integration tests inside the target directory, so the
/// next run replaces the fixture instead of adding one and two checkouts never share it.
pub fn fixture_dir(base: &str, tag: &str) -> PathBuf {
    let path = Path::new(base).join(tag);
    let _ = std::fs::remove_dir_all(&path);
    std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("cannot create {}: {e}", path.display()));
    path
}

/// A tiny `SCAN2D01` scan file: 2 scans of 3 beams, poses (0, 1, 0.5) and (4, 5, 6),
/// ranges 1, 2, 3 and 7, 8, 9, grid origin (−5, −5).
pub fn tiny_scanfile_bytes() -> Vec<u8> {
    let mut b = b"SCAN2D01".to_vec();
    for v in [2i64, 3, 10, 10] {
        b.extend(v.to_le_bytes());
    }
    for v in [-1.0f64, 0.5, 0.1, 10.0, 0.05, -5.0, -5.0] {
        b.extend(v.to_le_bytes());
    }
    for v in [0.0f64, 1.0, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0] {
        b.extend(v.to_le_bytes());
    }
    b
}

/// A ROS-style scan message on `/scan` (frame `laser`, range limits 0–10 m, no poses),
/// for tests of what is done with scans.
pub fn scan_message(
    stamp: fusemap_core::time::Stamp,
    angle_min: f64,
    angle_increment: f64,
    angle_max: f32,
    ranges: Vec<f32>,
) -> crate::log::ScanMessage {
    crate::log::ScanMessage {
        topic: "/scan".into(),
        frame_id: "laser".into(),
        receive_stamp: None,
        scan: fusemap_core::sensor::LaserScan { stamp, angle_min, angle_increment, ranges },
        angle_max,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max: 10.0,
        pose: None,
        odom_pose: None,
        laser_pose: None,
    }
}

/// A 3 × 2 raster of 0.5 m cells whose lower-left corner is at (10, 20), with the cells'
/// occupancy probabilities and known flags row by row (row 0 the lowest y): the small map
/// the writers' tests turn into files.
pub fn raster_3x2(probabilities: [f64; 6], known: [bool; 6]) -> fusemap_core::grid::Raster {
    use fusemap_core::grid::{logodds::logit, CellIndex, OccupancyParams, Raster};
    Raster {
        width: 3,
        height: 2,
        resolution: 0.5,
        origin: fusemap_core::geometry::Point2::new(10.0, 20.0),
        first_cell: CellIndex::new(0, 0),
        log_odds: probabilities.iter().map(|&p| logit(p) as f32).collect(),
        known: known.to_vec(),
        params: OccupancyParams::default(),
    }
}
