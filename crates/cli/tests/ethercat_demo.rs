//! `drivebus demo --ethercat`: an ethercrab master and an emulated iPOS in
//! one process, no root. It runs, prints its summary, writes a non-empty
//! SVG (by default `drivebus-demo-ethercat.svg` in the working
//! directory) and exits 0; `--json` gives the same figures.

use std::process::Command;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_drivebus")
}

#[test]
fn the_ethercat_demo_runs_prints_its_summary_and_writes_the_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(bin())
        .args(["demo", "--ethercat", "--no-progress"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    for want in [
        "drivebus demo --ethercat — ethercrab master, emulated iPOS on the in-process link, DC SYNC0 at 1 ms, simulated time",
        "  found slave 1: iPOS360x VX-CAT vendor 0x000001A3 product 0x01AB46E5 revision 0x41303047 serial 1 (1018h = SII)",
        "  homing slave 1 (method 35)",
        "  profile position move slave 1 (4000 counts)",
        "  CSP sine slave 1 (1000 counts, 1 Hz)         2000 cycles",
        "  cycles with a wrong working counter          0 (expected 3 on every cycle)",
        "plot: drivebus-demo-ethercat.svg (",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
    let svg = std::fs::read_to_string(dir.path().join("drivebus-demo-ethercat.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("iPOS following error") && svg.len() > 10_000,
        "{}",
        svg.len()
    );
}

#[test]
fn the_ethercat_demo_in_json_follows_its_trajectory() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("x.svg");
    let out = Command::new(bin())
        .args(["demo", "--ethercat", "--json", "--sine-seconds", "1", "--out"])
        .arg(&svg)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["dc"], true, "{j}");
    assert_eq!(j["bad_wkc"], 0, "{j}");
    assert_eq!(j["csp"]["cycles"], 1000, "{j}");
    assert_eq!(j["homing"]["position"], 0, "{j}");
    assert!((j["move"]["position"].as_i64().unwrap() - 4000).abs() <= 10, "{j}");
    // The iPOS's following error window is one turn (2000 counts).
    assert!(j["csp"]["following_error_max"].as_f64().unwrap() < 2000.0, "{j}");
    assert!(j["samples"].as_u64().unwrap() > 1000, "{j}");
    assert!(std::fs::metadata(&svg).unwrap().len() > 10_000);
}
