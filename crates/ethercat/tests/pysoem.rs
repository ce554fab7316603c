//! SOEM (through pysoem 1.1.13) against four digital I/O slaves on a veth
//! pair in a network namespace: discovery, SII names and identity, process
//! data mapped from the SII PDO categories, OP, 2000 cycles with the
//! expected working counter and correct data.
//!
//! Needs root, `ip`, and a Python with pysoem: `PYSOEM_PYTHON`, which
//! `scripts/test` points at the interop venv (`tests/interop/.venv`, where
//! `tests/interop/requirements.txt` pins pysoem 1.1.13) once
//! `tests/interop/run` has made it. Without `PYSOEM_PYTHON` the test tries
//! `python3` and prints why it skipped when that has no pysoem; a
//! `PYSOEM_PYTHON` that cannot import pysoem is a failure (the set-up was
//! asked for and is broken). Without root or `ip` it prints why it skipped.

mod common;

use std::process::Command;
use std::time::Duration;

#[test]
fn soem_via_pysoem_over_veth() {
    let explicit = std::env::var("PYSOEM_PYTHON").ok();
    let python = explicit.clone().unwrap_or_else(|| "python3".into());
    let why = match Command::new(&python).args(["-c", "import pysoem"]).output() {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(format!(
            "`{python}` cannot import pysoem ({})",
            String::from_utf8_lossy(&o.stderr).lines().last().unwrap_or("").trim()
        )),
        Err(e) => Some(format!("cannot run `{python}`: {e}")),
    };
    if let Some(why) = why {
        assert!(explicit.is_none(), "PYSOEM_PYTHON is set but unusable: {why}");
        println!(
            "SKIPPED soem_via_pysoem_over_veth: {why}; PYSOEM_PYTHON unset (scripts/test sets it to \
             tests/interop/.venv/bin/python after tests/interop/run made the venv)"
        );
        return;
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
