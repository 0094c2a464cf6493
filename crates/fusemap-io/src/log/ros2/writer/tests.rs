//! The writer against fusemap's own reader: bytes laid out by hand, every decodable type
//! read back field for field, whole bags read back message for message, and the errors.
//! (`tests/ros2_writer_rosbags.rs` reads the bags with the third-party `rosbags`.)

use super::cdr_write::encode_cdr;
use super::*;
use crate::error::{Error, Location};
use crate::log::ros2::cdr::decode_cdr;
use crate::log::ros2::msgs as dec;
use crate::log::ros2::msgs::geometry_msgs::{
    Pose, PoseWithCovariance, PoseWithCovarianceStamped, Transform, TransformStamped, Twist, TwistWithCovariance,
};
use crate::log::ros2::msgs::nav_msgs::Odometry;
use crate::log::ros2::msgs::sensor_msgs::{CameraInfo, Image, Imu, LaserScan, NavSatFix, NavSatStatus};
use crate::log::ros2::msgs::std_msgs::Header;
use crate::log::ros2::Ros2Reader;
use crate::log::{ImuMessage, LogMessage, LogReader, OdomMessage, ScanMessage, TfMessage};
use fusemap_core::geometry::{quaternion_yaw, Pose2};
use fusemap_core::sensor::LaserScan as CoreScan;
use fusemap_core::time::Stamp;
use proptest::prelude::*;
use std::path::Path;

fn scan(stamp: i64, frame: &str, ranges: Vec<f32>) -> LaserScan {
    LaserScan {
        header: Header::new(Stamp(stamp), frame),
        angle_min: -1.5,
        angle_max: 1.5,
        angle_increment: 0.75,
        time_increment: 0.001,
        scan_time: 0.1,
        range_min: 0.05,
        range_max: 30.0,
        intensities: ranges.iter().map(|r| r * 2.0).collect(),
        ranges,
    }
}

fn odom(stamp: i64, x: f64, yaw: f64) -> Odometry {
    let mut cov = [0.0; 36];
    cov.iter_mut().enumerate().for_each(|(i, c)| *c = i as f64 * 0.5);
    Odometry {
        header: Header::new(Stamp(stamp), "odom"),
        child_frame_id: "base_link".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: [x, -2.0, 0.25].into(),
                orientation: [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()].into(),
            },
            covariance: cov,
        },
        twist: TwistWithCovariance {
            twist: Twist { linear: [0.5, 0.0, 0.0].into(), angular: [0.0, 0.0, 0.2].into() },
            covariance: [0.125; 36],
        },
    }
}

fn imu(stamp: i64) -> Imu {
    Imu {
        header: Header::new(Stamp(stamp), "imu_link"),
        orientation: [0.0, 0.6, 0.0, 0.8].into(),
        orientation_covariance: [0.01; 9],
        angular_velocity: [0.1, 0.2, 0.3].into(),
        angular_velocity_covariance: [0.02; 9],
        linear_acceleration: [0.0, 0.0, 9.81].into(),
        linear_acceleration_covariance: [0.03; 9],
    }
}

fn transform(stamp: i64, parent: &str, child: &str, t: [f64; 3]) -> TransformStamped {
    TransformStamped {
        header: Header::new(Stamp(stamp), parent),
        child_frame_id: child.into(),
        transform: Transform {
            translation: t.into(),
            rotation: [0.0, 0.0, 0.38268343236508984, 0.9238795325112867].into(),
        },
    }
}

#[test]
fn laser_scan_bytes_as_laid_out_by_hand() {
    // Header: sec 1, nanosec 2, "laser" (6 bytes with NUL) ends at body offset 18;
    // angle_min aligns to 20 with two zero bytes.
    let m = LaserScan {
        header: Header::new(Stamp(1_000_000_002), "laser"),
        angle_min: -1.0,
        angle_max: 1.0,
        angle_increment: 0.5,
        range_max: 81.0,
        ranges: vec![1.25, f32::NAN, f32::INFINITY],
        ..LaserScan::default()
    };
    let mut p = vec![0x00, 0x01, 0x00, 0x00];
    p.extend_from_slice(&1i32.to_le_bytes());
    p.extend_from_slice(&2u32.to_le_bytes());
    p.extend_from_slice(&6u32.to_le_bytes());
    p.extend_from_slice(b"laser\0\0\0");
    for v in [-1.0f32, 1.0, 0.5, 0.0, 0.0, 0.0, 81.0] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&3u32.to_le_bytes());
    for v in [1.25f32, f32::NAN, f32::INFINITY] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&0u32.to_le_bytes());
    assert_eq!(encode_cdr(&OutMessage::LaserScan(m)).unwrap(), p);
}

