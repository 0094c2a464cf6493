//! Arbitrary text as a rosbag2 `metadata.yaml`: parsing may fail, never panic.

#![no_main]

use fusemap_io::log::ros2::rosbag2::parse_metadata;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = parse_metadata(&String::from_utf8_lossy(data));
});
