//! fusemap's rosbag2 writer checked by a reader that is not fusemap's: the python
//! `rosbags` library (`rosbags_dump.py` beside this file) opens the bag, and every topic,
//! type, count, QoS profile, message definition and every field of every message must be
//! what was written. rosbags must also serialise each message back to exactly the bytes
//! in the bag, so the CDR layout matches its encoder byte for byte. The `mcap-ros2-support`
//! decoder, which knows types only from the schemas, must decode every message too.
//!
//! Without python3, rosbags and mcap-ros2-support (pip install -r tests/fixtures/requirements.txt) the test
//! is skipped, or fails under `FUSEMAP_NO_SKIP=1`.

use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::geometry_msgs::{
    Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, Transform, TransformStamped, Twist,
    TwistWithCovariance, Vector3,
};
use fusemap_io::log::ros2::msgs::nav_msgs::Odometry;
use fusemap_io::log::ros2::msgs::sensor_msgs::{
    CameraInfo, Image, Imu, LaserScan, NavSatFix, NavSatStatus, RegionOfInterest,
};
use fusemap_io::log::ros2::msgs::std_msgs::Header;
use fusemap_io::log::ros2::writer::{ChunkCompression, OutMessage, Rosbag2Writer, Rosbag2WriterOptions};
use fusemap_io::testdata;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

fn python_with_rosbags() -> Option<String> {
    testdata::python_with(&["rosbags.rosbag2", "rosbags.typesys", "numpy", "mcap.reader", "mcap_ros2.decoder"])
}

/// A float as the comparison expects it: compared by value with the repr python prints.
fn fl(x: f64) -> Value {
    json!(format!("f64:{:016x}", x.to_bits()))
}

fn fls(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|x| fl(*x)).collect())
}

fn fls32(v: &[f32]) -> Value {
    Value::Array(v.iter().map(|x| fl(f64::from(*x))).collect())
}

fn time(s: Stamp) -> Value {
    json!({ "sec": s.0.div_euclid(1_000_000_000), "nanosec": s.0.rem_euclid(1_000_000_000) })
}

fn header(h: &Header) -> Value {
    json!({ "stamp": time(h.stamp), "frame_id": h.frame_id })
}

fn vec3(v: [f64; 3]) -> Value {
    json!({ "x": fl(v[0]), "y": fl(v[1]), "z": fl(v[2]) })
}

fn quat(q: &Quaternion) -> Value {
    json!({ "x": fl(q.x), "y": fl(q.y), "z": fl(q.z), "w": fl(q.w) })
}

fn pose_cov(p: &PoseWithCovariance) -> Value {
    json!({ "pose": { "position": vec3(p.pose.position.to_array()), "orientation": quat(&p.pose.orientation) },
            "covariance": fls(&p.covariance) })
}

