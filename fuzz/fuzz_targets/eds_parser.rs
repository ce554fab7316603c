//! Any byte string fed to the EDS/DCF reader, the checker, the writer and
//! the dictionary builder must give a result or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(p) = drivebus_eds::parse(&text) {
        let _ = drivebus_eds::check(&p.eds);
        let _ = drivebus_eds::to_od(&p.eds, 1);
        let again = drivebus_eds::parse(&drivebus_eds::write(&p.eds));
        assert!(again.is_ok(), "written file does not read back");
    }
});
