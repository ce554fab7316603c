//! What candump/cansend/canplayer, PCAN-View and canopen users expect:
//! raw frames, log replay with timing, dump filters and decoded PDOs, the
//! monitor table, a live node's dictionary as a DCF, JSON everywhere.

mod common;

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, connect, wait_frame};
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

/// Lines of a background command until it exits (bounded by its own --seconds).
fn lines_of(url: &str, args: &[&str], during: impl FnOnce()) -> Vec<String> {
    let mut child = std::process::Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = child.stdout.take().unwrap();
    let reader =
        std::thread::spawn(move || BufReader::new(out).lines().map_while(Result::ok).collect::<Vec<_>>());
    during();
    let _ = child.wait();
    reader.join().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn send_and_replay_put_their_frames_on_the_bus() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let mut spy = connect(&u).await;
    let u2 = u.clone();
    tokio::task::spawn_blocking(move || {
        db(&u2, &["send", "605#40.00.10.00.00.00.00.00", "123#01", "1ABCDEF0#0102"])
            .success()
            .stdout(contains("sent 3 frame(s)"));
    })
    .await
    .unwrap();
    let f = wait_frame(&mut spy, Duration::from_secs(3), |f| f.std_id() == Some(0x585)).await.unwrap();
    assert_eq!(&f.data()[..4], &[0x43, 0x00, 0x10, 0x00], "the drive answered the raw SDO read");
    db(&u, &["send", "705#R1"]).failure().stderr(contains("RTR"));
    db(&u, &["send", "605#40.0"]).failure().stderr(contains("bad frame `605#40.0` at column"));
    // A candump log, twice, with its gaps.
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bus.log");
    std::fs::write(
        &log,
        "(1700000000.000000) can0 321#01\n\n(1700000000.020000) can0 322#0203\n(1700000000.040000) can1 323#\n",
    )
    .unwrap();
    let (u2, l2) = (u.clone(), log.clone());
    tokio::task::spawn_blocking(move || {
        db(&u2, &["replay", l2.to_str().unwrap(), "-l", "2", "-v"])
            .success()
            .stdout(contains("321#01").and(contains("replayed 6 frame(s)")));
    })
    .await
    .unwrap();
    let mut ids = Vec::new();
    while ids.len() < 6 {
        let f = wait_frame(&mut spy, Duration::from_secs(3), |f| matches!(f.std_id(), Some(0x321..=0x323)))
            .await
            .expect("replayed frame");
        ids.push(f.std_id().unwrap());
    }
    assert_eq!(ids, [0x321, 0x322, 0x323, 0x321, 0x322, 0x323]);
    db(&u, &["replay", "-I", log.to_str().unwrap(), "--interface", "can1", "-t"])
        .success()
        .stdout(contains("replayed 1 frame"));
    let bad = dir.path().join("bad.log");
    std::fs::write(&bad, "(1700000000.000000) can0 321#01\n(17000 can0 321#01\n").unwrap();
    db(&u, &["replay", bad.to_str().unwrap()]).failure().stderr(contains("bad.log:2:"));
}

#[test]
fn dump_filters_by_node_and_id_and_decodes_pdos() {
    let srv = Serve::start(&["--drive", "generic:1", "--drive", "generic:2"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "sdo", "write", "1017", "0", "50"]).success();
    db(&u, &["--node", "2", "sdo", "write", "1017", "0", "50"]).success();
    let got = lines_of(&u, &["--node", "1", "dump", "--count", "4", "--seconds", "10"], || {});
    assert_eq!(got.len(), 4, "{got:?}");
    assert!(got.iter().all(|l| l.contains("node 1")), "{got:?}");
    let got = lines_of(&u, &["dump", "--id", "702", "--count", "2", "--seconds", "10"], || {});
    assert!(got.len() == 2 && got.iter().all(|l| l.contains("heartbeat node 2")), "{got:?}");
    // PDOs decoded by the mapping read from the drive.
    let u2 = u.clone();
    let got = lines_of(
        &u,
        &["--node", "1", "dump", "--pdo", "--id", "181", "--count", "1", "--seconds", "10"],
        move || {
            std::thread::sleep(Duration::from_millis(700));
            db(&u2, &["--node", "1", "nmt", "start"]).success();
            db(&u2, &["--node", "1", "drive", "enable"]).success();
        },
    );
    assert!(got.first().is_some_and(|l| l.contains("TPDO1 node 1: Statusword = 0x")), "{got:?}");
}

