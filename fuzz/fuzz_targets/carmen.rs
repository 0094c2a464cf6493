//! Arbitrary bytes into the CARMEN reader, plain or gzipped, strict and lenient: it
//! may return errors, never panic, and always comes to an end.

#![no_main]

use fusemap_io::log::carmen::{sniff, CarmenOptions, CarmenReader};
use fusemap_io::log::LogReader;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = sniff(data);
    for strict in [false, true] {
        let options = CarmenOptions { strict, ..Default::default() };
        let Ok(mut reader) = CarmenReader::from_reader("fuzz.log", data, options) else {
            continue;
        };
        while reader.next_message().is_some() {}
        let stats = reader.stats();
        assert!(stats.malformed_examples.len() <= 10);
        if strict {
            assert_eq!(stats.malformed, 0);
        }
    }
});
