//! Arbitrary bytes into the ROS 1 bag reader (magic line, record layer, chunks of every
//! compression, connections, messages): it may return errors, never panic, never reserve
//! more than the input can fill, and always comes to an end.

#![no_main]

use fusemap_io::log::ros1::BagReader;
use fusemap_io::log::LogReader;
use libfuzzer_sys::fuzz_target;

/// The magic line of a ROS 1 bag v2.0, so that most inputs reach the record layer.
const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

fuzz_target!(|data: &[u8]| {
    let mut with_magic = Vec::with_capacity(MAGIC.len() + data.len());
    with_magic.extend_from_slice(MAGIC);
    with_magic.extend_from_slice(data);
    for bytes in [data, &with_magic[..]] {
        let Ok(mut reader) = BagReader::from_reader(bytes, "fuzz.bag") else {
            continue;
        };
        // Each message consumes input or ends the reader, so this loop is bounded; the
        // guard catches a reader that would repeat itself forever.
        let mut steps = 0usize;
        while let Some(m) = reader.next_message() {
            steps += 1;
            assert!(steps <= bytes.len() + 1, "more results than input bytes");
            if m.is_err() {
                break;
            }
        }
    }
});
