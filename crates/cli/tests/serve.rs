//! `drivebus serve`: the contract other tools rely on (issue 5 §4).

mod common;

use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, connect, sdo_read, sdo_write, wait_frame};
use drivebus_transport::Frame;
use predicates::prelude::*;

const SAVE: [u8; 4] = *b"save";
const LOAD: [u8; 4] = *b"load";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn serves_drives_boots_heartbeats_and_stops_on_sigterm() {
    let mut srv = Serve::start(&["--drive", "akd:1", "--drive", "dds6:2", "--drive", "generic:5"], None);
    assert!(srv.line.contains(&format!("127.0.0.1:{}", srv.port)), "{}", srv.line);
    let mut bus = connect(&srv.url()).await;
    // Each drive answers 1000h with its personality's device type.
    for (node, profile) in [(1u8, "akd"), (2, "dds6"), (5, "generic")] {
        let p = drivebus_personality::Profile::from_name(profile).unwrap();
        assert_eq!(sdo_read(&mut bus, node, 0x1000, 0).await, Ok(p.info().device_type), "{profile}");
    }
    // A missing object: the abort code CiA 301 defines.
    assert_eq!(sdo_read(&mut bus, 1, 0x2FFF, 0x7F).await, Err(0x0602_0000));
    // Reset node: boot-up message, then pre-operational heartbeats at 1017h.
    bus.send(Frame::new(0x000, &[0x81, 1])).await.unwrap();
    let boot = wait_frame(&mut bus, Duration::from_secs(3), |f| f.std_id() == Some(0x701)).await;
    assert_eq!(boot.map(|f| f.data().to_vec()), Some(vec![0x00]), "boot-up after reset node");
    sdo_write(&mut bus, 1, 0x1017, 0, &50u16.to_le_bytes()).await.unwrap();
    let mut beats = 0;
    let t0 = tokio::time::Instant::now();
    while beats < 3 {
        let f = wait_frame(&mut bus, Duration::from_secs(2), |f| f.std_id() == Some(0x701)).await;
        assert_eq!(f.expect("heartbeat").data(), [0x7F], "pre-operational heartbeat");
        beats += 1;
    }
    assert!(t0.elapsed() < Duration::from_secs(2));
    // NMT start: the heartbeat reports operational.
    bus.send(Frame::new(0x000, &[0x01, 1])).await.unwrap();
    let op =
        wait_frame(&mut bus, Duration::from_secs(2), |f| f.std_id() == Some(0x701) && f.data() == [0x05])
            .await;
    assert!(op.is_some(), "operational heartbeat");
    drop(bus);
    let st = srv.terminate();
    assert!(st.success(), "serve exit status {st:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn drives_keep_running_without_clients_and_accept_reconnects() {
    let srv = Serve::start(&["--drive", "kc1:3"], None);
    {
        let mut bus = connect(&srv.url()).await;
        sdo_write(&mut bus, 3, 0x1017, 0, &100u16.to_le_bytes()).await.unwrap();
    }
    tokio::time::sleep(Duration::from_millis(200)).await;
    let mut bus = connect(&srv.url()).await;
    // Still producing the heartbeat configured by the previous client.
    let hb = wait_frame(&mut bus, Duration::from_secs(2), |f| f.std_id() == Some(0x703)).await;
    assert!(hb.is_some(), "heartbeat after reconnect");
    assert_eq!(sdo_read(&mut bus, 3, 0x1017, 0).await, Ok(100));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn state_dir_keeps_stored_parameters_across_restarts() {
    let dir = tempfile::tempdir().unwrap();
    let default = {
        let mut srv = Serve::start(&["--drive", "akd:1"], Some(dir.path()));
        let mut bus = connect(&srv.url()).await;
        let default = sdo_read(&mut bus, 1, 0x1017, 0).await.unwrap();
        sdo_write(&mut bus, 1, 0x1017, 0, &123u16.to_le_bytes()).await.unwrap();
        sdo_write(&mut bus, 1, 0x1010, 1, &SAVE).await.unwrap();
        drop(bus);
        assert!(srv.terminate().success());
        default
    };
    assert_ne!(default, 123);
    assert!(dir.path().join("akd-1").is_dir(), "per-drive state directory");
    let mut srv = Serve::start(&["--drive", "akd:1"], Some(dir.path()));
    let mut bus = connect(&srv.url()).await;
    assert_eq!(sdo_read(&mut bus, 1, 0x1017, 0).await, Ok(123), "stored 1017h survives the restart");
    // 1011h "load" + reset node brings the defaults back.
    sdo_write(&mut bus, 1, 0x1011, 1, &LOAD).await.unwrap();
    bus.send(Frame::new(0x000, &[0x81, 1])).await.unwrap();
    assert!(
        wait_frame(&mut bus, Duration::from_secs(3), |f| f.std_id() == Some(0x701) && f.data() == [0])
            .await
            .is_some()
    );
    assert_eq!(sdo_read(&mut bus, 1, 0x1017, 0).await, Ok(default));
    drop(bus);
    assert!(srv.terminate().success());
}

#[test]
fn bad_drive_specs_fail_with_a_clear_message() {
    for (spec, needle) in [
        ("foo:1", "unknown profile `foo`"),
        ("akd:0", "not in 1..127"),
        ("akd:128", "not in 1..127"),
        ("akd", "expected PROFILE:NODE"),
        ("akd:x", "not in 1..127"),
    ] {
        Command::new(common::bin())
            .args(["serve", "--listen", "127.0.0.1:0", "--drive", spec])
            .timeout(Duration::from_secs(20))
            .assert()
            .failure()
            .stderr(predicate::str::contains(needle));
    }
    Command::new(common::bin())
        .args(["serve", "--listen", "127.0.0.1:0", "--drive", "akd:1", "--drive", "kc1:1"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(predicate::str::contains("already taken"));
}

#[test]
fn serve_without_drive_or_with_busy_port_fails() {
    Command::new(common::bin())
        .args(["serve"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(predicate::str::contains("--drive"));
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    Command::new(common::bin())
        .args(["serve", "--listen", &format!("127.0.0.1:{port}"), "--drive", "akd:1"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(predicate::str::contains("cannot listen on"));
}

#[test]
fn serve_help_has_examples() {
    Command::new(common::bin())
        .args(["serve", "--help"])
        .assert()
        .success()
        .stdout(predicate::str::contains("Examples:").and(predicate::str::contains("--state-dir")));
}

/// `--fault`: the hub drops (or corrupts) frames by rule, for testing how a
/// master copes (issue 5 §1: fault injection on every transport hosting drives).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fault_rules_drop_and_corrupt_frames() {
    // Every SDO response of node 5 is lost; node 6 answers, with byte 7 flipped.
    let srv = Serve::start(
        &[
            "--drive",
            "generic:5",
            "--drive",
            "generic:6",
            "--fault",
            "drop:0x585",
            "--fault",
            "corrupt:0x586:00000000000000FF",
        ],
        None,
    );
    let mut bus = connect(&srv.url()).await;
    bus.send(Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0])).await.unwrap();
    assert!(wait_frame(&mut bus, Duration::from_millis(500), |f| f.std_id() == Some(0x585)).await.is_none());
    // 1000h of the generic drive: 0x00020192 → the top byte arrives XORed with FF.
    assert_eq!(sdo_read(&mut bus, 6, 0x1000, 0).await, Ok(0xFF02_0192));
}

#[test]
fn bad_fault_rules_fail_with_a_clear_message() {
    Command::new(common::bin())
        .args(["serve", "--listen", "127.0.0.1:0", "--drive", "generic:5", "--fault", "drop:banana"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(predicate::str::contains("bad --fault `drop:banana`"));
}

/// `--lss-slave`: an unconfigured slave that `drivebus lss` finds and
/// gives a node-ID, which it then answers SDO under.
#[test]
fn an_lss_slave_is_found_and_configured() {
    let srv = Serve::start(&["--drive", "generic:5", "--lss-slave", "0xABC:0x77:3:0x10"], None);
    assert!(srv.line.contains("unconfigured LSS slaves 0xABC:0x77:3:0x10"), "{}", srv.line);
    let db = |args: &[&str]| {
        Command::new(common::bin())
            .arg("--bus")
            .arg(srv.url())
            .args(args)
            .env_remove("DRIVEBUS_BUS")
            .timeout(Duration::from_secs(60))
            .assert()
    };
    db(&["lss", "scan"]).success().stdout(predicate::str::contains("serial 0x00000010"));
    db(&["lss", "set-node-id", "9"]).success().stdout(predicate::str::contains("only unconfigured slave"));
    std::thread::sleep(Duration::from_millis(100));
    db(&["--node", "9", "sdo", "read", "1018:04"]).success().stdout(predicate::str::contains("= 16"));
    Command::new(common::bin())
        .args(["serve", "--listen", "127.0.0.1:0", "--drive", "generic:5", "--lss-slave", "1:2:3"])
        .timeout(Duration::from_secs(20))
        .assert()
        .failure()
        .stderr(predicate::str::contains("bad --lss-slave `1:2:3`"));
}
