//! Format equivalence: the same scans and poses read from CARMEN text, a ROS 1 bag and
//! ROS 2 logs (rosbag2 with MCAP or SQLite storage, a bare MCAP), all written from one
//! CARMEN log by third-party tools, must give bit-identical maps.
//!
//! The five logs are made at test time by `tests/fixtures/make_ros_fixtures.py` (see
//! `tests/fixtures/README.md`); without python3 and its pinned packages, or without the
//! shared datasets, the tests skip (and fail under `FUSEMAP_NO_SKIP=1`).

use crate::util::{repo_root, run, stderr, stdout, temp_dir};
use fusemap_io::npz::{read_npz, NpyOwned, NpyValues};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// FLASER lines of `intel-corrected.log.gz` the fixtures hold.
pub const FIXTURE_SCANS: u64 = 300;

/// The interpreter: `$FUSEMAP_PYTHON`, else `python3` (tests/fixtures/README.md).
fn python() -> String {
    std::env::var("FUSEMAP_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Makes the fixtures once per test run; `None` (after the skip notice) when python, its
/// packages or the dataset are missing.
fn make_fixtures() -> Option<PathBuf> {
    let carmen = fusemap_io::testdata::dataset("intel/intel-corrected.log.gz")?;
    let python = python();
    let imports = "import rosbags.rosbag1, rosbags.rosbag2, mcap, mcap_ros2.writer, numpy";
    if !Command::new(&python).args(["-c", imports]).output().is_ok_and(|o| o.status.success()) {
        fusemap_io::testdata::skip(&format!(
            "`{python}` cannot import rosbags, mcap, mcap_ros2 and numpy \
             (pip install -r tests/fixtures/requirements.txt)"
        ));
        return None;
    }
    let out = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "ros-fixtures").join("out");
    let o = Command::new(&python)
        .arg(repo_root().join("tests/fixtures/make_ros_fixtures.py"))
        .arg(&carmen)
        .arg(&out)
        .args(["--max-scans", &FIXTURE_SCANS.to_string(), "--carmen-subset"])
        .output()
        .expect("cannot start python");
    assert!(o.status.success(), "make_ros_fixtures.py failed:\n{}", stderr(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the script's JSON summary");
    assert_eq!(summary["counts"]["/scan"], FIXTURE_SCANS, "{summary}");
    Some(out)
}

/// The directory of the fixtures made from the first [`FIXTURE_SCANS`] scans of
/// `intel-corrected.log.gz`: `carmen.log`, `ros1.bag`, `rosbag2_mcap/`,
/// `rosbag2_sqlite3/`, `bare.mcap`.
pub fn intel_fixtures() -> Option<&'static Path> {
    static DIR: OnceLock<Option<PathBuf>> = OnceLock::new();
    DIR.get_or_init(make_fixtures).as_deref()
}

/// An array of `map.npz` as its raw little-endian bytes, with its shape.
fn raw(npz: &Path, name: &str) -> (Vec<usize>, Vec<u8>) {
    let NpyOwned { shape, values } = read_npz(npz, name).unwrap_or_else(|e| panic!("{e}"));
    let bytes = match values {
        NpyValues::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        NpyValues::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        NpyValues::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        NpyValues::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        NpyValues::I16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        NpyValues::Bool(v) => v.iter().map(|&b| u8::from(b)).collect(),
        NpyValues::U8(v) => v,
        NpyValues::Str(v) => v.iter().flat_map(|s| s.bytes().chain([0])).collect(),
    };
    (shape, bytes)
}

/// What one run produced.
struct Mapped {
    input: &'static str,
    scans: u64,
    log_odds: (Vec<usize>, Vec<u8>),
    known: (Vec<usize>, Vec<u8>),
    origin: (Vec<usize>, Vec<u8>),
    resolution: (Vec<usize>, Vec<u8>),
}

#[test]
fn the_same_log_in_five_formats_gives_bit_identical_maps() {
    let Some(fixtures) = intel_fixtures() else { return };
    let dir = temp_dir("formats");
    // Every format posed the same way: odometry interpolated at each scan's stamp (the
    // CARMEN lines' own poses would otherwise be used for the text log).
    let config = dir.join("odometry.toml");
    std::fs::write(&config, "[log]\npose_source = \"odometry\"\n").expect("cannot write the config");
    let inputs = [
        ("carmen.log", "carmen"),
        ("ros1.bag", "ros1-bag"),
        ("rosbag2_mcap", "rosbag2"),
        ("rosbag2_sqlite3", "rosbag2"),
        ("bare.mcap", "mcap"),
    ];
    let mut runs = Vec::new();
    for (input, format) in inputs {
        let out = dir.join(format!("map-{input}"));
        let path = fixtures.join(input);
        let o =
            run(&["map", "--config", config.to_str().unwrap(), "--out", out.to_str().unwrap(), path.to_str().unwrap()]);
        assert!(o.status.success(), "fusemap map {input} failed:\n{}\n{}", stdout(&o), stderr(&o));
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary.json")).expect("JSON");
        assert_eq!(summary["source_kind"], format, "{input}");
        let pose_source = summary["log"]["pose_source"].as_str().unwrap_or_default();
        // SLAM corrects the odometry (on by default for raw odometry): the same scans and
        // odometry in every format give the same SLAM track, bit for bit.
        assert!(
            pose_source.starts_with("SLAM") && pose_source.contains("over odometry"),
            "{input}: posed by {pose_source}"
        );
        assert_eq!(summary["log"]["scans_read"], FIXTURE_SCANS, "{input}");
        let npz = out.join("map.npz");
        runs.push(Mapped {
            input,
            scans: summary["scans"].as_u64().expect("summary.scans"),
            log_odds: raw(&npz, "log_odds"),
            known: raw(&npz, "known"),
            origin: raw(&npz, "origin"),
            resolution: raw(&npz, "resolution"),
        });
    }

    let first = &runs[0];
    assert!(first.scans > 0);
    for other in &runs[1..] {
        let what = format!("{} vs {}", first.input, other.input);
        assert_eq!(first.scans, other.scans, "{what}: scans mapped");
        assert_eq!(first.origin, other.origin, "{what}: origin");
        assert_eq!(first.resolution, other.resolution, "{what}: resolution");
        assert_eq!(first.log_odds.0, other.log_odds.0, "{what}: shape");
        assert_eq!(first.known.0, other.known.0, "{what}: shape of `known`");
        for (name, a, b, size) in
            [("log_odds", &first.log_odds.1, &other.log_odds.1, 4), ("known", &first.known.1, &other.known.1, 1)]
        {
            let differing = a.chunks(size).zip(b.chunks(size)).filter(|(x, y)| x != y).count();
            assert!(a == b, "{what}: {differing} cells of `{name}` differ");
        }
    }
    let cells = first.known.1.len();
    let known = first.known.1.iter().filter(|&&b| b != 0).count();
    eprintln!(
        "formats: {} scans mapped from each of {} inputs; {cells} cells ({known} known) bit-identical",
        first.scans,
        runs.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The ROS 2 fixture's `metadata.yaml` rewritten in flow style and as JSON (by ruamel.yaml,
/// the YAML library of the `rosbags` that wrote the bag) maps to the same bytes as the
/// block style `rosbags` wrote.
#[test]
fn a_metadata_yaml_in_block_flow_or_json_style_maps_the_bag_identically() {
    let Some(fixtures) = intel_fixtures() else { return };
    let dir = temp_dir("metadata-styles");
    let restyle = "\
import io, json, sys
from pathlib import Path
from ruamel.yaml import YAML
path, style = Path(sys.argv[1]), sys.argv[2]
doc = YAML(typ='safe', pure=True).load(path.read_text())
if style == 'json':
    path.write_text(json.dumps(doc, indent=2))
else:
    out = YAML(typ='safe', pure=True)
    out.default_flow_style = True
    buf = io.StringIO()
    out.dump(doc, buf)
    path.write_text(buf.getvalue())
";
    let mut maps = Vec::new();
    for style in ["block", "flow", "json"] {
        let bag = dir.join(format!("bag-{style}"));
        std::fs::create_dir_all(&bag).expect("cannot make the bag directory");
        for entry in std::fs::read_dir(fixtures.join("rosbag2_mcap")).expect("the fixture bag") {
            let entry = entry.expect("a directory entry");
            std::fs::copy(entry.path(), bag.join(entry.file_name())).expect("cannot copy the bag");
        }
        let metadata = bag.join("metadata.yaml");
        if style != "block" {
            let o = Command::new(python()).args(["-c", restyle]).arg(&metadata).arg(style).output().expect("python");
            assert!(o.status.success(), "restyling failed:\n{}", stderr(&o));
        }
        let text = std::fs::read_to_string(&metadata).expect("metadata.yaml");
        assert_eq!(text.trim_start().starts_with('{'), style != "block", "{style}:\n{text}");
        let out = dir.join(format!("out-{style}"));
        let o = run(&["map", "--out", out.to_str().unwrap(), bag.to_str().unwrap()]);
        assert!(o.status.success(), "{style}: fusemap map failed:\n{}\n{}", stdout(&o), stderr(&o));
        maps.push((style, std::fs::read(out.join("map.npz")).expect("map.npz")));
    }
    for (style, bytes) in &maps[1..] {
        assert!(*bytes == maps[0].1, "{style} style: map.npz differs from the block style's");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
