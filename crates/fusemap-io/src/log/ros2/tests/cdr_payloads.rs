//! CDR payloads of the lidar, odometry, TF and IMU messages laid out byte by byte, and
//! the decoder on every truncation, corruption and foreign encapsulation of them.

use super::*;

#[test]
fn laser_scan_bytes_laid_out_by_hand() {
    // Header: sec 1, nanosec 2, frame_id "laser" (6 bytes with the NUL) ends at body
    // offset 18; angle_min is aligned to 20, so 2 bytes of padding.
    let mut p = vec![0x00, 0x01, 0x00, 0x00];
    p.extend_from_slice(&1i32.to_le_bytes());
    p.extend_from_slice(&2u32.to_le_bytes());
    p.extend_from_slice(&6u32.to_le_bytes());
    p.extend_from_slice(b"laser\0");
    p.extend_from_slice(&[0xAA, 0xAA]);
    for v in [-1.0f32, 1.0, 0.5, 0.0, 0.0, 0.0, 81.0] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&3u32.to_le_bytes());
    for v in [1.25f32, f32::NAN, f32::INFINITY] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&0u32.to_le_bytes());
    assert_eq!(p.len(), 4 + 68);

    let m: sensor_msgs::LaserScan = decode_cdr(&p).unwrap();
    assert_eq!(m.header.stamp, Stamp(1_000_000_002));
    assert_eq!(m.header.frame_id, "laser");
    assert_eq!((m.angle_min, m.angle_max, m.angle_increment), (-1.0, 1.0, 0.5));
    assert_eq!(m.range_max, 81.0);
    assert_eq!(m.ranges[0], 1.25);
    assert!(m.ranges[1].is_nan());
    assert_eq!(m.ranges[2], f32::INFINITY);
    assert!(m.intensities.is_empty());

    let Some(LogMessage::Scan(s)) = decode_message("sensor_msgs/msg/LaserScan", "/scan", Some(Stamp(9)), &p).unwrap()
    else {
        panic!("not a scan")
    };
    assert_eq!(s.topic, "/scan");
    assert_eq!(s.frame_id, "laser");
    assert_eq!(s.receive_stamp, Some(Stamp(9)));
    assert_eq!(s.scan.stamp, Stamp(1_000_000_002));
    assert_eq!((s.scan.angle_min, s.scan.angle_increment), (-1.0, 0.5));
    assert_eq!(s.range_max, 81.0);
    assert_eq!(s.scan.ranges.len(), 3);
    assert_eq!((s.pose, s.odom_pose, s.laser_pose), (None, None, None));
}

#[test]
fn empty_ranges_array() {
    let p = scan_payload(5, 0, "", &[]);
    let m: sensor_msgs::LaserScan = decode_cdr(&p).unwrap();
    assert!(m.ranges.is_empty());
    assert_eq!(m.header.frame_id, "");
    assert_eq!(m.range_max, 30.0);
}

#[test]
fn odometry_with_odd_string_before_doubles() {
    // Body: header ends at 17 ("odom" + NUL), child length aligned to 20, "base_link" + NUL
    // ends at 34, position.x aligned to 40: 3 then 6 padding bytes.
    let p = odom_payload(10, "odom", "base_link", 1.5, -2.0, 0.75);
    assert_eq!(&p[4 + 17..4 + 20], &[0xAA; 3]);
    assert_eq!(&p[4 + 34..4 + 40], &[0xAA; 6]);
    assert_eq!(&p[4 + 40..4 + 48], &1.5f64.to_le_bytes());

    let m: nav_msgs::Odometry = decode_cdr(&p).unwrap();
    assert_eq!(m.child_frame_id, "base_link");
    assert_eq!(m.pose.pose.position.x, 1.5);
    assert_eq!(m.pose.covariance, [0.5; 36]);
    assert_eq!(m.twist.twist.angular.z, 0.2);
    assert_eq!(m.twist.covariance, [0.25; 36]);

    let Some(LogMessage::Odometry(o)) = decode_message("nav_msgs/msg/Odometry", "/odom", None, &p).unwrap() else {
        panic!("not odometry")
    };
    assert_eq!((o.frame_id.as_str(), o.child_frame_id.as_str()), ("odom", "base_link"));
    assert_eq!(o.stamp, Stamp(10_000_000_007));
    assert_eq!((o.pose.x, o.pose.y), (1.5, -2.0));
    assert!((o.pose.theta - 0.75).abs() < 1e-12);
}

