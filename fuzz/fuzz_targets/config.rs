//! Arbitrary text as a fusemap config file (`--config`): parsing and validation may fail
//! with an error, never panic; an accepted config passes its own budget check.

#![no_main]

use fusemap_io::config_file::parse_config_str;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = parse_config_str(&String::from_utf8_lossy(data), Path::new("fuzz.toml"));
});
