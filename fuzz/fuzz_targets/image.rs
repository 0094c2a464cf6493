//! Arbitrary bytes as a ROS 2 `sensor_msgs/Image` (CDR) and then as camera labels and
//! depth: decoding may fail with an error, never panic, and never allocate more pixels
//! than the payload holds.

#![no_main]

use fusemap_io::camera::{depth, labels};
use fusemap_io::log::ros2::cdr::CDR_LE;
use fusemap_io::log::ros2::{decode_known_with, KnownType};
use fusemap_io::log::LogMessage;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut with_header = Vec::with_capacity(data.len() + 4);
    with_header.extend_from_slice(&CDR_LE);
    with_header.extend_from_slice(&[0, 0]);
    with_header.extend_from_slice(data);
    for payload in [data, &with_header[..]] {
        for pixels in [false, true] {
            match decode_known_with(KnownType::Image, "/fuzz", None, payload, pixels) {
                Ok(LogMessage::Image(m)) => {
                    assert!(pixels);
                    let _ = labels(&m);
                    let _ = depth(&m);
                }
                Ok(LogMessage::ImageHeader(h)) => assert!(!pixels && h.data_len <= payload.len() as u64),
                Ok(other) => panic!("an image decoded as {other:?}"),
                Err(_) => {}
            }
        }
    }
});
