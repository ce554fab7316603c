//! `--machine FILE` (docs/machine.md): the machine around the virtual
//! drives of `serve` and `--sim` (and the refusals of a bad file), and the
//! default machine every served drive has without it (issue 11 §1:
//! method 17 on `generic` must not run away).

mod common;

use assert_cmd::Command;
use common::Serve;
use predicates::prelude::*;
use predicates::str::contains;

fn db() -> Command {
    let mut c = Command::new(common::bin());
    c.env_remove("DRIVEBUS_BUS");
    c
}

fn file(dir: &tempfile::TempDir, name: &str, text: &str) -> String {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_owned()
}

#[test]
fn limit_switch_homing_on_a_served_drive_and_a_fault_at_run_time() {
    let dir = tempfile::tempdir().unwrap();
    // Node 5 starts on its negative limit switch (−300° of a 3:1 table =
    // −900° of the motor); its positive limit switch trips 1.5 s after the
    // drive started, for 60 s.
    let m = file(
        &dir,
        "m.toml",
        "[[node]]\nid = 5\nfeed = 360.0\ngear_ratio = 3.0\nstart = -310.0\n\
         limits = { negative = -300.0, positive = 300.0 }\nhome_switch = { from = 30.0, to = 60.0 }\n\
         hard_stops = { negative = -330.0, positive = 330.0 }\n\
         [[node.faults]]\nat = 1.5\nkind = \"trip\"\nswitch = \"positive_limit\"\nduration = 60.0\n",
    );
    let srv = Serve::start(&["--drive", "generic:5", "--drive", "akd:1", "--machine", &m], None);
    let u = srv.url();
    let run = |args: &[&str]| {
        let out = db().args(["--bus", &u]).args(args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    // On the negative limit switch: 60FDh bit 0.
    assert!(run(&["--node", "5", "sdo", "read", "60FD"]).contains("Digital inputs = 1 (0x00000001)"));
    run(&["--node", "5", "drive", "enable"]);
    let out = run(&["--node", "5", "drive", "home", "--method", "17"]);
    assert!(out.contains("node 5: homing attained (method 17), position"), "{out}");
    // Off the switch again, a little right of its edge.
    let pos: i64 = out.split("position ").nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap();
    assert!((1..=2000).contains(&pos), "{out}");
    assert!(run(&["--node", "5", "sdo", "read", "60FD"]).contains("Digital inputs = 0 (0x00000000)"));
    // The AKD without a table: its default machine (the home switch 0.5…1.5
    // turns right of the start, so method −4, "reference switch positive",
    // completes; a bare axis would run away).
    run(&["--node", "1", "drive", "enable"]);
    let out = run(&["--node", "1", "drive", "home", "--method", "-4", "--wait", "20"]);
    assert!(out.contains("node 1: homing attained (method -4)"), "{out}");
    // The scheduled fault: by 1.5 s after the start the positive limit
    // switch reads tripped although the axis is far from it.
    std::thread::sleep(std::time::Duration::from_millis(1600));
    assert!(run(&["--node", "5", "sdo", "read", "60FD"]).contains("Digital inputs = 2 (0x00000002)"));
    // Out of homing (where the switches are the method's signals), it is a
    // limit: statusword bit 11 (internal limit active), and a velocity
    // towards it is held at 0.
    run(&["--node", "5", "drive", "velocity", "36000"]);
    std::thread::sleep(std::time::Duration::from_millis(300));
    let value = |out: String| -> i64 {
        out.split("= ").nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap()
    };
    let sw = value(run(&["--node", "5", "sdo", "read", "6041"]));
    assert_eq!(sw & 0x0800, 0x0800, "statusword {sw:04X}h");
    let v = value(run(&["--node", "5", "sdo", "read", "606C"]));
    assert!(v.abs() <= 100, "velocity {v} towards the tripped switch");
    drop(srv);
}

#[test]
fn sim_drives_take_the_machine_file() {
    let dir = tempfile::tempdir().unwrap();
    let m = file(&dir, "m.toml", "[[node]]\nid = 2\nstart = 99999.0\n");
    // generic node 2 at +1300°: on its positive limit switch (+1260°).
    let m2 = file(&dir, "m2.toml", "[[node]]\nid = 2\nstart = 1300.0\n");
    db().args([
        "--bus",
        "virtual",
        "--sim",
        "generic:2",
        "--machine",
        &m,
        "--node",
        "2",
        "sdo",
        "read",
        "60FD",
    ])
    .assert()
    .failure()
    .stderr(contains("m.toml: line 3, column 9: node 2: start: 99999 is beyond a hard stop"));
    db().args([
        "--bus",
        "virtual",
        "--sim",
        "generic:2",
        "--machine",
        &m2,
        "--node",
        "2",
        "sdo",
        "read",
        "60FD",
    ])
    .assert()
    .success()
    .stdout(contains("Digital inputs = 2 (0x00000002)"));
    // Without the file: its default machine, off the switches.
    db().args(["--bus", "virtual", "--sim", "generic:2", "--node", "2", "sdo", "read", "60FD"])
        .assert()
        .success()
        .stdout(contains("Digital inputs = 0 (0x00000000)"));
}

#[test]
fn a_bad_machine_file_is_refused_with_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let bad = file(&dir, "bad.toml", "[[node]]\nid = 5\nfeed = \n");
    db().args(["serve", "--drive", "generic:5", "--listen", "127.0.0.1:0", "--machine", &bad])
        .assert()
        .failure()
        .stderr(contains("bad.toml: line 3, column 8:"));
    let typo = file(&dir, "typo.toml", "[[node]]\nid = 5\n[node.limits]\nnegatve = -10.0\n");
    db().args([
        "--bus",
        "virtual",
        "--sim",
        "generic:5",
        "--machine",
        &typo,
        "--node",
        "5",
        "drive",
        "status",
    ])
    .assert()
    .failure()
    .stderr(contains("typo.toml: line 4, column 1:").and(contains("negatve")));
    let other = file(&dir, "other.toml", "[[node]]\nid = 9\n");
    db().args(["serve", "--drive", "generic:5", "--listen", "127.0.0.1:0", "--machine", &other])
        .assert()
        .failure()
        .stderr(contains("other.toml: line 2, column 6: node 9 has a machine but no drive"));
    db().args(["demo", "--no-progress", "--machine", &other])
        .assert()
        .failure()
        .stderr(contains("node 9 has a machine but no drive"));
    db().args([
        "serve",
        "--drive",
        "generic:5",
        "--listen",
        "127.0.0.1:0",
        "--machine",
        "/nonexistent/m.toml",
    ])
    .assert()
    .failure()
    .stderr(contains("/nonexistent/m.toml: cannot read"));
    // A machine for drives this command does not host, or for none at all.
    db().args(["--bus", "virtual", "--machine", &other, "scan"])
        .assert()
        .failure()
        .stderr(contains("--machine is the machine around --sim drives"));
    db().args(["eds", "check", "--machine", &other, "x.eds"])
        .assert()
        .failure()
        .stderr(contains("--machine does not apply to `drivebus eds check`"));
}

/// `slcan-pty` hosts its drives on their machines too.
#[cfg(unix)]
#[test]
fn slcan_pty_drives_take_the_machine_file() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    // generic node 5 on its negative limit switch (−1260°).
    let m = file(&dir, "m.toml", "[[node]]\nid = 5\nstart = -1300.0\n");
    let mut child = std::process::Command::new(common::bin())
        .args(["slcan-pty", "--drive", "generic:5", "--machine", &m, "--seconds", "20"])
        .env_remove("DRIVEBUS_BUS")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
    let path = first.trim().strip_prefix("slcan-pty ").map(str::to_owned);
    let out = path.map(|p| {
        db().args(["--bus", &format!("slcan://{p}?bitrate=1000000"), "--node", "5", "sdo", "read", "60FD"])
            .output()
            .unwrap()
    });
    let _ = child.kill();
    let _ = child.wait();
    let out = out.expect("slcan-pty PATH line");
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("Digital inputs = 1 (0x00000001)"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
