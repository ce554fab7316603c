//! Commands that never lie: each test is one misbehaviour of the tool
//! before issue 10 (it failed then), run as the binary against
//! `drivebus serve` over socketcand or against in-process devices.

mod common;

use std::process::Stdio;
use std::time::Duration;

use assert_cmd::Command;
use common::Serve;
use predicates::prelude::*;
use predicates::str::contains;

fn db(url: &str, args: &[&str]) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(90))
        .assert()
}

fn json(url: &str, args: &[&str]) -> serde_json::Value {
    let mut a = vec!["--json"];
    a.extend_from_slice(args);
    let out = db(url, &a).success().get_output().stdout.clone();
    serde_json::from_slice(&out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out)))
}

/// A machine file putting `node` on an axis without limit switches or
/// hard stops (every served drive has both by default since issue 11):
/// method 17 then searches for ever, the motion these tests stop.
fn endless_axis(dir: &tempfile::TempDir, node: u8) -> String {
    let p = dir.path().join("endless.toml");
    let text = format!(
        "[[node]]\nid = {node}\nlimits = {{ enabled = false }}\nhard_stops = {{ enabled = false }}\n"
    );
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_owned()
}

fn velocity(url: &str, node: &str) -> i64 {
    json(url, &["--node", node, "drive", "status"])["velocity"].as_i64().unwrap()
}

/// `drive home` reported "homing attained" from the bit 12 an earlier
/// homing left set; a homing that times out left the axis running away
/// (method 17 on `generic`: no limit switch) and said nothing.
#[test]
fn homing_waits_for_a_fresh_attained_and_a_timeout_halts_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Serve::start(&["--drive", "generic:5", "--machine", &endless_axis(&dir, 5)], None);
    let u = srv.url();
    db(&u, &["--node", "5", "drive", "enable"]).success();
    db(&u, &["--node", "5", "drive", "home", "--method", "35"]).success().stdout(contains("homing attained"));
    db(&u, &["--node", "5", "drive", "home", "--method", "17", "--wait", "1"]).failure().stderr(
        contains("timed out waiting for homing attained")
            .and(contains("halted"))
            .and(contains("6099h homing speeds"))
            .and(contains("position")),
    );
    assert!(velocity(&u, "5").abs() <= 100, "the axis stands still after the command");
    // A failed command that started motion: the drive is stopped, not left turning.
    db(&u, &["--node", "5", "drive", "status"]).success().stdout(contains("operation enabled"));
}

/// Ctrl-C in a waiting `drive` command left the axis moving.
#[cfg(unix)]
#[test]
fn ctrl_c_halts_the_motion_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Serve::start(&["--drive", "generic:6", "--machine", &endless_axis(&dir, 6)], None);
    let u = srv.url();
    db(&u, &["--node", "6", "drive", "enable"]).success();
    let child = std::process::Command::new(common::bin())
        .args(["--bus", &u, "--node", "6", "drive", "home", "--method", "17", "--wait", "60"])
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Let the search get under way (a second SDO client now would share
    // the node's one SDO channel with the command: CiA 301 allows one).
    std::thread::sleep(Duration::from_secs(2));
    let _ = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("interrupted") && err.contains("halted"), "{err}");
    assert!(velocity(&u, "6").abs() <= 100, "halted");
}

/// `drive move 90000` on the AKD (6081h starts at 10 units/s, its
/// manual §6.11.2.3) waited 30 s and failed with no hint.
#[test]
fn a_move_that_cannot_finish_is_refused_with_the_limiting_objects() {
    let srv = Serve::start(&["--drive", "akd:1"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "drive", "enable"]).success();
    db(&u, &["--node", "1", "drive", "move", "90000"]).failure().stderr(
        contains("6081h profile velocity: 10").and(contains("nothing was moved")).and(contains("--velocity")),
    );
    let out = json(&u, &["--node", "1", "drive", "status"]);
    assert_eq!(out["position"], 0, "nothing moved");
    // With a speed it goes, and stays quiet on a non-terminal (no progress lines).
    let ok = db(&u, &["--node", "1", "drive", "move", "90000", "--velocity", "360000"]).success();
    ok.stdout(contains("target reached at")).stderr(predicates::str::is_empty());
    // JSON errors: one object with a code.
    db(&u, &["--node", "1", "sdo", "write", "6081", "0", "10"]).success();
    let out = Command::new(common::bin())
        .args(["--bus", &u, "--json", "--node", "1", "drive", "move", "0"])
        .env_remove("DRIVEBUS_BUS")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["error"]["code"], "refused", "{j}");
    assert!(j["error"]["message"].as_str().unwrap().contains("6081h"));
}

/// `drive reset` wrote controlword 0 first: a running drive was disabled.
#[test]
fn reset_leaves_a_running_drive_alone() {
    let srv = Serve::start(&["--drive", "generic:7"], None);
    let u = srv.url();
    db(&u, &["--node", "7", "drive", "enable"]).success();
    db(&u, &["--node", "7", "drive", "reset"]).success().stdout(contains("no fault to reset"));
    db(&u, &["--node", "7", "drive", "status"]).success().stdout(contains("operation enabled"));
}

