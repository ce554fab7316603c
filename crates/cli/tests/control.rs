//! `drivebus serve --control` driven by `drivebus control` (issue 17 §3):
//! an input seen in 60FDh, an encoder fault's EMCY and its clear, frames
//! dropped by a rule, a drive powered off and on and bus-off, errors
//! that say why.

mod common;

use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, bin, connect, sdo_read, sdo_write, wait_frame};
use drivebus_transport::Frame;

fn control(sock: &str, args: &[&str]) -> std::process::Output {
    Command::new(bin()).args(["control", "--connect", sock]).args(args).output().unwrap()
}

fn ok(sock: &str, args: &[&str]) {
    let out = control(sock, args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "ok\n");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_sets_inputs_faults_bus_rules_and_power() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("control.sock");
    let sock = sock.to_str().unwrap();
    let mut srv = Serve::start(&["--drive", "generic:5", "--control", sock], None);
    assert!(srv.line.ends_with(&format!("; control on {sock}")), "{}", srv.line);
    let mut bus = connect(&srv.url()).await;

    // An input: generic shows line 3 in 60FDh bit 18.
    assert_eq!(sdo_read(&mut bus, 5, 0x60FD, 0).await.unwrap() & (1 << 18), 0);
    ok(sock, &["input", "5", "digital", "3", "on"]);
    assert_ne!(sdo_read(&mut bus, 5, 0x60FD, 0).await.unwrap() & (1 << 18), 0);

    // A machine fault: EMCY 7305h; cleared, a fault reset leaves Fault.
    ok(sock, &["fault", "5", "encoder"]);
    let emcy = wait_frame(&mut bus, Duration::from_secs(3), |f| f.std_id() == Some(0x85)).await;
    assert_eq!(emcy.map(|f| f.data()[..2].to_vec()), Some(vec![0x05, 0x73]));
    assert_eq!(sdo_read(&mut bus, 5, 0x6041, 0).await.unwrap() & 0x4F, 0x08, "Fault");
    ok(sock, &["fault", "5", "clear"]);
    tokio::time::sleep(Duration::from_millis(50)).await;
    sdo_write(&mut bus, 5, 0x6040, 0, &0x80u16.to_le_bytes()).await.unwrap();
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert_eq!(sdo_read(&mut bus, 5, 0x6041, 0).await.unwrap() & 0x4F, 0x40, "Switch on disabled");

    // A bus rule: the next SDO response is lost, the one after arrives.
    ok(sock, &["bus", "drop", "--id", "0x585", "--count", "1"]);
    bus.send(Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0])).await.unwrap();
    assert!(wait_frame(&mut bus, Duration::from_millis(500), |f| f.std_id() == Some(0x585)).await.is_none());
    assert_eq!(sdo_read(&mut bus, 5, 0x1000, 0).await, Ok(0x0002_0192));

    // Power: off stops the heartbeat, on boots (00h) with 1017h as at power-on.
    sdo_write(&mut bus, 5, 0x1017, 0, &50u16.to_le_bytes()).await.unwrap();
    assert!(wait_frame(&mut bus, Duration::from_secs(1), |f| f.std_id() == Some(0x705)).await.is_some());
    ok(sock, &["power", "5", "off"]);
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert!(wait_frame(&mut bus, Duration::from_millis(300), |f| f.std_id() == Some(0x705)).await.is_none());
    let off = control(sock, &["input", "5", "digital", "3", "off"]);
    assert!(String::from_utf8_lossy(&off.stderr).contains("node 5 is powered off: power it on first"));
    ok(sock, &["power", "5", "on"]);
    let boot = wait_frame(&mut bus, Duration::from_secs(3), |f| f.std_id() == Some(0x705)).await;
    assert_eq!(boot.map(|f| f.data().to_vec()), Some(vec![0x00]));
    assert_eq!(sdo_read(&mut bus, 5, 0x1017, 0).await, Ok(0));

    // Bus-off: silent and deaf until it is back on the bus.
    sdo_write(&mut bus, 5, 0x1017, 0, &50u16.to_le_bytes()).await.unwrap();
    ok(sock, &["bus", "off", "5"]);
    tokio::time::sleep(Duration::from_millis(100)).await;
    bus.send(Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0])).await.unwrap();
    let heard =
        wait_frame(&mut bus, Duration::from_millis(300), |f| matches!(f.std_id(), Some(0x585 | 0x705)));
    assert!(heard.await.is_none(), "a bus-off node sends nothing");
    ok(sock, &["bus", "on", "5"]);
    assert!(wait_frame(&mut bus, Duration::from_secs(1), |f| f.std_id() == Some(0x705)).await.is_some());
    assert_eq!(sdo_read(&mut bus, 5, 0x1000, 0).await, Ok(0x0002_0192));
    // With --recover the controller is back by itself after 128 × 11 bits
    // and the node says so: EMCY 8140h with 1001h bit 4.
    ok(sock, &["bus", "off", "5", "--recover"]);
    let recovered = |f: &Frame| f.std_id() == Some(0x85) && f.data()[..2] == [0x40, 0x81];
    let emcy = wait_frame(&mut bus, Duration::from_secs(1), recovered).await;
    assert_eq!(emcy.map(|f| f.data()[2] & 0x11), Some(0x11));
    assert_eq!(sdo_read(&mut bus, 5, 0x1000, 0).await, Ok(0x0002_0192));

    // Errors: the cause first, then what to do; --json like the others.
    let out = control(sock, &["input", "9", "digital", "3", "on"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no node with node-ID 9 is served: use one of 5"));
    let out = control(sock, &["fault", "5", "encodr"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown variant `encodr`"));
    let out = Command::new(bin())
        .args(["--json", "control", "--connect", sock, "power", "5", "on"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["ok"], true);
    assert_eq!(v["request"]["op"], "power");
    drop(bus);
    assert!(srv.terminate().success());
    assert!(!std::path::Path::new(sock).exists(), "the socket is removed at exit");
}

#[test]
fn control_without_a_server_says_what_to_do() {
    // A port just freed (a fixed one such as 1 may be taken on a shared host).
    let addr = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().to_string();
    let out = control(&addr, &["power", "5", "on"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("cannot reach the control interface at {addr}")), "{err}");
    assert!(err.contains(&format!("drivebus serve --control {addr}")), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_sets_the_inputs_of_a_cia401_module() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("control.sock");
    let sock = sock.to_str().unwrap();
    let eds = concat!(env!("CARGO_MANIFEST_DIR"), "/../cia401/eds/io16.eds");
    let device = format!("{eds}:3");
    let mut srv = Serve::start(&["--drive", "generic:5", "--device", &device, "--control", sock], None);
    let mut bus = connect(&srv.url()).await;
    // Line 9 is 6000h sub 2 bit 0 (docs/machine.md).
    assert_eq!(sdo_read(&mut bus, 3, 0x6000, 2).await, Ok(0));
    ok(sock, &["input", "3", "digital", "9", "on"]);
    assert_eq!(sdo_read(&mut bus, 3, 0x6000, 2).await, Ok(1));
    let out = control(sock, &["fault", "3", "encoder"]);
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("node 3: kind: a device from an EDS/DCF has no machine faults")
    );
    // Powered on again: its inputs as at power-on.
    ok(sock, &["power", "3", "off"]);
    ok(sock, &["power", "3", "on"]);
    let boot = wait_frame(&mut bus, Duration::from_secs(3), |f| f.std_id() == Some(0x703)).await;
    assert_eq!(boot.map(|f| f.data().to_vec()), Some(vec![0x00]));
    assert_eq!(sdo_read(&mut bus, 3, 0x6000, 2).await, Ok(0));
    drop(bus);
    assert!(srv.terminate().success());
}
