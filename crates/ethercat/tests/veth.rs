//! ethercrab over a real veth pair: the test creates a network namespace
//! and a veth pair, serves four digital I/O slaves with the AF_PACKET
//! server on the root-namespace end, and runs the `drivebus-ecat-probe`
//! binary (ethercrab's own raw-socket transport) inside the namespace on
//! the other end — 5000 free-run cycles, then 5000 cycles with DC SYNC0 at
//! 1 ms, in real time.
//!
//! Needs root (CAP_NET_ADMIN, CAP_NET_RAW) and `ip`. When the namespace
//! cannot be created the test prints exactly why and stops; the namespace
//! and the links are removed even when it fails.

mod common;

use std::time::Duration;

#[test]
fn ethercrab_over_veth_in_a_network_namespace() {
    let mut wire = match common::Wire::new("ec") {
        Ok(w) => w,
        Err(why) => {
            println!("SKIPPED ethercrab_over_veth_in_a_network_namespace: {why}");
            return;
        }
    };
    let probe = env!("CARGO_BIN_EXE_drivebus-ecat-probe");
    let masks = common::masks();
    let base =
        ["--interface", wire.inner.as_str(), "--slaves", "4", "--masks", masks.as_str(), "--cycles", "5000"];
    let (free_ok, free_out) = wire.run(probe, &base, Duration::from_secs(120));
    let mut dc = base.to_vec();
    dc.extend_from_slice(&["--dc-us", "1000"]);
    let (dc_ok, dc_out) = wire.run(probe, &dc, Duration::from_secs(120));
    let stats = wire.stop();
    println!("free run:\n{free_out}\nDC:\n{dc_out}\nserver: {stats:?}");
    assert!(free_ok, "free run over veth failed:\n{free_out}");
    assert!(dc_ok, "DC over veth failed:\n{dc_out}");
    assert!(free_out.contains("slaves=4 cycles=5000 expected_wkc=12 bad_wkc=0 bad_data=0"), "{free_out}");
    assert!(dc_out.contains("slaves=4 cycles=5000 expected_wkc=12 bad_wkc=0 bad_data=0"), "{dc_out}");
    assert!(free_out.contains("DB-DIO16"), "names from the SII: {free_out}");
    assert!(free_out.contains("delay 1500 ns"), "propagation delays: {free_out}");
    assert!(stats.frames > 10_000);
}