#[test]
fn nav_sat_fix_packs_status_and_aligns_the_doubles() {
    let m = NavSatFix {
        header: Header::new(Stamp(5), ""),
        status: NavSatStatus { status: NavSatStatus::STATUS_NO_FIX, service: NavSatStatus::SERVICE_GALILEO },
        latitude: 48.5,
        position_covariance_type: NavSatFix::COVARIANCE_TYPE_KNOWN,
        ..NavSatFix::default()
    };
    let p = encode_cdr(&OutMessage::NavSatFix(m)).unwrap();
    // stamp 0..8, frame_id count 8..12 + NUL at 12; status (int8) at 13, service (uint16)
    // at 14..16; latitude aligned to 16.
    let body = &p[4..];
    assert_eq!(&body[8..16], &[1, 0, 0, 0, 0, 0xff, 8, 0]);
    assert_eq!(&body[16..24], &48.5f64.to_le_bytes());
    // longitude, altitude, 9 covariances, then the covariance type byte last.
    assert_eq!(body.len(), 16 + 8 * 12 + 1);
    assert_eq!(body[body.len() - 1], 3);
}

#[test]
fn every_field_the_project_decodes_comes_back() {
    let s = scan(-1, "laser", vec![0.5, f32::NAN, 7.0]);
    let d: dec::sensor_msgs::LaserScan = decode_cdr(&encode_cdr(&OutMessage::LaserScan(s.clone())).unwrap()).unwrap();
    assert_eq!(d.header, s.header);
    assert_eq!(
        [d.angle_min, d.angle_max, d.angle_increment, d.time_increment, d.scan_time, d.range_min, d.range_max],
        [s.angle_min, s.angle_max, s.angle_increment, s.time_increment, s.scan_time, s.range_min, s.range_max]
    );
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&d.ranges), bits(&s.ranges));
    assert_eq!(bits(&d.intensities), bits(&s.intensities));

    let o = odom(3, 1.5, 0.7);
    let d: dec::nav_msgs::Odometry = decode_cdr(&encode_cdr(&OutMessage::Odometry(o.clone())).unwrap()).unwrap();
    assert_eq!(d, o);

    let i = imu(4);
    let d: dec::sensor_msgs::Imu = decode_cdr(&encode_cdr(&OutMessage::Imu(i.clone())).unwrap()).unwrap();
    assert_eq!(d, i);

    let ts = vec![transform(1, "odom", "base_link", [1.0, 2.0, 3.0]), transform(2, "base_link", "laser", [0.2; 3])];
    let m = OutMessage::Tf { is_static: false, transforms: ts.clone() };
    let d: dec::tf2_msgs::TfMessage = decode_cdr(&encode_cdr(&m).unwrap()).unwrap();
    assert_eq!(d.transforms, ts);
}