/// The message as rosbags' dataclasses hold it, field for field.
fn expected(m: &OutMessage) -> Value {
    match m {
        OutMessage::LaserScan(s) => json!({
            "header": header(&s.header),
            "angle_min": fl(s.angle_min.into()), "angle_max": fl(s.angle_max.into()),
            "angle_increment": fl(s.angle_increment.into()), "time_increment": fl(s.time_increment.into()),
            "scan_time": fl(s.scan_time.into()), "range_min": fl(s.range_min.into()), "range_max": fl(s.range_max.into()),
            "ranges": fls32(&s.ranges), "intensities": fls32(&s.intensities),
        }),
        OutMessage::Odometry(o) => json!({
            "header": header(&o.header), "child_frame_id": o.child_frame_id, "pose": pose_cov(&o.pose),
            "twist": { "twist": { "linear": vec3(o.twist.twist.linear.to_array()),
                                  "angular": vec3(o.twist.twist.angular.to_array()) },
                       "covariance": fls(&o.twist.covariance) },
        }),
        OutMessage::Imu(i) => json!({
            "header": header(&i.header),
            "orientation": quat(&i.orientation), "orientation_covariance": fls(&i.orientation_covariance),
            "angular_velocity": vec3(i.angular_velocity.to_array()), "angular_velocity_covariance": fls(&i.angular_velocity_covariance),
            "linear_acceleration": vec3(i.linear_acceleration.to_array()),
            "linear_acceleration_covariance": fls(&i.linear_acceleration_covariance),
        }),
        OutMessage::NavSatFix(f) => json!({
            "header": header(&f.header), "status": { "status": f.status.status, "service": f.status.service },
            "latitude": fl(f.latitude), "longitude": fl(f.longitude), "altitude": fl(f.altitude),
            "position_covariance": fls(&f.position_covariance), "position_covariance_type": f.position_covariance_type,
        }),
        OutMessage::PoseWithCovarianceStamped(p) => json!({ "header": header(&p.header), "pose": pose_cov(&p.pose) }),
        OutMessage::Tf { transforms, .. } => json!({ "transforms": transforms.iter().map(|t| json!({
            "header": header(&t.header), "child_frame_id": t.child_frame_id,
            "transform": { "translation": vec3(t.transform.translation.to_array()), "rotation": quat(&t.transform.rotation) },
        })).collect::<Vec<_>>() }),
        OutMessage::Image(i) => json!({
            "header": header(&i.header), "height": i.height, "width": i.width, "encoding": i.encoding,
            "is_bigendian": i.is_bigendian, "step": i.step, "data": i.data,
        }),
        OutMessage::CameraInfo(c) => json!({
            "header": header(&c.header), "height": c.height, "width": c.width, "distortion_model": c.distortion_model,
            "d": fls(&c.d), "k": fls(&c.k), "r": fls(&c.r), "p": fls(&c.p),
            "binning_x": c.binning_x, "binning_y": c.binning_y,
            "roi": { "x_offset": c.roi.x_offset, "y_offset": c.roi.y_offset, "height": c.roi.height,
                     "width": c.roi.width, "do_rectify": c.roi.do_rectify },
        }),
    }
}

/// Compares `expected` with what python printed: floats (tagged `f64:<bits>`) against
/// python's repr, bit for bit (NaN against NaN), everything else exactly.
fn same(expected: &Value, actual: &Value, path: &str) -> Result<(), String> {
    match (expected, actual) {
        (Value::String(e), Value::String(a)) if e.starts_with("f64:") => {
            let want = f64::from_bits(u64::from_str_radix(&e[4..], 16).unwrap());
            let got: f64 = a.parse().map_err(|_| format!("{path}: `{a}` is not a float"))?;
            if want.to_bits() == got.to_bits() || (want.is_nan() && got.is_nan()) {
                Ok(())
            } else {
                Err(format!("{path}: wrote {want:?}, rosbags read {got:?}"))
            }
        }
        (Value::Object(e), Value::Object(a)) => {
            let mut ek: Vec<&String> = e.keys().collect();
            let mut ak: Vec<&String> = a.keys().collect();
            ek.sort();
            ak.sort();
            if ek != ak {
                return Err(format!("{path}: fields {ek:?} written, rosbags has {ak:?}"));
            }
            e.iter().try_for_each(|(k, v)| same(v, &a[k], &format!("{path}.{k}")))
        }
        (Value::Array(e), Value::Array(a)) if e.len() == a.len() => {
            e.iter().zip(a).enumerate().try_for_each(|(i, (x, y))| same(x, y, &format!("{path}[{i}]")))
        }
        _ if expected == actual => Ok(()),
        _ => Err(format!("{path}: wrote {expected}, rosbags read {actual}")),
    }
}

fn transform(stamp: i64, parent: &str, child: &str, x: f64) -> TransformStamped {
    TransformStamped {
        header: Header::new(Stamp(stamp), parent),
        child_frame_id: child.into(),
        transform: Transform { translation: [x, -0.25, 0.125].into(), rotation: [0.0, 0.0, 0.6, 0.8].into() },
    }
}

