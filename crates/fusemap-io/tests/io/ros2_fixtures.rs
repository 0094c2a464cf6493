//! ROS 2 and ROS 1 logs written by third-party tools (`rosbags`, `mcap` +
//! `mcap-ros2-support`) from one CARMEN log, read back with fusemap's readers: the three
//! ROS 2 containers and the ROS 1 bag must give the same scans, odometry and transforms,
//! bit for bit, and as many as the writer reports.
//!
//! The fixtures are made at test time by `tests/fixtures/make_ros_fixtures.py` (see
//! `tests/fixtures/README.md`); without python3 and those packages the test is skipped,
//! or fails under `FUSEMAP_NO_SKIP=1`.

use fusemap_io::log::{open_log, LogMessage, OdomMessage, ScanMessage, TfMessage};
use fusemap_io::testdata;
use std::path::{Path, PathBuf};
use std::process::Command;

fn python_with_writers() -> Option<String> {
    testdata::python_with(&["rosbags.rosbag1", "rosbags.rosbag2", "mcap", "mcap_ros2.writer", "numpy"])
}

#[derive(Default)]
struct Decoded {
    scans: Vec<ScanMessage>,
    odometry: Vec<OdomMessage>,
    tf: Vec<TfMessage>,
    tf_static: Vec<TfMessage>,
}

fn read(path: &Path) -> Decoded {
    let mut reader = open_log(path).unwrap_or_else(|e| panic!("{e}")).reader;
    let mut d = Decoded::default();
    while let Some(m) = reader.next_message() {
        match m.unwrap_or_else(|e| panic!("{e}")) {
            LogMessage::Scan(s) => d.scans.push(s),
            LogMessage::Odometry(o) => d.odometry.push(o),
            LogMessage::Tf(t) if t.is_static => d.tf_static.push(t),
            LogMessage::Tf(t) => d.tf.push(t),
            LogMessage::Imu(_)
            | LogMessage::Gnss(_)
            | LogMessage::Pose(_)
            | LogMessage::Image(_)
            | LogMessage::ImageHeader(_)
            | LogMessage::CameraInfo(_) => {
                panic!("{}: only scans, odometry and transforms were written", path.display())
            }
        }
    }
    assert!(reader.stats().skipped_by_type.is_empty(), "{:?}", reader.stats());
    d
}

/// Equal bit for bit (ranges compared as bits, so NaN payloads count too).
fn assert_same_scans(a: &[ScanMessage], b: &[ScanMessage], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: scan count");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let bits = |s: &ScanMessage| s.scan.ranges.iter().map(|r| r.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(x), bits(y), "{what}: ranges of scan {i}");
        assert_eq!(x.scan.stamp, y.scan.stamp, "{what}: stamp of scan {i}");
        assert_eq!(x.scan.angle_min.to_bits(), y.scan.angle_min.to_bits(), "{what}: scan {i}");
        assert_eq!(x.scan.angle_increment.to_bits(), y.scan.angle_increment.to_bits(), "{what}: scan {i}");
        assert_eq!(
            (&x.topic, &x.frame_id, x.receive_stamp, x.range_min.to_bits(), x.range_max.to_bits()),
            (&y.topic, &y.frame_id, y.receive_stamp, y.range_min.to_bits(), y.range_max.to_bits()),
            "{what}: scan {i}"
        );
    }
}

#[test]
fn third_party_ros_logs_decode_identically() {
    let Some(python) = python_with_writers() else { return };
    let Some(carmen) = testdata::dataset("intel/intel-corrected.log.gz") else { return };
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/make_ros_fixtures.py");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = Command::new(&python)
        .arg(&script)
        .arg(&carmen)
        .arg(&out)
        .args(["--max-scans", "200"])
        .output()
        .expect("running the fixture script");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&run.stdout).expect("the script's JSON summary");
    let count = |topic: &str| summary["counts"][topic].as_u64().unwrap_or_else(|| panic!("count of {topic}")) as usize;

    let outputs = ["rosbag2_mcap", "rosbag2_sqlite3", "bare.mcap", "ros1.bag"];
    let decoded: Vec<Decoded> = outputs.iter().map(|o| read(&out.join(o))).collect();
    let first = &decoded[0];

    assert_eq!(first.scans.len(), 200);
    assert_eq!(first.scans.len(), count("/scan"));
    assert_eq!(first.odometry.len(), count("/odom"));
    assert_eq!(first.tf.len(), count("/tf"));
    assert_eq!(first.tf_static.len(), count("/tf_static"));
    assert_eq!(first.tf_static.len(), 1);

    // What the script promises about the content.
    let t = &first.tf_static[0].transforms[0];
    assert_eq!((t.parent.as_str(), t.child.as_str()), ("base_link", "laser"));
    assert_eq!((t.translation, t.rotation), ([0.0; 3], [0.0, 0.0, 0.0, 1.0]));
    for s in &first.scans {
        assert_eq!(s.frame_id, "laser");
        assert_eq!(s.scan.ranges.len(), 180, "intel's FLASER lines have 180 readings");
        assert_eq!(s.scan.angle_min, f64::from(-std::f32::consts::FRAC_PI_2));
        assert_eq!(s.scan.angle_increment, f64::from(std::f32::consts::PI / 180.0));
        assert_eq!(s.range_min, 0.0);
        assert!(s.range_max == 50.0 || s.range_max == 81.0);
    }
    // Scan 0 of intel-corrected.log is stamped 32.9068 s: split exactly, not through f64.
    assert_eq!(first.scans[0].scan.stamp.0, 32_906_800_000);
    for (o, tf) in first.odometry.iter().zip(&first.tf) {
        let t = &tf.transforms[0];
        assert_eq!((o.frame_id.as_str(), o.child_frame_id.as_str()), ("odom", "base_link"));
        assert_eq!((t.parent.as_str(), t.child.as_str()), ("odom", "base_link"));
        assert_eq!((t.stamp, t.translation[0], t.translation[1]), (o.stamp, o.pose.x, o.pose.y));
        assert_eq!(o.receive_stamp, tf.receive_stamp);
    }

    for (name, other) in outputs.iter().zip(&decoded).skip(1) {
        let what = format!("{} vs {name}", outputs[0]);
        assert_same_scans(&first.scans, &other.scans, &what);
        assert_eq!(first.odometry, other.odometry, "{what}: odometry");
        assert_eq!(first.tf, other.tf, "{what}: /tf");
        assert_eq!(first.tf_static, other.tf_static, "{what}: /tf_static");
    }
}
