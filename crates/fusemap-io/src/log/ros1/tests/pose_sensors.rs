//! ROS 1 payloads of the pose sensors laid out byte by byte: `sensor_msgs/NavSatFix`,
//! `geometry_msgs/PoseWithCovarianceStamped`, and the covariances and twist of
//! `sensor_msgs/Imu` and `nav_msgs/Odometry`, read through whole bags.

use super::*;
use crate::log::ros2::msgs::sensor_msgs::{NavSatFix, NavSatStatus};
use crate::log::{GnssMessage, PoseMessage};
use proptest::prelude::*;

const NAVSAT_MD5: &str = "2d3a8cd499b9b4a0249fb98fd05cfa48";
const POSE_MD5: &str = "953b798c0f514ff060a53a3498ce6246";
const NAVSAT: Conn = Conn { id: 6, topic: "/fix", ty: "sensor_msgs/NavSatFix", md5: NAVSAT_MD5 };
const POSE: Conn = Conn { id: 7, topic: "/amcl_pose", ty: "geometry_msgs/PoseWithCovarianceStamped", md5: POSE_MD5 };

/// `base, base + 1, …`: every element different, so a field read from the wrong offset
/// shows as a wrong value.
fn ramp<const N: usize>(base: f64) -> [f64; N] {
    std::array::from_fn(|i| base + i as f64)
}

/// One `sensor_msgs/NavSatFix` as a test writes it.
#[derive(Clone, Copy, Debug)]
struct Fix {
    stamp: (u32, u32),
    status: i8,
    service: u16,
    lla: [f64; 3],
    covariance: [f64; 9],
    covariance_type: u8,
}

impl Fix {
    fn sample() -> Self {
        Fix {
            stamp: (50, 250),
            status: NavSatStatus::STATUS_SBAS_FIX,
            service: NavSatStatus::SERVICE_GPS | NavSatStatus::SERVICE_GALILEO,
            lla: [48.858_37, 2.294_481, 35.25],
            covariance: ramp(0.5),
            covariance_type: NavSatFix::COVARIANCE_TYPE_KNOWN,
        }
    }

    /// ROS 1 serialisation: header, `int8 status`, `uint16 service` (no padding),
    /// three doubles, nine doubles, `uint8`.
    fn payload(&self) -> Vec<u8> {
        let mut p = Vec::new();
        ros_header(&mut p, 11, self.stamp, "gps");
        p.extend(self.status.to_le_bytes());
        p.extend(self.service.to_le_bytes());
        f64s(&mut p, &self.lla);
        f64s(&mut p, &self.covariance);
        p.push(self.covariance_type);
        p
    }

    fn message(&self, receive: Stamp) -> GnssMessage {
        GnssMessage {
            topic: "/fix".into(),
            stamp: Stamp::from_sec_nsec(i64::from(self.stamp.0), self.stamp.1),
            receive_stamp: Some(receive),
            frame_id: "gps".into(),
            status: self.status,
            service: self.service,
            latitude: self.lla[0],
            longitude: self.lla[1],
            altitude: self.lla[2],
            position_covariance: self.covariance,
            position_covariance_type: self.covariance_type,
        }
    }
}

fn pose_payload(stamp: (u32, u32), position: [f64; 3], orientation: [f64; 4], covariance: &[f64; 36]) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 2, stamp, "map");
    f64s(&mut p, &position);
    f64s(&mut p, &orientation);
    f64s(&mut p, covariance);
    p
}

/// `nav_msgs/Odometry` with every covariance and twist element distinct.
fn odom_with_twist(orientation: [f64; 4]) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 4, (7, 8), "odom");
    ros_string(&mut p, "base_link");
    f64s(&mut p, &[1.25, -3.5, 0.125]);
    f64s(&mut p, &orientation);
    f64s(&mut p, &ramp::<36>(100.0));
    f64s(&mut p, &[0.5, 0.01, 0.0, 0.0, 0.0, -0.25]);
    f64s(&mut p, &ramp::<36>(200.0));
    p
}

/// The messages of a bag holding `records` in one chunk, all of which must decode.
fn decode_all(records: Vec<Inner>) -> Vec<LogMessage> {
    let (messages, error, stats) = read_bytes(&bag(vec![(Compression::Lz4, records)]));
    assert!(error.is_none(), "{error:?}");
    assert!(stats.skipped_by_type.is_empty(), "{stats:?}");
    messages
}