/// Two messages of every type, header stamps distinct and some before 1970.
fn sample() -> Vec<(i64, &'static str, OutMessage)> {
    let t0 = 1_700_000_000_123_456_789i64;
    let mut out = vec![(
        t0,
        "/tf_static",
        OutMessage::Tf { is_static: true, transforms: vec![transform(t0, "base_link", "laser", 0.2)] },
    )];
    for k in 0..2i64 {
        let t = t0 + 1 + k * 100_000_000;
        let h = |frame: &str, dt: i64| Header::new(Stamp(t - dt), frame);
        let cov: Vec<f64> = (0..36).map(|i| i as f64 / 8.0 + k as f64).collect();
        let cov36: [f64; 36] = cov.try_into().unwrap();
        out.extend([
            (
                t,
                "/scan",
                OutMessage::LaserScan(LaserScan {
                    header: h("laser", 7),
                    angle_min: -2.0,
                    angle_max: 2.0,
                    angle_increment: 0.1,
                    time_increment: 1e-4,
                    scan_time: 0.1,
                    range_min: 0.1,
                    range_max: 30.0,
                    ranges: vec![1.5, f32::INFINITY, f32::NAN, 0.1 + k as f32],
                    intensities: if k == 0 { vec![] } else { vec![100.0, 0.0, 1.0, 2.5] },
                }),
            ),
            (
                t + 1,
                "/odom",
                OutMessage::Odometry(Odometry {
                    header: h("odom", 11),
                    child_frame_id: "base_link".into(),
                    pose: PoseWithCovariance {
                        pose: Pose {
                            position: [1.0 + k as f64, 2.0, 0.0].into(),
                            orientation: [0.0, 0.0, 0.6, 0.8].into(),
                        },
                        covariance: cov36,
                    },
                    twist: TwistWithCovariance {
                        twist: Twist { linear: [0.3, 0.0, 0.0].into(), angular: [0.0, 0.0, -0.1].into() },
                        covariance: cov36,
                    },
                }),
            ),
            (
                t + 2,
                "/tf",
                OutMessage::Tf {
                    is_static: false,
                    transforms: vec![
                        transform(t - 11, "odom", "base_link", 1.0),
                        transform(t - 12, "map", "odom", -3.0),
                    ],
                },
            ),
            (
                t + 3,
                "/imu",
                OutMessage::Imu(Imu {
                    header: h("imu_link", 13),
                    orientation: Quaternion::default(),
                    orientation_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                    angular_velocity: Vector3 { x: 0.01, y: -0.02, z: 0.5 },
                    angular_velocity_covariance: [0.001; 9],
                    linear_acceleration: Vector3 { x: 0.1, y: 0.2, z: 9.80665 },
                    linear_acceleration_covariance: [0.01; 9],
                }),
            ),
            (
                t + 4,
                "/gps/fix",
                OutMessage::NavSatFix(NavSatFix {
                    header: h("gps", 17),
                    status: NavSatStatus {
                        status: if k == 0 { NavSatStatus::STATUS_NO_FIX } else { NavSatStatus::STATUS_GBAS_FIX },
                        service: NavSatStatus::SERVICE_GPS | NavSatStatus::SERVICE_GALILEO,
                    },
                    latitude: 48.137154,
                    longitude: 11.576124,
                    altitude: if k == 0 { f64::NAN } else { 519.5 },
                    position_covariance: [4.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0, 16.0],
                    position_covariance_type: NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN,
                }),
            ),
            (
                t + 5,
                "/amcl_pose",
                OutMessage::PoseWithCovarianceStamped(PoseWithCovarianceStamped {
                    header: h("map", 19),
                    pose: PoseWithCovariance {
                        pose: Pose { position: [-4.5, 3.25, 0.0].into(), orientation: [0.0, 0.0, -0.6, 0.8].into() },
                        covariance: cov36,
                    },
                }),
            ),
            (
                t + 6,
                "/camera/image_raw",
                OutMessage::Image(Image {
                    header: h("camera_optical", 23),
                    height: 2,
                    width: 3,
                    encoding: "rgb8".into(),
                    is_bigendian: 0,
                    step: 9,
                    data: (0..18).map(|i| (i * 13 + k) as u8).collect::<Vec<u8>>().into(),
                }),
            ),
            (
                t + 7,
                "/camera/camera_info",
                OutMessage::CameraInfo(CameraInfo {
                    header: h("camera_optical", 23),
                    height: 480,
                    width: 640,
                    distortion_model: "plumb_bob".into(),
                    d: if k == 0 { vec![-0.28, 0.07, 0.001, -0.0002, 0.0] } else { vec![] },
                    k: [525.0, 0.0, 319.5, 0.0, 525.0, 239.5, 0.0, 0.0, 1.0],
                    r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                    p: [525.0, 0.0, 319.5, 0.0, 0.0, 525.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0],
                    binning_x: 1,
                    binning_y: 2,
                    roi: RegionOfInterest { x_offset: 10, y_offset: 20, height: 100, width: 200, do_rectify: k == 1 },
                }),
            ),
        ]);
    }
    // A stamp before 1970 (negative seconds, positive nanoseconds).
    out.push((
        t0 + 500_000_000,
        "/imu",
        OutMessage::Imu(Imu { header: Header::new(Stamp(-1_500_000_000), "imu_link"), ..Imu::default() }),
    ));
    out
}

