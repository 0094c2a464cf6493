//! Arbitrary bytes into the ROS 2 CDR decoders, as given and behind a valid
//! little-endian encapsulation header, for every message type fusemap decodes: they may
//! return errors, never panic, and never allocate more than the input can fill.

#![no_main]

use fusemap_io::log::ros2::cdr::{decode_cdr, CDR_LE};
use fusemap_io::log::ros2::msgs::wire::RosMsg;
use fusemap_io::log::ros2::msgs::{nav_msgs, sensor_msgs, tf2_msgs};
use fusemap_io::log::ros2::{decode_known, KnownType};
use libfuzzer_sys::fuzz_target;

fn check<T: RosMsg>(payload: &[u8], kind: KnownType) {
    let typed = decode_cdr::<T>(payload);
    let converted = decode_known(kind, "/fuzz", None, payload);
    assert_eq!(typed.is_ok(), converted.is_ok(), "{kind:?}");
}

fuzz_target!(|data: &[u8]| {
    let mut with_header = Vec::with_capacity(data.len() + 4);
    with_header.extend_from_slice(&CDR_LE);
    with_header.extend_from_slice(&[0, 0]);
    with_header.extend_from_slice(data);
    for payload in [data, &with_header[..]] {
        check::<sensor_msgs::LaserScan>(payload, KnownType::LaserScan);
        check::<nav_msgs::Odometry>(payload, KnownType::Odometry);
        check::<tf2_msgs::TfMessage>(payload, KnownType::TfMessage);
        check::<sensor_msgs::Imu>(payload, KnownType::Imu);
    }
});
