//! SOEM (through pysoem 1.1.13) against a line made from real devices'
//! descriptions on a veth pair in a network namespace: an EK1100 coupler,
//! an EL2004 (Intel hex image) and an EL2828 (binary image) dumped from
//! the real terminals, the KickCAT Freedom-K64F board from its ESI file,
//! and two iPOS twins. SOEM discovers them by their real names and
//! identities, maps the process data (SII categories for the terminals,
//! CoE 1C12h/1C13h for the board and the drives), goes to OP; the outputs
//! it writes appear on the devices, the board's inputs loop them back and
//! read the same over CoE, and its write-only LED object refuses a read.
//!
//! Same set-up and skip rules as `pysoem.rs` (root, `ip`, `PYSOEM_PYTHON`).

#[allow(dead_code)]
mod common;

use drivebus_ethercat::described::{self, Member};
use drivebus_personality::Profile;
use std::process::Command;
use std::time::Duration;

fn vector(name: &str) -> String {
    format!("{}/../../tests/vectors/ethercat/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn soem_discovers_real_devices_and_drives_their_outputs() {
    let explicit = std::env::var("PYSOEM_PYTHON").ok();
    let python = explicit.clone().unwrap_or_else(|| "python3".into());
    let usable =
        Command::new(&python).args(["-c", "import pysoem"]).output().is_ok_and(|o| o.status.success());
    if !usable {
        assert!(explicit.is_none(), "PYSOEM_PYTHON is set but cannot import pysoem");
        println!("SKIPPED soem_discovers_real_devices_and_drives_their_outputs: `{python}` has no pysoem");
        return;
    }
    let dev =
        |f: &str| Member::Device(Box::new(described::load(&vector(f)).unwrap_or_else(|e| panic!("{e}"))));
    let members = [
        dev("ek1100.bin"),
        dev("el2004.hex"),
        dev("el2828.bin"),
        dev("kickcat-freedom-k64f.xml"),
        Member::Drive(Profile::Ipos),
        Member::Drive(Profile::Ipos),
    ];
    let devices = described::devices(&members, None).unwrap();
    let mut wire = match common::Wire::with_devices("sd", devices) {
        Ok(w) => w,
        Err(why) => {
            println!("SKIPPED soem_discovers_real_devices_and_drives_their_outputs: {why}");
            return;
        }
    };
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/interop/pysoem_described.py");
    let (ok, out) = wire.run(&python, &[script, wire.inner.as_str(), "500"], Duration::from_secs(120));
    let host = wire.host.clone().unwrap();
    let stats = wire.stop();
    println!("{out}\nserver: {stats:?}");
    assert!(ok, "pysoem run failed:\n{out}");
    for line in [
        "slave 0 EK1100 vendor 0x00000002 product 0x044c2c52 rev 0x00120000",
        "slave 1 EL2004 vendor 0x00000002 product 0x07d43052 rev 0x00100000",
        "slave 2 EL2828 vendor 0x00000002 product 0x0b0c3052 rev 0x00110000",
        "slave 3 Board vendor 0x000006a5 product 0x00defede rev 0x00005a01",
        "slave 4 iPOS360x VX-CAT vendor 0x000001a3",
        "slave 1 in 0 B out 1 B",
        "slave 3 in 12 B out 3 B",
        "board inputs over CoE 333435333435",
        "board 7000h read aborted 0x06010001",
        "slaves=6 cycles=500",
        "bad_wkc=0 looped=1",
    ] {
        assert!(out.contains(line), "missing {line:?}:\n{out}");
    }
    // The master left OP at the end (outputs off again): what the devices
    // applied last in OP is the pattern the script wrote, (0x30 + i + j).
    let applied = |i| described::with_device(&host, i, |s| s.app().last_applied().to_vec()).unwrap();
    assert_eq!(applied(1), [0x01], "EL2004: the low 4 bits of 0x31");
    assert_eq!(applied(2), [0x32], "EL2828");
    assert_eq!(applied(3), [0x33, 0x34, 0x35], "the board's LEDs");
    assert_eq!(
        described::with_device(&host, 1, |s| s.app().outputs().to_vec()).unwrap(),
        [0],
        "off outside OP"
    );
}
