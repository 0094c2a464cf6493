//! `fusemap doctor`: its whole report on real logs, as snapshots
//! (`snapshots/cli__doctor__*.snap`; review a change with `cargo insta review`, or rerun
//! with `INSTA_UPDATE=always` and read the diff).
//!
//! The figures were checked against an independent reading when the snapshots were made
//! (`rosbags` for the bags: message counts, rates, jitter, regressions in log-time order,
//! pauses, the share of scans interpolation can pose; a Python scan of the CARMEN text).

use crate::formats::intel_fixtures;
use crate::util::{run, stderr, stdout};
use std::path::Path;

/// `fusemap doctor LOG`'s stdout, after checking it succeeded.
fn doctor(log: &Path) -> String {
    let o = run(&["doctor", log.to_str().unwrap()]);
    assert!(o.status.success(), "fusemap doctor {} failed:\n{}", log.display(), stderr(&o));
    stdout(&o)
}

/// The SLAM-benchmark Intel bag (ROS 1, bz2 chunks): odometry pauses while the robot
/// stands, and some of them too long to bridge.
#[test]
fn doctor_intel_orig_bag() {
    let Some(bag) = fusemap_io::testdata::dataset("rosbag1-slam-benchmark/intel.orig.bag") else { return };
    insta::assert_snapshot!(doctor(&bag));
}

/// The bare MCAP written by `make_ros_fixtures.py` from the first 300 scans of the
/// corrected Intel log: keyframe scans, re-anchored odometry with repeated stamps.
#[test]
fn doctor_ros2_mcap_fixture() {
    let Some(fixtures) = intel_fixtures() else { return };
    insta::assert_snapshot!(doctor(&fixtures.join("bare.mcap")));
}

/// The raw MIT CSAIL CARMEN log: poses on the scan lines, logger time counted from the
/// start of the log while the scans carry Unix time.
#[test]
fn doctor_mit_csail_clf() {
    let Some(clf) = fusemap_io::testdata::dataset("mit-csail-raw/mit-csail.clf") else { return };
    insta::assert_snapshot!(doctor(&clf));
}

/// A log `fusemap map` refuses (odometry and no scan): the doctor prints its report and
/// exits non-zero with the same reason, so a script cannot take it for a healthy log.
#[test]
fn doctor_fails_on_a_log_map_would_refuse() {
    let dir = crate::util::temp_dir("doctor-no-scans");
    let log = crate::util::write_file(
        &dir,
        "odometry-only.log",
        "ODOM 0.0 0.0 0.0 0.0 0.0 0.0 100.0 host 0.0\nODOM 0.1 0.0 0.0 0.0 0.0 0.0 100.1 host 0.1\n",
    );
    let o = run(&["doctor", log.to_str().unwrap()]);
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("- cannot be mapped:") && !out.contains("no clock faults found"), "{out}");
    assert!(
        err.starts_with("error: ") && err.contains("cannot be mapped") && err.contains("odometry-only.log"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A mapping run keeps what the doctor finds in the log's streams and pose sensors
/// (`summary.json`'s `log.log_findings`, shown by `report.html`), in the doctor's words.
#[test]
fn map_keeps_the_doctors_findings_of_the_log() {
    let Some(fixtures) = intel_fixtures() else { return };
    let mcap = fixtures.join("bare.mcap");
    let dir = crate::util::temp_dir("doctor-in-map");
    let out = dir.join("out");
    let o = run(&["map", "--out", out.to_str().unwrap(), mcap.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let found: Vec<&str> = summary["log"]["log_findings"]
        .as_array()
        .expect("log.log_findings")
        .iter()
        .filter_map(|f| f.as_str())
        .collect();
    // The fixture's re-anchored odometry repeats stamps: at least that is found.
    assert!(found.iter().any(|f| f.contains("repeats a stamp")), "{found:?}");
    let doctor = doctor(&mcap);
    for f in &found {
        assert!(doctor.contains(&format!("- {f}\n")), "{f:?} is not in the doctor's findings:\n{doctor}");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("<h3>The log</h3>") && html.contains("repeats a stamp"));
}
