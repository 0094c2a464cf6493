//! Camera images and calibrations written by a third-party tool (`rosbags`) into a ROS 1
//! bag and rosbag2 directories with SQLite3 and MCAP storage, read back with fusemap's
//! readers: every field as written, the pixels decoded into class ids and metres as the
//! script computed them, and a default (first-pass) read that keeps only the images'
//! stamps, frames and sizes.
//!
//! The fixtures are made at test time by `crates/fusemap-io/tests/make_camera_fixtures.py`;
//! without python3 and rosbags the test is skipped, or fails under `FUSEMAP_NO_SKIP=1`.

use fusemap_io::camera;
use fusemap_io::log::{open_log, open_log_with, ImagePayloads, LogMessage, ReadOptions};
use fusemap_io::testdata;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const OUTPUTS: [&str; 3] = ["ros1.bag", "rosbag2_sqlite3", "rosbag2_mcap"];

/// Runs the script into a temporary directory: the directory and the JSON summary.
fn fixtures() -> Option<(tempfile::TempDir, Value)> {
    let python = testdata::python_with(&["rosbags.rosbag1", "rosbags.rosbag2", "numpy"])?;
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/make_camera_fixtures.py");
    let tmp = tempfile::tempdir().unwrap();
    let run = Command::new(&python).arg(&script).arg(tmp.path().join("out")).output().expect("running the script");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let summary = serde_json::from_slice(&run.stdout).expect("the script's JSON summary");
    Some((tmp, summary))
}

fn read(path: &Path, options: &ReadOptions) -> Vec<LogMessage> {
    let mut reader = open_log_with(path, options).unwrap_or_else(|e| panic!("{e}")).reader;
    let out: Vec<LogMessage> =
        std::iter::from_fn(|| reader.next_message()).map(|m| m.unwrap_or_else(|e| panic!("{e}"))).collect();
    let stats = reader.stats();
    assert!(stats.skipped_by_type.is_empty() && stats.malformed == 0, "{}: {stats:?}", path.display());
    out
}

