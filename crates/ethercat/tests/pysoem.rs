//! SOEM (through pysoem 1.1.13) against four digital I/O slaves on a veth
//! pair in a network namespace: discovery, SII names and identity, process
//! data mapped from the SII PDO categories, OP, 2000 cycles with the
//! expected working counter and correct data.
//!
//! Needs root, `ip`, and a Python with pysoem: `PYSOEM_PYTHON` (default
//! `python3`). Prints why it was skipped when one of them is missing.
//! Set up with: `python3 -m venv /tmp/pysoem && /tmp/pysoem/bin/pip install
//! pysoem==1.1.13`, then `PYSOEM_PYTHON=/tmp/pysoem/bin/python`.

mod common;

use std::process::Command;
use std::time::Duration;

#[test]
fn soem_via_pysoem_over_veth() {
    let python = std::env::var("PYSOEM_PYTHON").unwrap_or_else(|_| "python3".into());
    match Command::new(&python).args(["-c", "import pysoem"]).output() {
        Ok(o) if o.status.success() => {}
        Ok(o) => {
            println!(
                "SKIPPED soem_via_pysoem_over_veth: `{python}` cannot import pysoem ({}); \
                 install pysoem==1.1.13 and set PYSOEM_PYTHON",
                String::from_utf8_lossy(&o.stderr).lines().last().unwrap_or("").trim()
            );
            return;
        }
        Err(e) => {
            println!("SKIPPED soem_via_pysoem_over_veth: cannot run `{python}`: {e}");
            return;
        }
    }
    let mut wire = match common::Wire::new("so") {
        Ok(w) => w,
        Err(why) => {
            println!("SKIPPED soem_via_pysoem_over_veth: {why}");
            return;
        }
    };
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/interop/pysoem_probe.py");
    let masks = common::masks();
    let (ok, out) = wire.run(
        &python,
        &[script, wire.inner.as_str(), "4", "2000", masks.as_str()],
        Duration::from_secs(120),
    );
    let stats = wire.stop();
    println!("{out}\nserver: {stats:?}");
    assert!(ok, "pysoem run failed:\n{out}");
    assert!(out.contains("slaves=4 cycles=2000 expected_wkc=12 bad_wkc=0 bad_data=0"), "{out}");
    assert!(out.contains("slave 3 DB-DIO16 vendor 0x00000db0 product 0x0000d10f in 2 B out 2 B"), "{out}");
}
