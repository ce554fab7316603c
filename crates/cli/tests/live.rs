//! Commands against a running `drivebus serve` (state kept between
//! invocations): `drive ...`, `dump`, and `slcan-pty`.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Stdio};
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
        .timeout(Duration::from_secs(60))
        .assert()
}

#[test]
fn drive_commands_walk_the_state_machine_and_move() {
    let srv = Serve::start(&["--drive", "akd:1", "--drive", "dds6:2"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "drive", "status"]).success().stdout(contains("switch on disabled"));
    db(&u, &["--node", "1", "drive", "move", "1000"]).failure().stderr(contains("not in operation enabled"));
    db(&u, &["--node", "1", "drive", "enable"]).success().stdout(contains("operation enabled"));
    db(&u, &["--node", "1", "drive", "home", "--method", "35"]).success().stdout(contains("homing attained"));
    // The AKD starts with 6081h = 10 units/s (§6.11.2.3): a commissioning
    // move names its speed.
    db(&u, &["--node", "1", "drive", "move", "90000", "--velocity", "360000"])
        .success()
        .stdout(contains("target reached"));
    let out = db(&u, &["--node", "1", "--json", "drive", "status"]).success().get_output().stdout.clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(j["state"], "operation enabled");
    assert!((j["position"].as_i64().unwrap() - 90_000).abs() <= 100, "{j}");
    db(&u, &["--node", "1", "drive", "move", "-45000", "--relative", "--velocity", "360000"])
        .success()
        .stdout(contains("target reached"));
    db(&u, &["--node", "1", "drive", "velocity", "36000"])
        .success()
        .stdout(contains("target velocity 36000"));
    db(&u, &["--node", "1", "drive", "velocity", "0"]).success();
    db(&u, &["--node", "1", "drive", "torque", "50"]).success().stdout(contains("target torque 50"));
    db(&u, &["--node", "1", "drive", "torque", "40000"]).failure().stderr(contains("outside"));
    db(&u, &["--node", "1", "drive", "quickstop"]).success().stdout(contains("quick stop"));
    db(&u, &["--node", "1", "drive", "reset"]).success();
    db(&u, &["--node", "1", "drive", "enable"]).success();
    db(&u, &["--node", "1", "drive", "disable"]).success().stdout(contains("ready to switch on"));
    db(&u, &["--node", "2", "drive", "enable"]).success();
    db(&u, &["--node", "9", "--timeout", "200", "drive", "status"])
        .failure()
        .stderr(contains("node 9").and(contains("timed out")));
    db(&u, &["drive", "status"]).failure().stderr(contains("needs --node"));
}

/// Runs `drivebus dump ARGS` in the background and returns its child.
fn spawn_dump(url: &str, args: &[&str]) -> Child {
    std::process::Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .arg("dump")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

struct Kill(Child);
impl Drop for Kill {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn lines(child: &mut Child, n: usize) -> Vec<String> {
    let out = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(out).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    let mut got = Vec::new();
    while got.len() < n {
        match rx.recv_timeout(Duration::from_secs(10)) {
            Ok(l) => got.push(l),
            Err(_) => break,
        }
    }
    got
}

#[test]
fn dump_decodes_and_writes_candump() {
    let srv = Serve::start(&["--drive", "akd:1"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "sdo", "write", "0x1017", "0", "20", "--type", "u16"]).success();
    let mut d = Kill(spawn_dump(&u, &["--count", "3", "--seconds", "10"]));
    let got = lines(&mut d.0, 3);
    assert_eq!(got.len(), 3, "{got:?}");
    assert!(got.iter().all(|l| l.contains("heartbeat node 1: pre-operational")), "{got:?}");
    let st = d.0.wait().unwrap();
    assert!(st.success());
    let mut c = Kill(spawn_dump(&u, &["--candump", "--count", "2", "--seconds", "10"]));
    let got = lines(&mut c.0, 2);
    assert_eq!(got.len(), 2);
    for l in &got {
        assert!(l.starts_with('(') && l.ends_with(" can0 701#7F"), "{l}");
    }
    // SDO, EMCY and NMT decoded, with names from an EDS.
    let dir = tempfile::tempdir().unwrap();
    let eds = dir.path().join("akd.eds");
    Command::new(common::bin())
        .args(["eds", "export", "--profile", "akd", "-o", eds.to_str().unwrap()])
        .assert()
        .success();
    let mut e = Kill(
        std::process::Command::new(common::bin())
            .args(["--bus", &u, "--eds", eds.to_str().unwrap(), "dump", "--seconds", "3"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    std::thread::sleep(Duration::from_millis(400));
    db(&u, &["--node", "1", "sdo", "read", "0x1000"]).success();
    db(&u, &["--node", "1", "nmt", "start"]).success();
    let got = lines(&mut e.0, 400);
    let all = got.join("\n");
    assert!(all.contains("SDO master → node 1: read 1000h:00 (Device type"), "{all}");
    assert!(all.contains("SDO node 1 → master: 1000h:00"), "{all}");
    assert!(all.contains("NMT start → node 1"), "{all}");
    // Bad URL: named.
    db("nope://x", &["dump"]).failure().stderr(contains("bad bus URL"));
}

#[test]
fn bitrate_paced_server_still_answers() {
    let srv = Serve::start(&["--drive", "ipos:4", "--bitrate", "125000"], None);
    db(&srv.url(), &["--node", "4", "sdo", "read", "0x1000"]).success().stdout(contains("1000h:00"));
    Command::new(common::bin())
        .args(["serve", "--listen", "127.0.0.1:0", "--drive", "akd:1", "--bitrate", "5"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(contains("bad --bitrate"));
}

#[cfg(unix)]
#[test]
fn slcan_pty_exposes_virtual_drives() {
    let mut child = Kill(
        std::process::Command::new(common::bin())
            .args(["slcan-pty", "--drive", "akd:1", "--seconds", "20"])
            .env_remove("DRIVEBUS_BUS")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let got = lines(&mut child.0, 1);
    let path =
        got.first().and_then(|l| l.strip_prefix("slcan-pty ")).expect("slcan-pty PATH line").to_owned();
    let url = format!("slcan://{path}?bitrate=1000000");
    db(&url, &["--node", "1", "sdo", "read", "0x1000"]).success().stdout(contains("131474"));
    Command::new(common::bin())
        .args(["--bus", "socketcand://127.0.0.1:1/can0", "slcan-pty", "--drive", "akd:1"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(contains("in-process virtual bus"));
    Command::new(common::bin())
        .args(["slcan-pty", "--drive", "zzz:1"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(contains("unknown profile"));
}
