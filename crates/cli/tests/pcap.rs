//! `dump --pcap FILE`: the capture Wireshark reads. tshark's own CAN and
//! CANopen dissectors decode it: NMT, SDO, PDO and heartbeat frames with
//! their COB-IDs and data. Skips (saying so) where tshark is missing,
//! unless `DRIVEBUS_REQUIRE_TSHARK` is set (`scripts/test` installs it).

mod common;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Duration;

use common::Serve;

fn db(url: &str, args: &[&str]) -> std::process::Output {
    let out = Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .output()
        .unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

fn tshark() -> bool {
    let found = Command::new("tshark").arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status();
    match found {
        Ok(s) if s.success() => true,
        _ if std::env::var_os("DRIVEBUS_REQUIRE_TSHARK").is_some() => {
            panic!("tshark is not installed (apt-get install tshark) and DRIVEBUS_REQUIRE_TSHARK is set")
        }
        _ => {
            let _ = writeln!(std::io::stderr(), "skipped: tshark is not installed (apt-get install tshark)");
            false
        }
    }
}

/// tshark's fields of every frame, CANopen decoding on: one Vec per frame.
fn fields(file: &std::path::Path, names: &[&str]) -> Vec<Vec<String>> {
    let mut cmd = Command::new("tshark");
    cmd.arg("-r").arg(file).args(["-d", "can.subdissector,canopen", "-T", "fields", "-E", "separator=|"]);
    for n in names {
        cmd.args(["-e", n]);
    }
    let out = cmd.output().unwrap();
    assert!(out.status.success(), "tshark: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).lines().map(|l| l.split('|').map(str::to_owned).collect()).collect()
}

#[test]
fn tshark_decodes_the_canopen_traffic_of_a_capture() {
    if !tshark() {
        return;
    }
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "write", "1017", "0", "50"]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bus.pcapng");
    let mut dump = Command::new(common::bin())
        .args(["--bus", &u, "dump", "--pcap"])
        .arg(&file)
        .args(["--seconds", "3"])
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(800));
    db(&u, &["--node", "5", "sdo", "read", "1018", "1"]);
    db(&u, &["send", "000#0105", "080#"]);
    db(&u, &["--node", "5", "drive", "enable"]);
    assert!(dump.wait().unwrap().success());
    let rows = fields(
        &file,
        &[
            "can.id",
            "can.flags.rtr",
            "canopen.function_code",
            "canopen.node_id",
            "canopen.nmt_ctrl.cd",
            "canopen.nmt_ctrl.node_id",
            "canopen.sdo.main_idx",
            "canopen.sdo.sub_idx",
            "canopen.sdo.data.bytes",
            "canopen.nmt_guard.state",
            "canopen.pdo.data.bytes",
            "_ws.col.Info",
        ],
    );
    let all = rows.iter().map(|r| r.join("|")).collect::<Vec<_>>().join("\n");
    let id = |r: &Vec<String>| r[0].clone();
    // The SDO request and the drive's answer: 1018h:01, the vendor-ID.
    assert!(
        rows.iter().any(|r| id(r) == "1541" && r[6] == "0x1018" && r[7] == "0x01"),
        "SDO request 605h for 1018h:01 decoded:\n{all}"
    );
    assert!(
        rows.iter().any(|r| id(r) == "1413" && r[6] == "0x1018" && r[7] == "0x01" && !r[8].is_empty()),
        "SDO response 585h decoded with its data:\n{all}"
    );
    // The NMT command and SYNC the tool sent, as the bus carried them.
    assert!(
        rows.iter().any(|r| id(r) == "0" && r[4] == "0x01" && r[5] == "0x05"),
        "NMT start node 5:\n{all}"
    );
    assert!(rows.iter().any(|r| id(r) == "128" && r[11].contains("SYNC")), "SYNC:\n{all}");
    // Heartbeats of node 5, operational after the start.
    assert!(
        rows.iter().any(|r| id(r) == "1797" && r[11].contains("NMT Error Control") && r[9] == "0x05"),
        "heartbeat of node 5 in operational:\n{all}"
    );
    // The drive's TPDO1 (statusword) once enabled: a PDO with its data.
    assert!(
        rows.iter().any(|r| id(r) == "389" && r[11].contains("PDO") && !r[10].is_empty()),
        "TPDO1 of node 5 decoded as a PDO:\n{all}"
    );
}

/// `--pcap -`: the capture on stdout (for `| wireshark -k -i -`), nothing else there.
#[test]
fn pcap_to_stdout() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "write", "1017", "0", "20"]);
    let out = db(&u, &["dump", "--pcap", "-", "--count", "3", "--seconds", "5"]).stdout;
    assert_eq!(&out[..4], &[0x0A, 0x0D, 0x0D, 0x0A], "a pcapng section header first");
    // Walk the blocks: three enhanced packet blocks (type 6), each a
    // 16-byte SocketCAN frame: 705h in network byte order, length 1.
    let mut at = 0;
    let mut frames = Vec::new();
    while at + 8 <= out.len() {
        let word = |i: usize| u32::from_le_bytes([out[i], out[i + 1], out[i + 2], out[i + 3]]) as usize;
        let (kind, len) = (word(at), word(at + 4));
        assert!(len >= 12 && at + len <= out.len(), "block at {at}: {out:02X?}");
        if kind == 6 {
            assert_eq!(word(at + 20), 16, "captured length");
            frames.push(out[at + 28..at + 44].to_vec());
        }
        at += len;
    }
    assert_eq!(at, out.len(), "nothing but pcapng blocks on stdout");
    assert_eq!(frames.len(), 3);
    for f in frames {
        assert_eq!(&f[..5], &[0, 0, 0x07, 0x05, 1], "{f:02X?}");
    }
    let e = Command::new(common::bin())
        .args(["--bus", &u, "dump", "--pcap", "-", "--candump", "--count", "1"])
        .output()
        .unwrap();
    assert!(!e.status.success() && String::from_utf8_lossy(&e.stderr).contains("--pcap -"));
}