/// `sdo read 6041` read index 1799h (decimal 6041); standard objects had
/// no name or type without `--eds`.
#[test]
fn indices_are_hex_and_standard_objects_are_named_and_typed() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "read", "6041"])
        .success()
        .stdout(contains("6041h:00 Statusword = ").and(contains("[UNSIGNED16]")));
    db(&u, &["--node", "5", "sdo", "read", "statusword"]).success().stdout(contains("6041h:00 Statusword"));
    db(&u, &["--node", "5", "sdo", "read", "6041:00"]).success().stdout(contains("6041h:00"));
    // A whole record.
    db(&u, &["--node", "5", "sdo", "read", "1018"]).success().stdout(
        contains("1018h:01 Identity object / Vendor-ID")
            .and(contains("1018h:04 Identity object / Serial number")),
    );
    let j = json(&u, &["--node", "5", "sdo", "read", "1018"]);
    assert_eq!(j["entries"].as_array().unwrap().len(), 5);
    // Typed writes by name; store with the "save" signature.
    db(&u, &["--node", "5", "sdo", "write", "producer_heartbeat_time", "250"])
        .success()
        .stdout(contains("UNSIGNED16"));
    db(&u, &["--node", "5", "sdo", "read", "1017"]).success().stdout(contains("= 250"));
    db(&u, &["--node", "5", "sdo", "store"]).success().stdout(contains("stored"));
    db(&u, &["--node", "5", "sdo", "restore", "--what", "app"]).success().stdout(contains("restored"));
    db(&u, &["--node", "5", "sdo", "read", "60x1"]).failure().stderr(contains("write the index in hex"));
}

/// A refused `pdo map` left the PDO invalid and empty.
#[test]
fn a_refused_mapping_leaves_the_previous_one() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let before = json(&u, &["--node", "5", "pdo", "show"]);
    db(&u, &["--node", "5", "pdo", "map", "tpdo", "1", "1000:0:32"])
        .failure()
        .stderr(contains("mapping refused").and(contains("in force again")));
    let after = json(&u, &["--node", "5", "pdo", "show"]);
    assert_eq!(before, after, "TPDO1 as it was");
}

/// Global options were accepted and silently ignored.
#[test]
fn options_that_do_not_apply_are_refused() {
    Command::new(common::bin())
        .args(["--node", "3", "eds", "check", "x.eds"])
        .assert()
        .code(2)
        .stderr(contains("--node does not apply to `drivebus eds check`"));
    Command::new(common::bin())
        .args(["--eds", "x.eds", "nmt", "stop", "--all"])
        .assert()
        .code(2)
        .stderr(contains("--eds does not apply to `drivebus nmt`"));
    let out = Command::new(common::bin()).args(["--json", "demo", "--timeout", "3"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["error"]["code"], "usage");
}

/// `lss set-node-id 9` with two unconfigured slaves gave both node-ID 9.
#[test]
fn lss_refuses_to_configure_two_slaves_at_once() {
    let bus = common::LssBus::start(&[0x20, 0x10]);
    let u = bus.url.clone();
    db(&u, &["lss", "set-node-id", "9"]).failure().stderr(
        contains("more than one unconfigured LSS slave")
            .and(contains("--serial 0x10"))
            .and(contains("nothing was changed")),
    );
    // Nothing answers at node 9.
    db(&u, &["--node", "9", "--timeout", "200", "sdo", "read", "1000"])
        .failure()
        .stderr(contains("timed out"));
    db(&u, &["lss", "scan"])
        .success()
        .stdout(contains("serial 0x00000010").and(contains("more unconfigured")));
    // The address path configures exactly one.
    db(
        &u,
        &[
            "lss",
            "set-node-id",
            "9",
            "--vendor",
            "0xABC",
            "--product",
            "0x77",
            "--revision",
            "3",
            "--serial",
            "0x20",
        ],
    )
    .success()
    .stdout(contains("node-ID 9 configured"));
    std::thread::sleep(Duration::from_millis(100));
    db(&u, &["--node", "9", "sdo", "read", "1018:04"]).success().stdout(contains("= 32"));
    // One unconfigured slave left: the global path is safe now.
    db(&u, &["lss", "set-node-id", "10"]).success().stdout(contains("only unconfigured slave"));
    std::thread::sleep(Duration::from_millis(100));
    db(&u, &["--node", "10", "sdo", "read", "1018:04"]).success().stdout(contains("= 16"));
    // A configured node by its node-ID: 1018h by SDO, selective switch.
    db(&u, &["--timeout", "300", "--node", "10", "lss", "set-node-id", "11"])
        .success()
        .stdout(contains("reset-comm"));
    drop(bus);
}
