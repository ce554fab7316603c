//! Any byte string as a `--device` file (SII image in binary or Intel hex,
//! or an ESI file), with or without a device selector, must give a slave
//! or an error naming where and why, never a panic.
#![no_main]

use drivebus_ethercat::described::{self, Loopback};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (select, data) = match data.split_first() {
        Some((b'#', rest)) => (Some("2"), rest),
        _ => (None, data),
    };
    let _ = described::ihex::parse(data);
    if let Ok(d) = described::from_bytes("fuzz", data, select) {
        let _ = described::slave(&d, 1, Box::new(Loopback));
    }
});
