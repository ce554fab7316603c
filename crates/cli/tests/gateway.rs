//! The CiA 309-3 gateway against lines exactly as CANopenLinux's `cocomm`
//! sends them (`[<seq>] <node> <command>` + LF over a TCP socket; comment
//! and empty lines from files), checking every answer; the same on stdin;
//! PDO configuration as Lely's `coctl` writes it.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::Duration;

use common::Serve;

struct Gateway {
    child: Child,
    port: u16,
}

impl Drop for Gateway {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn gateway(url: &str, node: Option<&str>) -> Gateway {
    let mut cmd = std::process::Command::new(common::bin());
    cmd.args(["--bus", url, "--timeout", "500"]);
    if let Some(n) = node {
        cmd.args(["--node", n]);
    }
    let mut child = cmd
        .args(["gateway", "--listen", "127.0.0.1:0"])
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let port = line
        .trim()
        .rsplit(':')
        .next()
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("ready line: {line}"));
    Gateway { child, port }
}

/// One request as cocomm writes it, and the whole answer (up to CR LF).
fn ask(s: &mut TcpStream, line: &str) -> String {
    s.write_all(format!("{line}\n").as_bytes()).unwrap();
    let mut got = Vec::new();
    let mut b = [0u8; 1];
    while !got.ends_with(b"\r\n") {
        assert_eq!(s.read(&mut b).unwrap(), 1, "gateway closed after {got:?}");
        got.push(b[0]);
    }
    String::from_utf8(got).unwrap()
}

#[test]
fn cocomm_lines_and_every_answer() {
    let srv = Serve::start(&["--drive", "generic:4"], None);
    let gw = gateway(&srv.url(), None);
    let mut s = TcpStream::connect(("127.0.0.1", gw.port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let mut check = |line: &str, want: &str| {
        let got = ask(&mut s, line);
        assert!(got.starts_with(want) && got.ends_with("\r\n"), "{line:?}: got {got:?}, want {want:?}...");
        got
    };
    // SDO: what `cocomm "4 write 0x1017 0 u16 500"` sends is "[1] 4 write ...".
    check("[1] 4 write 0x1017 0 u16 500", "[1] OK\r\n");
    check("[2] 4 read 0x1017 0 u16", "[2] 500\r\n");
    check("[3] 4 r 0x1000 0 x32", "[3] 0x00020192\r\n");
    check("[4] 4 read 0x1000 0", "[4] 92 01 02 00\r\n");
    check("[5] 4 read 0x1008 0 vs", "[5] \"drivebus generic servo\"\r\n");
    check("[6] 4 w 0x2002 0 i32 -5", "[6] ERROR:0x0602000");
    check("[7] 4 read 0x2FFF 0 u8", "[7] ERROR:0x06020000 #");
    check("[8] 4 write 0x1000 0 u32 1", "[8] ERROR:0x06010002 #");
    check("[9] 4 read 0x1017 0 u32", "[9] ERROR:0x06070010");
    // Numbers as strtoul reads them: decimal 4119 = 0x1017.
    check("[10] 4 read 4119 0 u16", "[10] 500\r\n");
    // Defaults and settings.
    check("[11] read 0x1000 0 u32", "[11] ERROR:105 #");
    check("[12] set node 4", "[12] OK\r\n");
    check("[13] r 0x1000 0 u32", "[13] 131474\r\n");
    check("[14] set sdo_timeout 100", "[14] OK\r\n");
    check("[15] 99 read 0x1000 0 u32", "[15] ERROR:0x05040000 #");
    check("[16] set network 1", "[16] OK\r\n");
    check("[17] 2 4 read 0x1000 0 u32", "[17] ERROR:106 #");
    // NMT.
    check("[18] 4 preop", "[18] OK\r\n");
    check("[19] 4 start", "[19] OK\r\n");
    check("[20] 0 stop", "[20] OK\r\n");
    check("[21] 4 reset comm", "[21] OK\r\n");
    std::thread::sleep(Duration::from_millis(100));
    check("[22] 4 preoperational", "[22] OK\r\n");
    // Errors exactly as CiA 309-3 numbers them.
    check("[23] 200 start", "[23] ERROR:107 #");
    check("[24] 4 frobnicate", "[24] ERROR:100 #");
    check("4 read 0x1000 0 u32", "[0] ERROR:101 #");
    check("[25] 4 read 0x1000", "[25] ERROR:101 #");
    check("[26] 4 read 0x1000 0 u99", "[26] ERROR:101 #");
    check("[27] reset", "[27] ERROR:101 #");
    // Empty lines and comments (cocomm sends them from files) get an empty answer.
    check("", "\r\n");
    check("# a comment", "\r\n");
    // Reset communication brought 1017h back to its default.
    check("[28] 4 read 0x1017 0 u16 # trailing comment", "[28] 0\r\n");
    check("[29] info version", "[29] 0 0 ");
    check("[30] help", "\nCommand strings");
    check("[31] lss_switch_glob 0", "[31] OK\r\n");
    check("[32] _lss_fastscan 20", "[32] ERROR:103 #");
    // PDOs as coctl configures them: the gateway's TPDO 1 is node 4's RPDO1
    // (controlword), its RPDO 1 node 4's TPDO1 (statusword).
    check("[33] set tpdo 1 0x204 255 1 0x6040 0 u16", "[33] OK\r\n");
    check("[34] set rpdo 1 0x184 255 1 0x6041 0 u16", "[34] OK\r\n");
    check("[35] 4 start", "[35] OK\r\n");
    std::thread::sleep(Duration::from_millis(100));
    check("[36] w p 1 1 6", "[36] OK\r\n");
    std::thread::sleep(Duration::from_millis(200));
    check("[37] 4 read 0x6041 0 x16", "[37] 0x0");
    let sw = check("[38] 4 read 0x6041 0 u16", "[38] ");
    let sw: u16 = sw.trim().rsplit(' ').next().unwrap().parse().unwrap();
    assert_eq!(sw & 0x6F, 0x21, "controlword 06h by the gateway's TPDO: ready to switch on");
    let pdo = check("[39] r p 1", "[39] 1 pdo 1 0x");
    assert!(pdo.contains(&format!("0x{sw:x}")), "{pdo} has the statusword {sw:x}");
    check("[40] w p 9 1 6", "[40] ERROR:102 #");
    check("[41] w p 1 2 6 7", "[41] ERROR:101 #");
    // Garbage never kills the gateway.
    for junk in ["[", "[]", "[1", "[x] start", "[42] \"", "[43] w 1 2 vs \"x", "\u{1}\u{2}\u{3}"] {
        check(junk, "[0] ERROR:101 #");
    }
    check("[44] 4 read 0x1000 0 u32", "[44] 131474\r\n");
}

#[test]
fn stdin_lines_and_a_default_node() {
    let srv = Serve::start(&["--drive", "generic:4"], None);
    let out = std::process::Command::new(common::bin())
        .args(["--bus", &srv.url(), "--node", "4", "gateway"])
        .env_remove("DRIVEBUS_BUS")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .and_then(|mut c| {
            c.stdin
                .take()
                .unwrap()
                .write_all(b"[1] read 0x1000 0 u32\r\n[2] 4 w 0x1017 0 u16 300\n\n[3] r 0x1017 0 u16\n")
                .unwrap();
            c.wait_with_output()
        })
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout), "[1] 131474\r\n[2] OK\r\n\r\n[3] 300\r\n");
}

