//! CDR payloads of the pose sensors laid out by hand: `sensor_msgs/msg/NavSatFix`,
//! `geometry_msgs/msg/PoseWithCovarianceStamped`, and the covariances and twist of
//! `sensor_msgs/msg/Imu` and `nav_msgs/msg/Odometry`; and a bad one in an MCAP file.

use super::*;
use crate::log::ros2::msgs::sensor_msgs::{NavSatFix, NavSatStatus};
use crate::log::{GnssMessage, PoseMessage};
use fusemap_core::geometry::Pose2;

impl W {
    fn i8(&mut self, v: i8) -> &mut Self {
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn u8(&mut self, v: u8) -> &mut Self {
        self.buf.push(v);
        self
    }
    fn u16(&mut self, v: u16) -> &mut Self {
        self.align(2);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
}

/// `base, base + 1, …`: every element different, so a field read from the wrong offset
/// shows as a wrong value.
fn ramp<const N: usize>(base: f64) -> [f64; N] {
    std::array::from_fn(|i| base + i as f64)
}

/// One `sensor_msgs/msg/NavSatFix` as a test writes it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fix {
    sec: i32,
    nanosec: u32,
    status: i8,
    service: u16,
    lla: [f64; 3],
    covariance: [f64; 9],
    covariance_type: u8,
}

impl Fix {
    pub(super) fn sample() -> Self {
        Fix {
            sec: 60,
            nanosec: 70,
            status: NavSatStatus::STATUS_GBAS_FIX,
            service: NavSatStatus::SERVICE_GPS | NavSatStatus::SERVICE_GLONASS,
            lla: [-33.856_784, 151.215_297, 12.5],
            covariance: ramp(0.25),
            covariance_type: NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN,
        }
    }
}

pub(super) fn nav_sat_fix_payload(f: &Fix) -> Vec<u8> {
    let mut w = W::new();
    w.header(f.sec, f.nanosec, "gps").i8(f.status).u16(f.service);
    w.f64s(&f.lla).f64s(&f.covariance).u8(f.covariance_type);
    w.done()
}

pub(super) fn pose_payload(frame: &str, position: [f64; 3], orientation: [f64; 4]) -> Vec<u8> {
    let mut w = W::new();
    w.header(4, 5, frame).f64s(&position).f64s(&orientation).f64s(&ramp::<36>(-7.0));
    w.done()
}

fn decode(kind: KnownType, payload: &[u8]) -> LogMessage {
    decode_known(kind, "/t", Some(Stamp(77)), payload).unwrap_or_else(|e| panic!("{kind:?}: {e}"))
}

#[test]
fn nav_sat_fix_bytes_laid_out_by_hand() {
    let fix = Fix::sample();
    let p = nav_sat_fix_payload(&fix);
    // Body: header ends at 16 ("gps" + NUL); status at 16, one padding byte, service at
    // 18..20, four padding bytes, latitude at 24, the 12 doubles end at 120, the type
    // byte at 120.
    assert_eq!(p.len(), 4 + 121);
    assert_eq!(p[4 + 16], 2);
    assert_eq!(p[4 + 17], 0xAA);
    assert_eq!(&p[4 + 18..4 + 20], &3u16.to_le_bytes());
    assert_eq!(&p[4 + 20..4 + 24], &[0xAA; 4]);
    assert_eq!(&p[4 + 24..4 + 32], &fix.lla[0].to_le_bytes());
    assert_eq!(p[4 + 120], 2);

    let expected = GnssMessage {
        topic: "/t".into(),
        stamp: Stamp(60_000_000_070),
        receive_stamp: Some(Stamp(77)),
        frame_id: "gps".into(),
        status: fix.status,
        service: fix.service,
        latitude: fix.lla[0],
        longitude: fix.lla[1],
        altitude: fix.lla[2],
        position_covariance: fix.covariance,
        position_covariance_type: fix.covariance_type,
    };
    assert_eq!(decode(KnownType::NavSatFix, &p), LogMessage::Gnss(expected));
    let by_name = decode_message("sensor_msgs/msg/NavSatFix", "/t", Some(Stamp(77)), &p).unwrap();
    assert_eq!(by_name, Some(decode(KnownType::NavSatFix, &p)));
}

#[test]
fn a_fix_with_nan_fields_decodes_as_written() {
    let fix =
        Fix { status: NavSatStatus::STATUS_NO_FIX, lla: [f64::NAN; 3], covariance: [f64::NAN; 9], ..Fix::sample() };
    let LogMessage::Gnss(m) = decode(KnownType::NavSatFix, &nav_sat_fix_payload(&fix)) else { panic!("not a fix") };
    assert!([m.latitude, m.longitude, m.altitude].iter().all(|v| v.is_nan()));
    assert!(m.position_covariance.iter().all(|v| v.is_nan()));
    assert!(!m.has_fix());
}

#[test]
fn pose_with_covariance_stamped_and_its_degenerate_quaternion() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let p = pose_payload("map_frame", [1.5, -2.0, 0.25], [0.0, 0.0, h, h]);
    let expected = PoseMessage {
        topic: "/t".into(),
        stamp: Stamp(4_000_000_005),
        receive_stamp: Some(Stamp(77)),
        frame_id: "map_frame".into(),
        position: [1.5, -2.0, 0.25],
        orientation: [0.0, 0.0, h, h],
        covariance: ramp(-7.0),
    };
    assert_eq!(decode(KnownType::PoseWithCovarianceStamped, &p), LogMessage::Pose(expected.clone()));
    assert!((expected.pose2().theta - std::f64::consts::FRAC_PI_2).abs() < 1e-12);