#[test]
fn tf_messages_align_each_transform() {
    // "a" (2 bytes) then "bb" (3 bytes): the second element's translation needs padding
    // different from the first's.
    let p = tf_payload(&[("a", "bb", [1.0, 2.0, 3.0]), ("odom", "base_link", [4.0, 5.0, 6.0])]);
    let m: tf2_msgs::TfMessage = decode_cdr(&p).unwrap();
    assert_eq!(m.transforms.len(), 2);
    assert_eq!(m.transforms[1].transform.translation.z, 6.0);
    for (topic, is_static) in [("/tf", false), ("/tf_static", true), ("/robot/tf_static", false)] {
        let Some(LogMessage::Tf(t)) = decode_message("tf2_msgs/msg/TFMessage", topic, None, &p).unwrap() else {
            panic!("not tf")
        };
        assert_eq!(t.is_static, is_static, "{topic}");
        assert_eq!(t.transforms[0].parent, "a");
        assert_eq!(t.transforms[0].child, "bb");
        assert_eq!(t.transforms[0].stamp, Stamp(100_000_000_005));
        assert_eq!(t.transforms[1].translation, [4.0, 5.0, 6.0]);
        assert_eq!(t.transforms[1].rotation, [0.0, 0.0, 0.0, 1.0]);
    }
    let empty: tf2_msgs::TfMessage = decode_cdr(&tf_payload(&[])).unwrap();
    assert!(empty.transforms.is_empty());
}

#[test]
fn imu() {
    let Some(LogMessage::Imu(m)) = decode_message("sensor_msgs/msg/Imu", "/imu", None, &imu_payload()).unwrap() else {
        panic!("not imu")
    };
    assert_eq!(m.frame_id, "imu_link");
    assert_eq!(m.stamp, Stamp(3_000_000_004));
    assert_eq!(m.angular_velocity, [0.1, 0.2, 0.3]);
    assert_eq!(m.linear_acceleration, [0.0, 0.0, 9.81]);
}

fn all_payloads() -> Vec<(KnownType, Vec<u8>)> {
    vec![
        (KnownType::LaserScan, scan_payload(1, 2, "laser", &[1.0, 2.0, 3.0])),
        (KnownType::LaserScan, scan_payload(1, 2, "lsr", &[])),
        (KnownType::Odometry, odom_payload(1, "odom", "base_link", 1.0, 2.0, 0.3)),
        (KnownType::TfMessage, tf_payload(&[("a", "bb", [1.0; 3]), ("ccc", "d", [2.0; 3])])),
        (KnownType::Imu, imu_payload()),
        (KnownType::NavSatFix, pose_sensors::nav_sat_fix_payload(&pose_sensors::Fix::sample())),
        (
            KnownType::PoseWithCovarianceStamped,
            pose_sensors::pose_payload("map", [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]),
        ),
        (KnownType::Image, camera::Img::labels().payload()),
        (KnownType::CameraInfo, camera::camera_info_payload(&[0.1, 0.2], camera::sample_k())),
    ]
}

#[test]
fn every_truncation_is_an_error_never_a_panic() {
    for (kind, p) in all_payloads() {
        assert!(decode_known(kind, "/t", None, &p).is_ok(), "{kind:?}");
        for cut in 0..p.len() {
            let e = decode_known(kind, "/t", None, &p[..cut]).unwrap_err();
            match (cut, &e) {
                (0..=3, CdrError::NoHeader { len }) => assert_eq!(*len, cut),
                (4.., CdrError::Truncated { offset, .. }) => assert!(*offset <= cut, "{kind:?} {cut}: {e}"),
                _ => panic!("{kind:?} cut at {cut}: {e}"),
            }
        }
    }
}

#[test]
fn corrupt_bytes_never_panic() {
    for (kind, p) in all_payloads() {
        for i in 4..p.len() {
            for v in [0x00, 0x7f, 0x80, 0xff] {
                let mut q = p.clone();
                q[i] = v;
                let _ = decode_known(kind, "/t", None, &q);
            }
        }
        // Every known decoder on every other type's payload.
        for other in KnownType::ALL {
            let _ = decode_known(other, "/t", None, &p);
        }
    }
}

#[test]
fn big_endian_and_other_encapsulations_are_refused() {
    let mut p = scan_payload(1, 2, "laser", &[1.0]);
    p[1] = 0x00;
    let e = decode_known(KnownType::LaserScan, "/scan", None, &p).unwrap_err();
    assert_eq!(e, CdrError::BigEndian);
    assert_eq!(e.to_string(), "CDR encapsulation is big-endian (0x0000); fusemap reads little-endian CDR (0x0001)");
    p[0] = 0xAB;
    p[1] = 0xCD;
    let e = decode_known(KnownType::LaserScan, "/scan", None, &p).unwrap_err();
    assert_eq!(e, CdrError::UnsupportedEncapsulation { bytes: [0xAB, 0xCD] });
    assert!(e.to_string().contains("0xabcd"), "{e}");
}