#[test]
fn nav_sat_fix_fields_are_read_at_their_offsets() {
    let fix = Fix::sample();
    let p = fix.payload();
    // seq, stamp, "gps" with its length, status, service, 12 doubles, the type byte.
    assert_eq!(p.len(), 4 + 8 + 4 + 3 + 1 + 2 + 12 * 8 + 1);
    let messages = decode_all(vec![Inner::Conn(NAVSAT), msg(NAVSAT, (51, 0), p)]);
    assert_eq!(messages, [LogMessage::Gnss(fix.message(Stamp(51_000_000_000)))]);
    let LogMessage::Gnss(m) = &messages[0] else { unreachable!() };
    assert!(m.has_fix());
}

#[test]
fn a_fix_with_nan_fields_and_no_fix_status_decodes_as_written() {
    let fix = Fix {
        status: NavSatStatus::STATUS_NO_FIX,
        service: 0,
        lla: [f64::NAN, 2.0, f64::NAN],
        covariance: [f64::NAN; 9],
        covariance_type: NavSatFix::COVARIANCE_TYPE_UNKNOWN,
        ..Fix::sample()
    };
    let messages = decode_all(vec![Inner::Conn(NAVSAT), msg(NAVSAT, (1, 0), fix.payload())]);
    let [LogMessage::Gnss(m)] = messages.as_slice() else { panic!("{messages:?}") };
    assert!(m.latitude.is_nan() && m.altitude.is_nan() && m.position_covariance.iter().all(|c| c.is_nan()));
    assert_eq!(m.longitude, 2.0);
    assert_eq!(m.status, -1);
    assert!(!m.has_fix());
}

#[test]
fn a_truncated_fix_is_a_skippable_message_error_and_the_next_message_is_read() {
    let whole = Fix::sample().payload();
    for cut in 0..whole.len() {
        let bytes = bag(vec![
            (
                Compression::None,
                vec![Inner::Conn(NAVSAT), Inner::Conn(ODOM), msg(NAVSAT, (1, 0), whole[..cut].to_vec())],
            ),
            (Compression::Bz2, vec![msg(ODOM, (2, 0), odom_payload((2, 0), 4.0, 5.0))]),
        ]);
        let mut reader = BagReader::from_reader(&bytes[..], "test.bag").unwrap();
        let e = reader.next_message().unwrap().unwrap_err();
        assert!(e.is_skippable(), "cut {cut}: {e}");
        let (location, message) = format_error(Some(e));
        assert_eq!(location, Location::Message { index: 1, topic: "/fix".into() });
        assert!(message.starts_with("NavSatFix: "), "{message}");
        match reader.next_message() {
            Some(Ok(LogMessage::Odometry(o))) => assert_eq!((o.pose.x, o.pose.y), (4.0, 5.0)),
            other => panic!("cut {cut}: {other:?}"),
        }
        assert!(reader.next_message().is_none());
    }
}