    let p = pose_payload("map", [1.5, -2.0, 0.25], [0.0; 4]);
    let LogMessage::Pose(m) = decode(KnownType::PoseWithCovarianceStamped, &p) else { panic!("not a pose") };
    assert!(!m.pose2().is_finite());
}

#[test]
fn odometry_keeps_twist_and_covariances_and_a_zero_quaternion_has_no_heading() {
    let body = |q: [f64; 4]| {
        let mut w = W::new();
        w.header(1, 2, "odom").string("base_link");
        w.f64s(&[3.0, 4.0, 0.0]).f64s(&q).f64s(&ramp::<36>(10.0));
        w.f64s(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.125]).f64s(&ramp::<36>(100.0));
        w.done()
    };
    let LogMessage::Odometry(o) = decode(KnownType::Odometry, &body([0.0, 0.0, 0.0, 1.0])) else { panic!() };
    assert_eq!(o.pose, Pose2::new(3.0, 4.0, 0.0));
    assert_eq!(o.pose_covariance, ramp::<36>(10.0));
    assert_eq!(o.twist, [0.5, 0.0, 0.0, 0.0, 0.0, 0.125]);
    assert_eq!(o.twist_covariance, ramp::<36>(100.0));
    for q in [[0.0; 4], [f64::NAN, 0.0, 0.0, 1.0]] {
        let LogMessage::Odometry(o) = decode(KnownType::Odometry, &body(q)) else { panic!() };
        assert!(!o.pose.is_finite(), "{q:?}: {:?}", o.pose);
    }
}

#[test]
fn imu_keeps_its_covariances() {
    let LogMessage::Imu(m) = decode(KnownType::Imu, &imu_payload()) else { panic!("not imu") };
    assert_eq!(m.orientation_covariance, [0.01; 9]);
    assert_eq!(m.angular_velocity_covariance, [0.02; 9]);
    assert_eq!(m.linear_acceleration_covariance, [0.03; 9]);
    assert!(m.has_orientation());

    let mut w = W::new();
    w.header(3, 4, "imu");
    w.f64s(&[0.0; 4]).f64s(&[-1.0; 9]);
    w.f64s(&[0.1, 0.2, 0.3]).f64s(&ramp::<9>(1.0));
    w.f64s(&[0.0, 0.0, 9.81]).f64s(&ramp::<9>(50.0));
    let LogMessage::Imu(m) = decode(KnownType::Imu, &w.done()) else { panic!("not imu") };
    assert!(!m.has_orientation());
    assert_eq!(m.angular_velocity_covariance, ramp::<9>(1.0));
    assert_eq!(m.linear_acceleration_covariance, ramp::<9>(50.0));
}

#[test]
fn type_names_of_the_pose_sensors() {
    for (name, kind) in [
        ("sensor_msgs/msg/NavSatFix", KnownType::NavSatFix),
        ("sensor_msgs/NavSatFix", KnownType::NavSatFix),
        ("geometry_msgs/msg/PoseWithCovarianceStamped", KnownType::PoseWithCovarianceStamped),
        ("geometry_msgs/PoseWithCovarianceStamped", KnownType::PoseWithCovarianceStamped),
    ] {
        assert_eq!(KnownType::from_name(name), Some(kind), "{name}");
    }
    assert_eq!(KnownType::from_name("geometry_msgs/msg/PoseStamped"), None);
}

#[test]
fn a_truncated_fix_in_an_mcap_is_skippable_and_the_next_message_is_read() {
    let whole = nav_sat_fix_payload(&Fix::sample());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fix.mcap");
    for cut in [0, 3, 4, 20, 30, whole.len() - 1] {
        let log = vec![
            ("/fix", "sensor_msgs/msg/NavSatFix", "cdr", 1_000, whole[..cut].to_vec()),
            ("/fix", "sensor_msgs/msg/NavSatFix", "cdr", 2_000, whole.clone()),
        ];
        write_mcap(&path, Some(mcap::Compression::Zstd), &log);
        let mut r = open_ros2(&path).unwrap();
        let all = read_all(r.as_mut());
        assert_eq!(all.len(), 2, "cut {cut}");
        match &all[0] {
            Err(e @ Error::Format { location, message, .. }) => {
                assert!(e.is_skippable(), "cut {cut}: {e}");
                assert_eq!(location, &Location::Message { index: 1, topic: "/fix".into() });
                assert!(message.starts_with("sensor_msgs/msg/NavSatFix: "), "{message}");
            }
            other => panic!("cut {cut}: {other:?}"),
        }
        match &all[1] {
            Ok(LogMessage::Gnss(m)) => assert_eq!(m.receive_stamp, Some(Stamp(2_000))),
            other => panic!("cut {cut}: {other:?}"),
        }
    }
}
