//! The mailbox and CoE/FoE server of a drive slave on a segment, fed
//! request mailboxes, SM1 reads, state requests and time steps through
//! frames (`drivebus_ethercat::drive::fuzzing` has the record format and
//! the checks): nothing may panic, every message fits the mailbox, and
//! afterwards the drive still answers an upload of 1000h.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    drivebus_ethercat::drive::fuzzing::drive_mailbox(data);
});
