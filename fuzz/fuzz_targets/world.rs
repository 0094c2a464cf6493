//! Arbitrary text as a simulated world file (`--world`): parsing and validation may fail
//! with an error, never panic, and never allocate past the world budget.

#![no_main]

use fusemap_io::world_file::parse_world_str;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(world) = parse_world_str(&String::from_utf8_lossy(data), Path::new("fuzz.toml")) {
        let _ = world.scan_count();
    }
});