fn run_rosbags(python: &str, bag: &Path) -> Value {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/rosbags_dump.py");
    let run = Command::new(python).arg(&script).arg(bag).output().expect("running rosbags_dump.py");
    assert!(
        run.status.success(),
        "rosbags could not read {}:\n{}",
        bag.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).expect("the script's JSON")
}

#[test]
fn rosbags_reads_what_fusemap_writes() {
    let Some(python) = python_with_rosbags() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let msgs = sample();
    for compression in [ChunkCompression::Zstd, ChunkCompression::None] {
        let bag = tmp.path().join(format!("bag_{compression:?}"));
        let options = Rosbag2WriterOptions { compression, chunk_size: 1024, ..Rosbag2WriterOptions::default() };
        let mut w = Rosbag2Writer::create_with(&bag, options).unwrap();
        for (t, topic, m) in &msgs {
            w.write(Stamp(*t), topic, m).unwrap();
        }
        w.finish().unwrap();
        let got = run_rosbags(&python, &bag);

        assert_eq!(got["message_count"], json!(msgs.len()));
        assert_eq!(got["start_time"], json!(msgs[0].0));
        assert_eq!(got["end_time"], json!(msgs.iter().map(|m| m.0).max().unwrap() + 1), "rosbags' end is exclusive");
        let topics = got["topics"].as_object().unwrap();
        assert_eq!(topics.len(), 9);
        for (name, t) in topics {
            let of_topic: Vec<_> = msgs.iter().filter(|m| m.1 == name).collect();
            assert_eq!(t["type"], json!(of_topic[0].2.type_name()), "{name}");
            assert_eq!(t["count"], json!(of_topic.len()), "{name}");
            assert_eq!(t["definition_format"], json!("MSG"), "{name}");
            assert_eq!(
                t["definition_matches_humble"],
                json!(true),
                "{name}: the .msg text differs from rosbags' Humble one"
            );
            let (depth, durability) = if name == "/tf_static" { (1, "transient_local") } else { (10, "volatile") };
            assert_eq!(
                t["qos"],
                json!([{ "history": "keep_last", "depth": depth, "reliability": "reliable", "durability": durability }]),
                "{name}"
            );
        }
        let read = got["messages"].as_array().unwrap();
        assert_eq!(read.len(), msgs.len());
        for (i, ((t, topic, m), r)) in msgs.iter().zip(read).enumerate() {
            assert_eq!((r["topic"].as_str(), r["log_time"].as_i64()), (Some(*topic), Some(*t)), "message {i}");
            if let Err(e) = same(&expected(m), &r["msg"], topic) {
                panic!("message {i} ({compression:?}): {e}");
            }
            assert_eq!(r["own_definitions_agree"], json!(true), "message {i} on {topic}: the bag's own definitions");
            assert_eq!(r["reserialised_identical"], json!(true), "message {i} on {topic}: rosbags' bytes differ");
        }
        assert_eq!(
            got["mcap"],
            json!({ "profile": "ros2", "metadata_records": ["rosbag2"], "decoded_from_schemas": msgs.len() })
        );
    }
}
