//! Fuzz the EtherCAT mailbox server (CoE SDO, complete access, SDO
//! Information, emergencies, FoE, mailbox errors) with request sequences,
//! reads, time steps, emergencies and resets. The decoding lives in
//! `crates/coe/tests/support/driver.rs`, which `crates/coe/tests/random_input.rs`
//! also runs on stable (proptest and this target's seed corpus).
#![no_main]

#[path = "../../crates/coe/tests/support/driver.rs"]
mod driver;

libfuzzer_sys::fuzz_target!(|input: &[u8]| {
    driver::drive(input);
});
