//! `drivebus ethercat serve --control` driven by `drivebus control` on a
//! veth pair (issue 17 §3): a broadcast read from the other end counts
//! the slaves that answer while the line is broken, loses frames, has a
//! slave miscount or a slave's power cut; clearing restores the line.
//! Machine faults reach the drive twins; requests that cannot apply say
//! why.
//!
//! Needs root (veth, AF_PACKET); prints why it was skipped otherwise.

use drivebus_ethercat::server::RawSocket;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod netns;
use netns::{Veth, count_frame};

/// The working counter of one broadcast read, `None` if no reply came.
fn count(sock: &RawSocket) -> Option<u16> {
    let mut buf = vec![0u8; 1514];
    sock.send(&count_frame()).unwrap();
    let until = Instant::now() + Duration::from_millis(300);
    while Instant::now() < until {
        if let Ok(Some(n)) = sock.recv(&mut buf, drivebus_can::Duration::from_millis(50))
            && n >= 30
            && buf[12..14] == [0x88, 0xA4]
            && buf[6] & 0x02 != 0
        {
            return Some(u16::from_le_bytes([buf[28], buf[29]]));
        }
    }
    None
}

fn control(sock: &str, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args(["control", "--connect", sock])
        .args(args)
        .output()
        .unwrap()
}

fn ok(sock: &str, args: &[&str]) {
    let out = control(sock, args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "ok\n");
}

fn refused(sock: &str, args: &[&str], why: &str) {
    let out = control(sock, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains(why), "{args:?}: {err}");
}

#[test]
fn control_breaks_loses_skews_and_power_cycles_the_line() {
    let veth = match Veth::create("dbctl") {
        Ok(v) => v,
        Err(why) => {
            println!("SKIPPED control_breaks_loses_skews_and_power_cycles_the_line: {why}");
            return;
        }
    };
    let (tag, a, b) = (veth.tag, veth.a.clone(), veth.b.clone());
    let dir = std::env::temp_dir().join(format!("drivebus-ecat-control-{tag}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let sock = dir.join("control.sock");
    let sock = sock.to_str().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args([
            "ethercat", "serve", "--iface", &a, "--drive", "ipos", "--drive", "ipos", "--drive", "generic",
        ])
        .args(["--control", sock])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn drivebus");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    assert!(line.trim_end().ends_with(&format!("; control on {sock}")), "{line}");
    let raw = RawSocket::open(&b).expect("socket on the other end");
    let start = Instant::now();
    while count(&raw).is_none() && start.elapsed() < Duration::from_secs(10) {}
    assert_eq!(count(&raw), Some(3));

    ok(sock, &["bus", "break", "--after", "1"]);
    assert_eq!(count(&raw), Some(1), "slaves 2 and 3 are behind the break");
    ok(sock, &["bus", "clear"]);
    assert_eq!(count(&raw), Some(3));

    ok(sock, &["bus", "lose", "--count", "2"]);
    assert_eq!([count(&raw), count(&raw), count(&raw)], [None, None, Some(3)]);

    ok(sock, &["bus", "corrupt", "--slave", "2", "--count", "1"]);
    assert_eq!([count(&raw), count(&raw)], [None, Some(3)]);

    ok(sock, &["bus", "wkc", "--slave", "2", "--skew", "1"]);
    assert_eq!(count(&raw), Some(4));
    ok(sock, &["bus", "drift", "--slave", "3", "--ppm", "2000"]);
    ok(sock, &["bus", "jitter", "--slave", "3", "--amplitude", "5000", "--seed", "7"]);
    refused(sock, &["bus", "jitter", "--slave", "3", "--amplitude", "0"], "NS must be 1..1000000");
    ok(sock, &["bus", "clear"]);

    ok(sock, &["power", "2", "off"]);
    assert_eq!(count(&raw), Some(1), "the line ends before the unpowered slave");
    refused(sock, &["fault", "2", "encoder"], "slave 2 is powered off");
    ok(sock, &["power", "2", "on"]);
    assert_eq!(count(&raw), Some(3));

    ok(sock, &["fault", "1", "encoder"]);
    ok(sock, &["fault", "1", "clear"]);
    ok(sock, &["input", "3", "digital", "2", "on"]);
    refused(sock, &["input", "4", "digital", "2", "on"], "no slave 4 on the line: use 1..3");
    refused(sock, &["bus", "off", "1"], "no bus-off");
    refused(sock, &["bus", "break", "--after", "3"], "bad EtherCAT fault");

    let st = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(st.success());
    let status = child.wait().unwrap();
    assert!(status.success(), "exit status {status:?}");
    assert!(!std::path::Path::new(sock).exists(), "the socket file is removed");
    let _ = std::fs::remove_dir_all(&dir);
}