#[test]
fn monitor_lists_states_emcys_and_watched_values() {
    let srv = Serve::start(&["--drive", "generic:3"], None);
    let u = srv.url();
    db(&u, &["--node", "3", "sdo", "write", "1017", "0", "50"]).success();
    let got = lines_of(&u, &["monitor", "--seconds", "2", "--watch", "statusword", "--watch", "6064"], || {});
    let all = got.join("\n");
    assert!(all.contains("node 3: state pre-operational"), "{all}");
    assert!(all.contains("Statusword 02") && all.contains("switch on disabled"), "{all}");
    assert!(all.contains("Position actual value 0"), "{all}");
    let got = lines_of(&u, &["--json", "monitor", "--seconds", "1"], || {});
    let j: serde_json::Value = serde_json::from_str(got.first().expect("a JSON line")).unwrap();
    assert_eq!(j["node"], 3);
}

#[test]
fn a_live_node_as_a_dcf() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "write", "1017", "0", "123"]).success();
    let dir = tempfile::tempdir().unwrap();
    let dcf = dir.path().join("node5.dcf");
    db(&u, &["--node", "5", "eds", "dcf", "--out", dcf.to_str().unwrap()])
        .success()
        .stdout(contains("wrote"));
    let text = std::fs::read_to_string(&dcf).unwrap();
    assert!(text.contains("[DeviceComissioning]") && text.contains("NodeID=0x05"), "{text}");
    assert!(text.contains("[1017]") && text.contains("ParameterValue=0x007B"), "{text}");
    assert!(text.contains("[6041]"), "CiA 402 objects of the drive");
    Command::new(common::bin())
        .args(["eds", "check", dcf.to_str().unwrap()])
        .assert()
        .stdout(contains("0 error(s)"));
    // With the drive's EDS: its manufacturer objects too.
    let eds = dir.path().join("generic.eds");
    Command::new(common::bin())
        .args(["eds", "export", "--profile", "generic", "-o", eds.to_str().unwrap()])
        .assert()
        .success();
    db(&u, &["--node", "5", "--eds", eds.to_str().unwrap(), "eds", "dcf"])
        .success()
        .stdout(contains("ParameterValue="));
}

#[test]
fn every_command_speaks_json() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    for args in [
        vec!["scan", "--to", "8"],
        vec!["--node", "5", "sdo", "read", "1000"],
        vec!["--node", "5", "sdo", "write", "1017", "0", "0"],
        vec!["--node", "5", "nmt", "preop"],
        vec!["--node", "5", "pdo", "show"],
        vec!["--node", "5", "drive", "status"],
        vec!["--node", "5", "sdo", "store"],
        vec!["send", "123#00"],
        vec!["lss", "scan", "--help"],
    ] {
        if args.contains(&"--help") {
            continue;
        }
        let mut a = vec!["--json"];
        a.extend(args.iter().copied());
        let out = db(&u, &a).success().get_output().stdout.clone();
        let j: serde_json::Value = serde_json::from_slice(&out)
            .unwrap_or_else(|e| panic!("{args:?}: {e}: {}", String::from_utf8_lossy(&out)));
        assert!(j.is_object(), "{args:?}");
    }
    // Errors too: one object, code and message.
    let out = db(&u, &["--json", "--node", "9", "--timeout", "100", "sdo", "read", "1000"])
        .failure()
        .get_output()
        .stdout
        .clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(j["error"]["code"], "sdo_timeout");
    let out = db(&u, &["--json", "--node", "5", "sdo", "read", "2FFF"]).failure().get_output().stdout.clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(
        (j["error"]["code"].as_str(), j["error"]["abort_code"].as_str()),
        (Some("sdo_abort"), Some("0x06020000"))
    );
    let out = db(&u, &["--json", "sdo", "read", "1000"]).failure().get_output().stdout.clone();
    assert!(String::from_utf8_lossy(&out).contains("\"usage\""));
}
