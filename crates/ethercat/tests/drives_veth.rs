//! ethercrab over a real veth pair against CoE drives: the test creates a
//! network namespace and a veth pair, serves a line of four drives (iPOS,
//! generic, iPOS, generic) with the AF_PACKET server on the root-namespace
//! end, and runs the `drivebus-ecat-drive-probe` binary (ethercrab's own
//! raw-socket transport) inside the namespace: discovery, identity, the
//! E10/E11 remapping in PRE-OP, 5000 csp cycles at 1 ms in free run, then
//! 5000 with DC SYNC0 at 1 ms, in real time.
//!
//! Needs root (CAP_NET_ADMIN, CAP_NET_RAW) and `ip`. When the namespace
//! cannot be created the test prints exactly why and stops; the namespace
//! and the links are removed even when it fails.

#[allow(dead_code)]
mod common;

use drivebus_ethercat::drive::DriveLine;
use drivebus_personality::Profile;
use std::time::Duration;

#[test]
fn drives_over_veth_in_a_network_namespace() {
    let line = [Profile::Ipos, Profile::Generic, Profile::Ipos, Profile::Generic]
        .iter()
        .fold(DriveLine::new(), |l, p| l.drive(*p));
    let devices = line.devices().expect("drives");
    let mut wire = match common::Wire::with_devices("dv", devices) {
        Ok(w) => w,
        Err(why) => {
            println!("SKIPPED drives_over_veth_in_a_network_namespace: {why}");
            return;
        }
    };
    let probe = env!("CARGO_BIN_EXE_drivebus-ecat-drive-probe");
    let base = ["--interface", wire.inner.as_str(), "--drives", "4", "--cycles", "5000", "--remap"];
    let (free_ok, free_out) = wire.run(probe, &base, Duration::from_secs(180));
    let mut dc = base.to_vec();
    dc.extend_from_slice(&["--dc-us", "1000"]);
    let (dc_ok, dc_out) = wire.run(probe, &dc, Duration::from_secs(180));
    let stats = wire.stop();
    println!("free run:\n{free_out}\nDC:\n{dc_out}\nserver: {stats:?}");
    assert!(free_ok, "free run over veth failed:\n{free_out}");
    assert!(dc_ok, "DC over veth failed:\n{dc_out}");
    for out in [&free_out, &dc_out] {
        assert!(out.contains("drives=4 cycles=5000 expected_wkc=12 bad_wkc=0 enabled=4 faults=0"), "{out}");
        assert!(
            out.contains("iPOS360x VX-CAT vendor 0x000001a3 product 28002021 revision 0x41303047"),
            "{out}"
        );
        assert!(out.contains("drivebus generic CiA 402 servo"), "{out}");
        assert_eq!(out.matches("coe_identity_matches true").count(), 4, "{out}");
    }
    assert!(stats.frames > 10_000);
}