#[test]
fn pose_with_covariance_stamped_decodes_and_a_zero_quaternion_has_no_heading() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let covariance = ramp::<36>(-10.0);
    let messages = decode_all(vec![
        Inner::Conn(POSE),
        msg(POSE, (9, 0), pose_payload((8, 5), [3.0, 4.0, 0.5], [0.0, 0.0, h, h], &covariance)),
        msg(POSE, (10, 0), pose_payload((9, 5), [3.0, 4.0, 0.5], [0.0; 4], &covariance)),
    ]);
    let expected = PoseMessage {
        topic: "/amcl_pose".into(),
        stamp: Stamp(8_000_000_005),
        receive_stamp: Some(Stamp(9_000_000_000)),
        frame_id: "map".into(),
        position: [3.0, 4.0, 0.5],
        orientation: [0.0, 0.0, h, h],
        covariance,
    };
    assert_eq!(messages[0], LogMessage::Pose(expected));
    let (LogMessage::Pose(turned), LogMessage::Pose(degenerate)) = (&messages[0], &messages[1]) else {
        panic!("{messages:?}")
    };
    assert!((turned.pose2().theta - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert_eq!(degenerate.orientation, [0.0; 4]);
    assert!(!degenerate.pose2().is_finite());
    assert_eq!((degenerate.pose2().x, degenerate.pose2().y), (3.0, 4.0));
}

#[test]
fn odometry_keeps_its_twist_and_covariances() {
    let messages = decode_all(vec![Inner::Conn(ODOM), msg(ODOM, (7, 9), odom_with_twist([0.0, 0.0, 0.0, 1.0]))]);
    let [LogMessage::Odometry(o)] = messages.as_slice() else { panic!("{messages:?}") };
    assert_eq!(o.pose, Pose2::new(1.25, -3.5, 0.0));
    assert_eq!(o.pose_covariance, ramp::<36>(100.0));
    assert_eq!(o.twist, [0.5, 0.01, 0.0, 0.0, 0.0, -0.25]);
    assert_eq!(o.twist_covariance, ramp::<36>(200.0));
}

#[test]
fn odometry_with_a_zero_or_non_finite_quaternion_has_a_non_finite_pose() {
    for q in [[0.0; 4], [0.0, 0.0, f64::NAN, 1.0], [0.0, 0.0, 0.0, f64::INFINITY]] {
        let messages = decode_all(vec![Inner::Conn(ODOM), msg(ODOM, (7, 9), odom_with_twist(q))]);
        let [LogMessage::Odometry(o)] = messages.as_slice() else { panic!("{messages:?}") };
        assert!(!o.pose.is_finite(), "{q:?} gave {:?}", o.pose);
        assert!(o.pose.theta.is_nan(), "{q:?}");
    }
}

#[test]
fn imu_keeps_its_three_covariances() {
    let mut p = Vec::new();
    ros_header(&mut p, 3, (5, 6), "imu_link");
    f64s(&mut p, &[0.0, 0.0, 0.0, 1.0]);
    f64s(&mut p, &ramp::<9>(1.0));
    f64s(&mut p, &[0.1, 0.2, 0.3]);
    f64s(&mut p, &ramp::<9>(20.0));
    f64s(&mut p, &[0.0, 0.0, 9.81]);
    f64s(&mut p, &ramp::<9>(300.0));
    let messages = decode_all(vec![Inner::Conn(IMU), msg(IMU, (5, 7), p), msg(IMU, (5, 8), imu_payload((5, 8)))]);
    let [LogMessage::Imu(with), LogMessage::Imu(without)] = messages.as_slice() else { panic!("{messages:?}") };
    assert_eq!(with.orientation_covariance, ramp::<9>(1.0));
    assert_eq!(with.angular_velocity_covariance, ramp::<9>(20.0));
    assert_eq!(with.linear_acceleration_covariance, ramp::<9>(300.0));
    assert!(with.has_orientation());
    // imu_payload writes -1 covariances: REP 145's "no orientation".
    assert!(!without.has_orientation());
}

#[test]
fn pose_sensor_types_with_another_md5sum_are_refused() {
    for c in [NAVSAT, POSE] {
        let odd = Conn { md5: "0123456789abcdef0123456789abcdef", ..c };
        let (_, error, _) = read_bytes(&bag(vec![(Compression::None, vec![Inner::Conn(odd)])]));
        let error = error.unwrap();
        assert!(!error.is_skippable());
        let (location, message) = format_error(Some(error));
        assert!(matches!(location, Location::Offset(_)));
        assert!(message.contains(c.md5), "{message}");
    }
}

proptest! {
    /// Any field values, NaN payloads and extreme integers included, come back bit for bit.
    #[test]
    fn any_nav_sat_fix_decodes_bit_for_bit(
        stamp in (any::<u32>(), 0u32..1_000_000_000),
        status in any::<i8>(),
        service in any::<u16>(),
        lla in prop::array::uniform3(any::<u64>()),
        covariance in prop::array::uniform9(any::<u64>()),
        covariance_type in any::<u8>(),
    ) {
        let fix = Fix {
            stamp,
            status,
            service,
            lla: lla.map(f64::from_bits),
            covariance: covariance.map(f64::from_bits),
            covariance_type,
        };
        let messages = decode_all(vec![Inner::Conn(NAVSAT), msg(NAVSAT, (1, 0), fix.payload())]);
        let [LogMessage::Gnss(m)] = messages.as_slice() else { panic!("{messages:?}") };
        let want = fix.message(Stamp(1_000_000_000));
        prop_assert_eq!((m.stamp, m.status, m.service, m.position_covariance_type),
            (want.stamp, want.status, want.service, want.position_covariance_type));
        prop_assert_eq!([m.latitude, m.longitude, m.altitude].map(f64::to_bits), lla);
        prop_assert_eq!(m.position_covariance.map(f64::to_bits), covariance);
    }
}