fn u64s(v: &Value) -> Vec<u64> {
    v.as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect()
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

#[test]
fn rosbags_images_and_camera_info_decode_as_written() {
    let Some((tmp, summary)) = fixtures() else { return };
    let expected = summary["messages"].as_array().unwrap();
    assert_eq!(expected.len(), 15);
    for name in OUTPUTS {
        let path = tmp.path().join("out").join(name);
        let mut got = read(&path, &ReadOptions { images: ImagePayloads::All, ..Default::default() });
        got.sort_by_key(|m| m.receive_stamp());
        assert_eq!(got.len(), expected.len(), "{name}");
        for (m, e) in got.iter().zip(expected) {
            let what = format!("{name}: {e}");
            let stamp = e["sec"].as_i64().unwrap() * 1_000_000_000 + e["nanosec"].as_i64().unwrap();
            assert_eq!(m.topic(), e["topic"].as_str().unwrap(), "{what}");
            assert_eq!(m.stamp().unwrap().0, stamp, "{what}");
            assert_eq!(m.receive_stamp().unwrap().0 as u64, e["log_time"].as_u64().unwrap(), "{what}");
            match m {
                LogMessage::CameraInfo(c) => {
                    assert_eq!(c.frame_id, "camera_optical");
                    assert_eq!((c.width, c.height, c.distortion_model.as_str()), (640, 480, "plumb_bob"));
                    assert_eq!(c.d, f64s(&e["d"]), "{what}");
                    assert_eq!(c.k.to_vec(), f64s(&e["k"]), "{what}");
                }
                LogMessage::Image(i) => {
                    assert_eq!(i.frame_id, "camera_optical");
                    assert_eq!(i.encoding, e["encoding"].as_str().unwrap(), "{what}");
                    assert_eq!(i.is_bigendian, e["is_bigendian"].as_u64() == Some(1), "{what}");
                    let sizes = [u64::from(i.width), u64::from(i.height), u64::from(i.step)];
                    assert_eq!(sizes.to_vec(), [&e["width"], &e["height"], &e["step"]].map(|v| v.as_u64().unwrap()));
                    let data: Vec<u64> = i.data.iter().map(|&b| u64::from(b)).collect();
                    assert_eq!(data, u64s(&e["data"]), "{what}");
                    if let Some(labels) = e.get("labels") {
                        let l = camera::labels(i).unwrap_or_else(|err| panic!("{what}: {err}"));
                        assert_eq!((l.width, l.height), (i.width, i.height));
                        let ids: Vec<u64> = l.labels.iter().map(|&v| u64::from(v)).collect();
                        assert_eq!(ids, u64s(labels), "{what}");
                        assert!(camera::depth(i).is_err() || i.encoding == "mono16");
                    } else {
                        let d = camera::depth(i).unwrap_or_else(|err| panic!("{what}: {err}"));
                        let want = e["metres"].as_array().unwrap();
                        assert_eq!(d.metres.len(), want.len());
                        for (got, want) in d.metres.iter().zip(want) {
                            match want.as_u64() {
                                Some(bits) => assert_eq!(u64::from(got.to_bits()), bits, "{what}: {got}"),
                                None => assert!(got.is_nan(), "{what}: {got}"),
                            }
                        }
                        assert!(camera::labels(i).is_err() || i.encoding == "16UC1");
                    }
                }
                other => panic!("{what}: {other:?}"),
            }
        }
    }
}

/// What a first pass keeps of each image topic: stamps and frame ids per topic.
#[derive(Debug, Default, PartialEq)]
struct CameraTopic {
    stamps: Vec<i64>,
    frames: BTreeMap<String, usize>,
    sizes: Vec<(u32, u32, String)>,
}

#[test]
fn a_default_read_gives_image_headers_for_an_inventory() {
    let Some((tmp, summary)) = fixtures() else { return };
    let mut expected: BTreeMap<String, CameraTopic> = BTreeMap::new();
    for e in summary["messages"].as_array().unwrap() {
        if e.get("encoding").is_none() {
            continue;
        }
        let t = expected.entry(e["topic"].as_str().unwrap().to_string()).or_default();
        t.stamps.push(e["sec"].as_i64().unwrap() * 1_000_000_000 + e["nanosec"].as_i64().unwrap());
        *t.frames.entry(e["frame_id"].as_str().unwrap().to_string()).or_default() += 1;
        let size = |k: &str| e[k].as_u64().unwrap() as u32;
        t.sizes.push((size("width"), size("height"), e["encoding"].as_str().unwrap().to_string()));
    }
    assert_eq!(expected.len(), 4);
    for name in OUTPUTS {
        let path = tmp.path().join("out").join(name);
        let mut reader = open_log(&path).unwrap().reader;
        let mut got: BTreeMap<String, CameraTopic> = BTreeMap::new();
        let mut infos = 0;
        while let Some(m) = reader.next_message() {
            match m.unwrap() {
                LogMessage::ImageHeader(h) => {
                    assert_eq!(h.data_len, u64::from(h.step) * u64::from(h.height), "{name}");
                    let t = got.entry(h.topic).or_default();
                    t.stamps.push(h.stamp.0);
                    *t.frames.entry(h.frame_id).or_default() += 1;
                    t.sizes.push((h.width, h.height, h.encoding));
                }
                LogMessage::CameraInfo(_) => infos += 1,
                other => panic!("{name}: an image with pixels or another message in a default read: {other:?}"),
            }
        }
        assert_eq!(infos, 3, "{name}");
        assert_eq!(got, expected, "{name}");
        // Asking for one topic gives its pixels and leaves the others as headers.
        let some = read(&path, &ReadOptions::with_image_topics(["/camera/depth"]));
        for m in &some {
            match m {
                LogMessage::Image(i) => assert_eq!(i.topic, "/camera/depth"),
                LogMessage::ImageHeader(h) => assert_ne!(h.topic, "/camera/depth"),
                LogMessage::CameraInfo(_) => {}
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(some.iter().filter(|m| matches!(m, LogMessage::Image(_))).count(), 3, "{name}");
    }
}
