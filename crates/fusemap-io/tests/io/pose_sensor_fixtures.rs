//! GNSS fixes, IMU readings and pose estimates written by a third-party tool (`rosbags`)
//! into a ROS 1 bag and a rosbag2 MCAP directory, read back with fusemap's readers: every
//! field must come back as written, floats bit for bit (NaN, infinities and -0.0
//! included), and nothing may be skipped.
//!
//! The fixtures are made at test time by `tests/fixtures/make_pose_sensor_fixtures.py`;
//! without python3 and rosbags the test is skipped, or fails under `FUSEMAP_NO_SKIP=1`.

use fusemap_io::log::{open_log, LogMessage};
use fusemap_io::testdata;
use std::path::{Path, PathBuf};
use std::process::Command;

fn python_with_rosbags() -> Option<String> {
    testdata::python_with(&["rosbags.rosbag1", "rosbags.rosbag2", "numpy"])
}

/// One message reduced to what both sides can state: topic, log time, header stamp
/// (sec, nanosec), frame, the integer fields, the float64 fields as bits.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Flat {
    log_time: u64,
    topic: String,
    stamp: (i64, u32),
    frame_id: String,
    ints: Vec<i64>,
    f64_bits: Vec<u64>,
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

fn flatten(m: LogMessage) -> Flat {
    let log_time = m.receive_stamp().expect("ROS logs have log times").0 as u64;
    let stamp = m.stamp().expect("a header stamp");
    let stamp = (stamp.0.div_euclid(1_000_000_000), stamp.0.rem_euclid(1_000_000_000) as u32);
    let topic = m.topic().to_string();
    let (frame_id, ints, f64_bits) = match m {
        LogMessage::Gnss(g) => {
            let mut f = vec![g.latitude, g.longitude, g.altitude];
            f.extend(g.position_covariance);
            let ints = vec![i64::from(g.status), i64::from(g.service), i64::from(g.position_covariance_type)];
            (g.frame_id, ints, bits(&f))
        }
        LogMessage::Imu(i) => {
            let mut f = i.orientation.to_vec();
            f.extend(i.orientation_covariance);
            f.extend(i.angular_velocity);
            f.extend(i.angular_velocity_covariance);
            f.extend(i.linear_acceleration);
            f.extend(i.linear_acceleration_covariance);
            (i.frame_id, vec![], bits(&f))
        }
        LogMessage::Pose(p) => {
            let mut f = p.position.to_vec();
            f.extend(p.orientation);
            f.extend(p.covariance);
            (p.frame_id, vec![], bits(&f))
        }
        other => panic!("only fixes, IMU readings and poses were written: {other:?}"),
    };
    Flat { log_time, topic, stamp, frame_id, ints, f64_bits }
}

/// What the script says it wrote.
fn written(summary: &serde_json::Value) -> Vec<Flat> {
    let messages = summary["messages"].as_array().expect("the written messages");
    messages
        .iter()
        .map(|m| {
            let int = |k: &str| m[k].as_i64().unwrap_or_else(|| panic!("{k} of {m}"));
            let topic = m["topic"].as_str().unwrap().to_string();
            let ints =
                if topic == "/fix" { vec![int("status"), int("service"), int("covariance_type")] } else { vec![] };
            Flat {
                log_time: m["log_time"].as_u64().unwrap(),
                topic,
                stamp: (int("sec"), int("nanosec") as u32),
                frame_id: m["frame_id"].as_str().unwrap().to_string(),
                ints,
                f64_bits: m["f64"].as_array().unwrap().iter().map(|b| b.as_u64().unwrap()).collect(),
            }
        })
        .collect()
}

fn read(path: &Path) -> Vec<Flat> {
    let mut reader = open_log(path).unwrap_or_else(|e| panic!("{e}")).reader;
    let mut out = Vec::new();
    while let Some(m) = reader.next_message() {
        out.push(flatten(m.unwrap_or_else(|e| panic!("{e}"))));
    }
    let stats = reader.stats();
    assert!(stats.skipped_by_type.is_empty() && stats.malformed == 0, "{}: {stats:?}", path.display());
    out.sort();
    out
}

#[test]
fn rosbags_fixes_imu_and_poses_decode_as_written() {
    let Some(python) = python_with_rosbags() else { return };
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/make_pose_sensor_fixtures.py");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = Command::new(&python).arg(&script).arg(&out).output().expect("running the fixture script");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&run.stdout).expect("the script's JSON summary");
    let mut expected = written(&summary);
    expected.sort();
    assert_eq!(expected.len(), 75);
    for topic in ["/fix", "/imu", "/amcl_pose"] {
        assert_eq!(expected.iter().filter(|m| m.topic == topic).count(), 25, "{topic}");
    }
    // The script's special values reach the files: NaN and a zero quaternion at least.
    assert!(expected.iter().any(|m| m.f64_bits.iter().any(|b| f64::from_bits(*b).is_nan())));
    assert!(expected.iter().any(|m| m.topic == "/amcl_pose" && m.f64_bits[3..7].iter().all(|b| *b == 0)));

    for name in ["ros1.bag", "rosbag2_mcap"] {
        let decoded = read(&out.join(name));
        assert_eq!(decoded.len(), expected.len(), "{name}: message count");
        for (d, e) in decoded.iter().zip(&expected) {
            assert_eq!(d, e, "{name}");
        }
    }
}
