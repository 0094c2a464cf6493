//! Helpers shared by the integration tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `fusemap` binary cargo built for these tests.
pub fn fusemap() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fusemap"))
}

/// Runs `fusemap` with `args`.
pub fn run(args: &[&str]) -> Output {
    fusemap().args(args).output().expect("cannot start fusemap")
}

/// A fresh, empty directory for one test, removed when the value is dropped
/// ([`fusemap_io::testdata::TestDir`]).
pub fn temp_dir(name: &str) -> fusemap_io::testdata::TestDir {
    fusemap_io::testdata::temp_dir(&format!("cli-{name}"))
}

/// stdout as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts a failed run printed one clear error line, no panic, and returns it.
pub fn one_line_error(o: &Output) -> String {
    assert!(!o.status.success(), "expected failure, got success; stdout: {}", stdout(o));
    let err = stderr(o);
    assert!(!err.contains("panicked"), "panic: {err}");
    assert!(!err.contains("RUST_BACKTRACE"), "backtrace hint: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected one error line, got: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    lines[0].to_string()
}

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A file of the repository, by its path from the root.
pub fn repo_file(relative: &str) -> PathBuf {
    repo_root().join(relative)
}

/// Writes `contents` to `dir/name` and returns the path.
pub fn write_file(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap_or_else(|e| panic!("cannot write {}: {e}", p.display()));
    p
}

/// The names in `dir`, sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A JSON file, parsed.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{} is not JSON: {e}", path.display()))
}

/// Asserts a run succeeded, showing its output otherwise.
pub fn assert_success(o: &Output) {
    assert!(o.status.success(), "fusemap failed ({}):\nstdout: {}\nstderr: {}", o.status, stdout(o), stderr(o));
}

/// The Python interpreter: `$FUSEMAP_PYTHON`, else `python3` (tests/fixtures/README.md).
pub fn python() -> Command {
    Command::new(std::env::var_os("FUSEMAP_PYTHON").unwrap_or_else(|| "python3".into()))
}

/// True when Python runs and imports every module of `modules`; otherwise prints a skip
/// notice (a failure under `FUSEMAP_NO_SKIP=1`) and returns false.
pub fn python_with(modules: &[&str]) -> bool {
    let code: String = modules.iter().map(|m| format!("import {m}\n")).collect();
    match python().args(["-c", &code]).output() {
        Ok(o) if o.status.success() => true,
        Ok(o) => {
            let why = stderr(&o);
            let last = why.lines().last().unwrap_or("").trim();
            fusemap_io::testdata::skip(&format!("python cannot import {}: {last}", modules.join(", ")));
            false
        }
        Err(e) => {
            fusemap_io::testdata::skip(&format!("cannot run python ($FUSEMAP_PYTHON or python3): {e}"));
            false
        }
    }
}

/// Runs a Python script with `args`, asserting it succeeds, and returns its stdout.
pub fn run_python(script: &str, args: &[&std::ffi::OsStr]) -> String {
    let o = python().arg("-c").arg(script).args(args).output().expect("cannot start python");
    assert!(o.status.success(), "python failed:\nstdout: {}\nstderr: {}", stdout(&o), stderr(&o));
    stdout(&o)
}

/// Reads `dir`'s `map.mcap`, `map.pcd` and `map.ply` with third-party readers
/// (`tests/fixtures/check_map_outputs.py`: mcap-ros2-support, rosbags with ROS 2 Humble's
/// definitions, pypcd4, plyfile) and checks them against `map.pgm` and `trajectory.tum`,
/// classifying `/map` with the default thresholds. Returns the script's counts, `None`
/// when the readers are missing (a skip).
pub fn check_map_outputs(dir: &Path) -> Option<serde_json::Value> {
    if !python_with(&["mcap_ros2", "rosbags", "plyfile", "pypcd4", "numpy"]) {
        return None;
    }
    let params = fusemap_core::grid::OccupancyParams::default();
    let o = python()
        .arg(repo_file("tests/fixtures/check_map_outputs.py"))
        .arg(dir)
        .args([params.occupied_threshold.to_string(), params.free_threshold.to_string()])
        .output()
        .expect("cannot start python");
    assert!(o.status.success(), "map outputs disagree:\nstdout: {}\nstderr: {}", stdout(&o), stderr(&o));
    Some(serde_json::from_str(&stdout(&o)).expect("the checker prints JSON"))
}

/// A CARMEN log of `scans` FLASER lines in a corridor with walls at y = ±1 m: `beams`
/// beams over 180° from the right (beam `k` at `k · 180 / beams − 90` degrees), each range
/// `1 / |sin|` capped at `max_range_m` plus `0.001 · ((i + k) mod jitter)` metres so no two
/// scans repeat, scan `i` at x = `x(i)` and 1 + 0.1 i s.
pub fn corridor_log(scans: usize, beams: usize, max_range_m: f64, jitter: usize, x: impl Fn(usize) -> f64) -> String {
    let lines: Vec<String> = (0..scans)
        .map(|i| {
            let ranges: Vec<String> = (0..beams)
                .map(|k| {
                    let a = (k as f64 * (180.0 / beams as f64) - 90.0).to_radians();
                    format!("{:.3}", (1.0 / a.sin().abs()).min(max_range_m) + 0.001 * ((i + k) % jitter) as f64)
                })
                .collect();
            let (x, t) = (x(i), 1.0 + 0.1 * i as f64);
            format!("FLASER {beams} {} {x:.2} 0 0 {x:.2} 0 0 {t:.3} host {t:.3}", ranges.join(" "))
        })
        .collect();
    lines.join("\n") + "\n"
}
