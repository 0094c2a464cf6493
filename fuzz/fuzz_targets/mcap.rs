//! Arbitrary bytes as a bare MCAP file into the ROS 2 reader (magic, records, chunks
//! compressed with zstd or lz4, schemas, channels, messages, the summary section): it may
//! return errors, never panic, and always comes to an end. The reader opens files by
//! path, so each input is written to a file of this process first.

#![no_main]

use fusemap_io::log::ros2::Ros2Reader;
use fusemap_io::log::LogReader;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

/// The MCAP magic, so that most inputs reach the record layer.
const MAGIC: &[u8] = b"\x89MCAP0\r\n";

fn scratch() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = if std::path::Path::new("/dev/shm").is_dir() { "/dev/shm".into() } else { std::env::temp_dir() };
        dir.join(format!("fusemap-fuzz-{}.mcap", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let path = scratch();
    let mut bytes = data.to_vec();
    if !bytes.starts_with(MAGIC) {
        bytes.splice(0..0, MAGIC.iter().copied());
    }
    std::fs::write(path, &bytes).expect("scratch file");
    let Ok(mut reader) = Ros2Reader::open_mcap(path) else {
        return;
    };
    let mut steps = 0usize;
    while let Some(m) = reader.next_message() {
        steps += 1;
        assert!(steps <= bytes.len() + 1, "more results than input bytes");
        if m.is_err() {
            break;
        }
    }
});