/// A log with every type, in log-time order, and what fusemap's reader must make of it.
fn sample() -> (Vec<(i64, &'static str, OutMessage)>, Vec<LogMessage>) {
    let base = 1_700_000_000_000_000_000i64;
    let msgs = vec![
        (
            base,
            "/tf_static",
            OutMessage::Tf {
                is_static: true,
                transforms: vec![transform(base, "base_link", "laser", [0.1, 0.0, 0.2])],
            },
        ),
        (base + 10, "/scan", OutMessage::LaserScan(scan(base + 5, "laser", vec![1.0, 2.0, f32::INFINITY]))),
        (base + 20, "/odom", OutMessage::Odometry(odom(base + 15, 0.5, 0.3))),
        (
            base + 30,
            "/tf",
            OutMessage::Tf {
                is_static: false,
                transforms: vec![transform(base + 15, "odom", "base_link", [0.5, 0.0, 0.0])],
            },
        ),
        (base + 40, "/imu", OutMessage::Imu(imu(base + 35))),
        (
            base + 50,
            "/fix",
            OutMessage::NavSatFix(NavSatFix { latitude: 48.1, longitude: 11.5, ..NavSatFix::default() }),
        ),
        (base + 60, "/initialpose", OutMessage::PoseWithCovarianceStamped(PoseWithCovarianceStamped::default())),
        (
            base + 70,
            "/camera/image_raw",
            OutMessage::Image(Image {
                height: 2,
                width: 3,
                encoding: "mono8".into(),
                step: 3,
                data: vec![1, 2, 3, 4, 5, 6].into(),
                ..Image::default()
            }),
        ),
        (
            base + 80,
            "/camera/camera_info",
            OutMessage::CameraInfo(CameraInfo {
                distortion_model: "plumb_bob".into(),
                d: vec![0.1, -0.2, 0.0, 0.0, 0.01],
                ..CameraInfo::default()
            }),
        ),
        (base + 90, "/scan", OutMessage::LaserScan(scan(base + 85, "laser", vec![]))),
    ];
    let expected = msgs.iter().filter_map(|(t, topic, m)| expect(Stamp(*t), topic, m)).collect();
    (msgs, expected)
}

/// What `Ros2Reader` gives for one written message.
fn expect(log_time: Stamp, topic: &str, m: &OutMessage) -> Option<LogMessage> {
    let receive_stamp = Some(log_time);
    Some(match m {
        OutMessage::LaserScan(s) => LogMessage::Scan(ScanMessage {
            topic: topic.into(),
            frame_id: s.header.frame_id.clone(),
            receive_stamp,
            scan: CoreScan {
                stamp: s.header.stamp,
                angle_min: f64::from(s.angle_min),
                angle_increment: f64::from(s.angle_increment),
                ranges: s.ranges.clone(),
            },
            angle_max: s.angle_max,
            time_increment: s.time_increment,
            scan_time: s.scan_time,
            range_min: s.range_min,
            range_max: s.range_max,
            pose: None,
            odom_pose: None,
            laser_pose: None,
        }),
        OutMessage::Odometry(o) => LogMessage::Odometry(OdomMessage {
            topic: topic.into(),
            stamp: o.header.stamp,
            receive_stamp,
            frame_id: o.header.frame_id.clone(),
            child_frame_id: o.child_frame_id.clone(),
            pose: Pose2::new(
                o.pose.pose.position.x,
                o.pose.pose.position.y,
                quaternion_yaw(o.pose.pose.orientation.to_array()),
            ),
            pose_covariance: o.pose.covariance,
            twist: {
                let (l, a) = (o.twist.twist.linear, o.twist.twist.angular);
                [l.x, l.y, l.z, a.x, a.y, a.z]
            },
            twist_covariance: o.twist.covariance,
        }),
        OutMessage::Imu(i) => LogMessage::Imu(ImuMessage {
            topic: topic.into(),
            stamp: i.header.stamp,
            receive_stamp,
            frame_id: i.header.frame_id.clone(),
            orientation: i.orientation.to_array(),
            orientation_covariance: i.orientation_covariance,
            angular_velocity: i.angular_velocity.to_array(),
            angular_velocity_covariance: i.angular_velocity_covariance,
            linear_acceleration: i.linear_acceleration.to_array(),
            linear_acceleration_covariance: i.linear_acceleration_covariance,
        }),
        OutMessage::NavSatFix(f) => LogMessage::Gnss(crate::log::GnssMessage {
            topic: topic.into(),
            stamp: f.header.stamp,
            receive_stamp,
            frame_id: f.header.frame_id.clone(),
            status: f.status.status,
            service: f.status.service,
            latitude: f.latitude,
            longitude: f.longitude,
            altitude: f.altitude,
            position_covariance: f.position_covariance,
            position_covariance_type: f.position_covariance_type,
        }),
        OutMessage::PoseWithCovarianceStamped(p) => LogMessage::Pose(crate::log::PoseMessage {
            topic: topic.into(),
            stamp: p.header.stamp,
            receive_stamp,
            frame_id: p.header.frame_id.clone(),
            position: p.pose.pose.position.to_array(),
            orientation: p.pose.pose.orientation.to_array(),
            covariance: p.pose.covariance,
        }),
        OutMessage::Tf { transforms, .. } => LogMessage::Tf(TfMessage {
            topic: topic.into(),
            is_static: topic == "/tf_static",
            receive_stamp,
            transforms: transforms
                .iter()
                .map(|t| crate::log::Transform {
                    stamp: t.header.stamp,
                    parent: t.header.frame_id.clone(),
                    child: t.child_frame_id.clone(),
                    translation: t.transform.translation.to_array(),
                    rotation: t.transform.rotation.to_array(),
                })
                .collect(),
        }),
        // Read with the default options: an image without its pixels.
        OutMessage::Image(i) => LogMessage::ImageHeader(crate::log::ImageHeader {
            topic: topic.into(),
            stamp: i.header.stamp,
            receive_stamp,
            frame_id: i.header.frame_id.clone(),
            width: i.width,
            height: i.height,
            encoding: i.encoding.clone(),
            is_bigendian: i.is_bigendian != 0,
            step: i.step,
            data_len: i.data.len() as u64,
        }),
        OutMessage::CameraInfo(c) => LogMessage::CameraInfo(crate::log::CameraInfoMessage {
            topic: topic.into(),
            stamp: c.header.stamp,
            receive_stamp,
            frame_id: c.header.frame_id.clone(),
            width: c.width,
            height: c.height,
            distortion_model: c.distortion_model.clone(),
            d: c.d.clone(),
            k: c.k,
        }),
    })
}

fn read_all(path: &Path) -> (Vec<LogMessage>, crate::log::ReadStats) {
    let mut r = Ros2Reader::open(path).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    while let Some(m) = r.next_message() {
        out.push(m.unwrap_or_else(|e| panic!("{e}")));
    }
    (out, r.stats().clone())
}

#[test]
fn bags_read_back_through_fusemaps_reader() {
    let d = crate::testdata::temp_dir("writer-roundtrip");
    for compression in [ChunkCompression::Zstd, ChunkCompression::None] {
        let dir = d.join(format!("bag_{compression:?}"));
        let (msgs, expected) = sample();
        let options = Rosbag2WriterOptions { compression, chunk_size: 256, ..Rosbag2WriterOptions::default() };
        let mut w = Rosbag2Writer::create_with(&dir, options).unwrap();
        for (t, topic, m) in &msgs {
            w.write(Stamp(*t), topic, m).unwrap();
        }
        assert!(!dir.exists(), "the bag appears only at finish");
        let written = w.finish().unwrap();
        assert_eq!(written.message_count, msgs.len() as u64);
        assert_eq!(written.storage_file, dir.join(format!("bag_{compression:?}_0.mcap")));
        assert_eq!((written.starting_time, written.duration_ns), (Stamp(msgs[0].0), 90));
        let scans = written.topics.iter().find(|t| t.name == "/scan").unwrap();
        assert_eq!((scans.type_name.as_str(), scans.message_count), ("sensor_msgs/msg/LaserScan", 2));
        let statics = written.topics.iter().find(|t| t.name == "/tf_static").unwrap();
        assert_eq!(statics.qos, QosProfile::LATCHED);

        let (got, stats) = read_all(&dir);
        assert_eq!(got.len(), expected.len());
        for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
            assert_eq!(format!("{g:?}"), format!("{e:?}"), "message {i} ({compression:?})");
        }
        assert!(stats.skipped_by_type.is_empty(), "{stats:?}");
        // The bare MCAP file reads the same.
        assert_eq!(read_all(&written.storage_file).0.len(), expected.len());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_messages_are_refused_and_the_bag_stays_good() {
    let d = crate::testdata::temp_dir("writer-refuse");
    let dir = d.join("bag");
    let mut w = Rosbag2Writer::create(&dir).unwrap();
    let ok = OutMessage::Imu(imu(1));
    w.write(Stamp(10), "/imu", &ok).unwrap();
    let cases: Vec<(Stamp, &str, OutMessage, &str)> = vec![
        (Stamp(11), "imu", ok.clone(), "fully qualified"),
        (Stamp(11), "/a//b", ok.clone(), "not a valid ROS 2 name"),
        (Stamp(11), "/9lives", ok.clone(), "not a valid ROS 2 name"),
        (Stamp(-1), "/imu", ok.clone(), "before 1970"),
        (Stamp(11), "/imu", OutMessage::Odometry(odom(1, 0.0, 0.0)), "carries sensor_msgs/msg/Imu"),
        (Stamp(11), "/imu2", OutMessage::Imu(imu(i64::MAX)), "int32 seconds"),
        (Stamp(11), "/scan", OutMessage::LaserScan(scan(1, "la\0ser", vec![])), "NUL"),
    ];
    for (i, (t, topic, m, why)) in cases.iter().enumerate() {
        let e = w.write(*t, topic, m).unwrap_err();
        let Error::Format { path, location, message } = &e else { panic!("{e}") };
        assert_eq!(path, &dir);
        assert_eq!(location, &Location::Message { index: i as u64 + 2, topic: topic.to_string() });
        assert!(message.contains(why), "{e}");
    }
    let tf = |is_static| OutMessage::Tf { is_static, transforms: vec![transform(1, "a", "b", [0.0; 3])] };
    w.write(Stamp(12), "/tf", &tf(false)).unwrap();
    assert!(w.write(Stamp(13), "/tf", &tf(true)).unwrap_err().to_string().contains("static"));
    assert!(w.set_topic_qos("/imu", QosProfile::LATCHED).is_err());
    w.set_topic_qos("/late", QosProfile::LATCHED).unwrap();
    w.write(Stamp(14), "/late", &ok).unwrap();
    // `/tf_static` is latched even when the transforms are not flagged static.
    w.write(Stamp(15), "/tf_static", &tf(false)).unwrap();
    let written = w.finish().unwrap();
    assert_eq!(written.message_count, 4);
    let names: Vec<&str> = written.topics.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["/imu", "/tf", "/late", "/tf_static"]);
    let qos: Vec<QosProfile> = written.topics.iter().map(|t| t.qos).collect();
    assert_eq!(qos, [QosProfile::DEFAULT, QosProfile::DEFAULT, QosProfile::LATCHED, QosProfile::LATCHED]);
    assert_eq!(read_all(&dir).0.len(), 4);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn existing_bags_are_not_overwritten_and_abandoned_ones_leave_nothing() {
    let d = crate::testdata::temp_dir("writer-dir");
    let nested = d.join("new/parents/bag");
    Rosbag2Writer::create(&nested).unwrap().finish().unwrap();
    assert!(nested.join("metadata.yaml").is_file() && nested.join("bag_0.mcap").is_file());
    std::fs::remove_dir_all(d.join("new")).unwrap();
    let dir = d.join("bag");
    let mut w = Rosbag2Writer::create(&dir).unwrap();
    w.write(Stamp(1), "/imu", &OutMessage::Imu(imu(1))).unwrap();
    drop(w);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "an abandoned bag leaves nothing");

    Rosbag2Writer::create(&dir).unwrap().finish().unwrap();
    let e = Rosbag2Writer::create(&dir).err().expect("a second bag over the first is refused");
    assert!(matches!(&e, Error::Io { path, .. } if path == &dir), "{e}");
    assert!(e.to_string().contains("not empty"), "{e}");
    // An empty bag reads as empty.
    assert!(read_all(&dir).0.is_empty());

    let options = Rosbag2WriterOptions { overwrite: true, ..Rosbag2WriterOptions::default() };
    let mut w = Rosbag2Writer::create_with(&dir, options).unwrap();
    w.write(Stamp(1), "/imu", &OutMessage::Imu(imu(1))).unwrap();
    w.finish().unwrap();
    assert_eq!(read_all(&dir).0.len(), 1);
    let mut names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["bag_0.mcap", "metadata.yaml"]);
    std::fs::remove_dir_all(&d).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any scan (stamps over the whole `builtin_interfaces/Time` range, any float bits,
    /// any frame name) decodes to the same fields with the project's decoder.
    #[test]
    fn scans_round_trip_through_the_decoder(
        stamp in (i64::from(i32::MIN) * 1_000_000_000)..(i64::from(i32::MAX) * 1_000_000_000),
        frame in "[a-z_/]{0,20}",
        bits in proptest::collection::vec(any::<u32>(), 0..64),
        angle in any::<u32>(),
    ) {
        let ranges: Vec<f32> = bits.iter().map(|b| f32::from_bits(*b)).collect();
        let mut s = scan(stamp, &frame, ranges);
        s.angle_min = f32::from_bits(angle);
        let d: dec::sensor_msgs::LaserScan = decode_cdr(&encode_cdr(&OutMessage::LaserScan(s.clone())).unwrap()).unwrap();
        prop_assert_eq!(d.header.stamp, s.header.stamp);
        prop_assert_eq!(d.header.frame_id, s.header.frame_id);
        prop_assert_eq!(d.angle_min.to_bits(), angle);
        prop_assert_eq!(d.ranges.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), bits);
        prop_assert_eq!(d.intensities.len(), s.intensities.len());
    }

    /// Transform batches of any size and frame names decode to the same transforms.
    #[test]
    fn tf_batches_round_trip(frames in proptest::collection::vec(("[a-z]{0,8}", "[a-z]{1,8}", any::<i32>()), 0..8)) {
        let ts: Vec<TransformStamped> = frames
            .iter()
            .map(|(p, c, x)| transform(i64::from(*x) * 1000, p, c, [f64::from(*x), 0.5, -0.5]))
            .collect();
        let d: dec::tf2_msgs::TfMessage =
            decode_cdr(&encode_cdr(&OutMessage::Tf { is_static: false, transforms: ts.clone() }).unwrap()).unwrap();
        prop_assert_eq!(d.transforms, ts);
    }
}