/// With the real `cocomm` (CANopenLinux; `COCOMM=/path/to/cocomm`, or on
/// the PATH): its command-line form, its exit status and its split of
/// values (stdout) from statuses (stderr). Skipped, saying so, without it.
#[test]
fn the_real_cocomm_if_available() {
    let cocomm = std::env::var("COCOMM").unwrap_or_else(|_| "cocomm".into());
    if std::process::Command::new(&cocomm).arg("--help").stderr(Stdio::null()).status().is_err() {
        eprintln!(
            "skipped: no cocomm (set COCOMM=/path/to/cocomm, built from CANopenLinux's cocomm/cocomm.c)"
        );
        return;
    }
    let srv = Serve::start(&["--drive", "generic:4"], None);
    let gw = gateway(&srv.url(), None);
    let port = gw.port.to_string();
    let run = |args: &[&str]| {
        std::process::Command::new(&cocomm)
            .args(["-t", "127.0.0.1", "-p", &port, "-o", "data"])
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[
        "4 write 0x1017 0 u16 500",
        "4 read 0x1017 0 u16",
        "4 read 0x1000 0 x32",
        "4 read 0x1008 0 vs",
    ]);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(String::from_utf8_lossy(&out.stdout), "5000x00020192\"drivebus generic servo\"");
    let out = run(&["4 read 0x2FFF 0 u8"]);
    assert!(!out.status.success(), "an SDO abort is a failure for cocomm");
}

/// `lss_allnodes TIMEOUT FIRST STORE`, as cocomm sends it: every
/// unconfigured slave gets the next node-ID and answers SDO under it.
#[test]
fn lss_allnodes_numbers_every_unconfigured_slave() {
    let bus = common::LssBus::start(&[0x20, 0x10]);
    let gw = gateway(&bus.url, None);
    let mut s = TcpStream::connect(("127.0.0.1", gw.port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    // 25 ms per fastscan step: about 130 steps per slave found.
    let got = ask(&mut s, "[1] lss_allnodes 25 20 0");
    let slave = |serial: u32| format!("0x00000ABC 0x00000077 0x00000003 0x{serial:08X}");
    let assigned: Vec<&str> = got.lines().filter(|l| l.starts_with("# Node-ID")).collect();
    assert_eq!(assigned.len(), 2, "{got:?}");
    assert!(assigned.iter().any(|l| l.starts_with("# Node-ID 20 assigned to: ")), "{got:?}");
    assert!(assigned.iter().any(|l| l.starts_with("# Node-ID 21 assigned to: ")), "{got:?}");
    assert!(assigned.iter().any(|l| l.ends_with(&slave(0x10))), "{got:?}");
    assert!(assigned.iter().any(|l| l.ends_with(&slave(0x20))), "{got:?}");
    assert!(got.ends_with("# Found 2 nodes, search finished.\n[1] OK\r\n"), "{got:?}");
    // Each answers under the node-ID the gateway printed for its serial.
    for l in assigned {
        let node = &l["# Node-ID ".len()..l.find(" assigned").unwrap()];
        let serial = l.rsplit(' ').next().unwrap();
        let answer = ask(&mut s, &format!("[2] {node} read 0x1018 4 x32"));
        assert_eq!(answer, format!("[2] {serial}\r\n"), "node {node}");
    }
    // Nobody is left unconfigured.
    assert_eq!(ask(&mut s, "[3] lss_allnodes 25 30 0"), "# Found 0 nodes, search finished.\n[3] OK\r\n");
    drop(bus);
}
