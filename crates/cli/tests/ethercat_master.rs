//! The EtherCAT master commands against `drivebus ethercat serve`: the
//! test creates a network namespace and a veth pair, serves an iPOS and a
//! generic servo on the root-namespace end, and runs `drivebus ethercat
//! scan|sdo|state|pdo|drive` inside the namespace (ethercrab's raw socket
//! on the other end): text and `--json`, an SDO abort with its code, a
//! refused AL state with its code, the PDO mapping, and a drive enabled
//! and moved with the position read back.
//!
//! Needs root (CAP_NET_ADMIN, CAP_NET_RAW) and `ip`. When the namespace
//! cannot be created the test prints exactly why and stops; the
//! namespace, the link and the server are removed even when it fails.

use std::io::{BufRead, BufReader};
use std::process::{Command, Output, Stdio};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_drivebus")
}

mod netns;
use netns::VethPair as Line;

impl Line {
    fn new(drives: &[&str]) -> Result<Line, String> {
        let mut l = Line::create("dbem")?;
        let mut cmd = Command::new(bin());
        cmd.args(["ethercat", "serve", "--iface", &l.outer]);
        for d in drives {
            cmd.args(["--drive", d]);
        }
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("spawn serve: {e}"))?;
        let mut ready = String::new();
        BufReader::new(child.stdout.take().ok_or("no stdout")?)
            .read_line(&mut ready)
            .map_err(|e| e.to_string())?;
        l.serve = Some(child);
        if !ready.contains(&format!("ready on {}", l.outer)) {
            panic!("serve did not get ready: {ready:?}");
        }
        Ok(l)
    }

    /// `drivebus ethercat ARGS --iface INNER` inside the namespace.
    fn run(&self, args: &[&str]) -> Output {
        let out = Command::new("ip")
            .args(["netns", "exec", &self.ns, bin(), "ethercat"])
            .args(args)
            .args(["--iface", &self.inner])
            .stdin(Stdio::null())
            .output()
            .expect("run drivebus");
        println!(
            "$ drivebus ethercat {}\n{}{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        out
    }

    fn ok(&self, args: &[&str]) -> String {
        let out = self.run(args);
        assert!(
            out.status.success(),
            "`{}` failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    fn json(&self, args: &[&str]) -> serde_json::Value {
        let mut a = args.to_vec();
        a.push("--json");
        let text = self.ok(&a);
        serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
    }

    /// A command that must fail with exit status 1: (stdout, stderr).
    fn fails(&self, args: &[&str]) -> (String, String) {
        let out = self.run(args);
        assert_eq!(out.status.code(), Some(1), "`{}` must fail with 1", args.join(" "));
        (String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

#[test]
fn master_commands_against_served_drives_over_veth() {
    let line = match Line::new(&["ipos", "generic"]) {
        Ok(l) => l,
        Err(why) => {
            println!("SKIPPED master_commands_against_served_drives_over_veth: {why}");
            return;
        }
    };
    // scan: the state found first (nobody initialised the line), identity
    // from the SII and over CoE.
    let j = line.json(&["scan"]);
    let s = j["slaves"].as_array().expect("slaves");
    assert_eq!(s.len(), 2, "{j}");
    assert_eq!(s[0]["position"], 1);
    assert_eq!(s[0]["state"], "INIT");
    assert_eq!(s[0]["name"], "iPOS360x VX-CAT");
    assert_eq!(s[0]["vendor_id"], 0x1A3);
    assert_eq!(s[0]["revision"], 0x4130_3047u32);
    assert_eq!(s[0]["coe_identity"]["vendor_id"], 0x1A3);
    assert_eq!(s[0]["serial"], 1);
    assert_eq!(s[0]["address"], 0x1000);
    assert!(s[0]["mailbox"].as_array().unwrap().contains(&"FoE".into()), "{j}");
    assert_eq!(s[1]["name"], "drivebus generic CiA 402 servo");
    assert_eq!(s[1]["serial"], 2);
    let text = line.ok(&["scan"]);
    assert!(text.lines().nth(1).unwrap().starts_with("1    0x1000  0      0x000001A3"), "{text}");
    assert!(text.contains("PRE-OP   CoE,FoE  iPOS360x VX-CAT"), "{text}");

    // CoE.
    let v = line.json(&["sdo", "read", "--slave", "1", "1018", "1"]);
    assert_eq!((v["slave"].as_u64(), v["value"].as_u64()), (Some(1), Some(0x1A3)), "{v}");
    let text = line.ok(&["sdo", "read", "--slave", "1", "0x1018:02"]);
    assert_eq!(text.trim(), "1018h:02 Identity object / Product code = 28002021 (0x01AB46E5) [UNSIGNED32]");
    let text = line.ok(&["sdo", "read", "--slave", "1", "1008"]);
    assert_eq!(text.trim(), "1008h:00 Manufacturer device name = iPOS [VISIBLE_STRING]");
    // Issue 15: the whole PDO assignment array, every entry named and
    // typed by the slave's SDO Information, read by complete access.
    let text = line.ok(&["sdo", "read", "--slave", "1", "1C13"]);
    let a = "1C13h:0{} Sync Manager Channel 3 (Process Data Input) / ";
    let b = "Sync Manager Channel 3: PDO Mapping object index of assigned TxPDO";
    let want = [
        format!("{}Number of entries = 2 (0x02) [UNSIGNED8]", a.replace("{}", "0")),
        format!("{}{b} (1st) = 6656 (0x1A00) [UNSIGNED16]", a.replace("{}", "1")),
        format!("{}{b} (2nd) = 6657 (0x1A01) [UNSIGNED16]", a.replace("{}", "2")),
    ];
    assert_eq!(text.lines().collect::<Vec<_>>(), want, "{text}");
    let j = line.json(&["sdo", "read", "--slave", "1", "1C13"]);
    assert_eq!(
        (j["names_from"].as_str(), j["complete_access"].as_bool()),
        (Some("sdo_info"), Some(true)),
        "{j}"
    );
    assert_eq!((j["object_code"].as_str(), j["slave"].as_u64()), (Some("ARRAY"), Some(1)), "{j}");
    let e = &j["entries"][2];
    assert_eq!(
        (e["sub"].as_u64(), e["value"].as_u64(), e["type"].as_str()),
        (Some(2), Some(0x1A01), Some("UNSIGNED16"))
    );
    assert_eq!((e["access"].as_str(), e["bits"].as_u64()), (Some("rw"), Some(16)), "{j}");
    // A record: the identity, names from the slave.
    let j = line.json(&["sdo", "read", "--slave", "2", "1018"]);
    assert_eq!(j["object_code"], "RECORD", "{j}");
    let e = j["entries"].as_array().unwrap();
    assert_eq!(e.len(), 5, "{j}");
    assert_eq!(
        (e[4]["name"].as_str(), e[4]["value"].as_u64()),
        (Some("Identity object / Serial number"), Some(2))
    );
    assert_eq!(e[4]["access"], "ro");
    line.ok(&["sdo", "write", "--slave", "2", "6081h", "123456"]);
    assert_eq!(line.json(&["sdo", "read", "--slave", "2", "profile velocity"])["value"], 123456);
    let (_, err) = line.fails(&["sdo", "read", "--slave", "1", "5FFF"]);
    assert!(
        err.contains(
            "slave 1: SDO read 5FFFh:00 aborted by the device with code 0x06020000: Object does not exist"
        ),
        "{err}"
    );
    let (out, _) = line.fails(&["sdo", "write", "--slave", "1", "1008", "0", "abc", "--json"]);
    let e: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(e["error"]["code"], "sdo_abort", "{e}");
    assert!(e["error"]["message"].as_str().unwrap().contains("0x06010002"), "{e}");
    let (_, err) = line.fails(&["sdo", "read", "--slave", "3", "1000"]);
    assert!(err.contains("there is no slave 3: the line has 2"), "{err}");

    // AL state: shown, refused with its code, requested.
    line.ok(&["state", "--slave", "1", "init"]);
    let (out, _) = line.fails(&["state", "--slave", "1", "--direct", "safeop", "--json"]);
    let e: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(e["error"]["code"], "al_refused", "{e}");
    assert_eq!(
        e["error"]["message"],
        "slave 1: SAFE-OP refused, stays in INIT: AL status code 0x0011 Invalid requested state change"
    );
    let (_, err) = line.fails(&["state", "--slave", "2", "--direct", "boot"]);
    assert!(err.contains("AL status code 0x0013 Bootstrap not supported"), "{err}");
    let st = line.json(&["state"]);
    assert_eq!(st["slaves"][0]["state"], "INIT", "{st}");
    assert_eq!(st["slaves"][0]["error"], false, "the refusal was acknowledged: {st}");
    let text = line.ok(&["state", "op"]);
    assert_eq!(text, "slave 1: OP\nslave 2: OP\n");
    line.ok(&["state", "preop"]);
    assert_eq!(line.json(&["state", "--slave", "2"])["slaves"][0]["state"], "PRE-OP");

    // PDOs: the iPOS default assignment (§2.3).
    let text = line.ok(&["pdo", "show", "--slave", "1"]);
    for want in [
        "RxPDO 1600h (1C12h:01)",
        "    6040h:00 16 bits  Controlword",
        "    607Ah:00 32 bits  Target position",
        "TxPDO 1A00h (1C13h:01)",
        "    6041h:00 16 bits  Statusword",
        "TxPDO 1A01h (1C13h:02)",
        "    60F4h:00 32 bits  Following error actual value",
        "outputs 6 bytes (RxPDOs), inputs 16 bytes (TxPDOs)",
    ] {
        assert!(text.contains(want), "{want}:\n{text}");
    }
    let p = line.json(&["pdo", "show", "--slave", "1"]);
    assert_eq!(p["rx"][0]["pdo"], 0x1600);
    assert_eq!(p["tx"][0]["entries"][1]["index"], 0x6064);
    assert_eq!(p["tx"][0]["entries"][1]["bits"], 32);
    assert_eq!((p["output_bytes"].as_u64(), p["input_bytes"].as_u64()), (Some(6), Some(16)));

    // The drive over process data with DC: enable, home, move; the
    // position read back over CoE afterwards.
    let text = line.ok(&["drive", "--slave", "1", "enable"]);
    assert!(text.starts_with("slave 1: operation enabled (statusword"), "{text}");
    assert!(text.contains("DC SYNC0 every 1000 µs"), "{text}");
    let text = line.ok(&["drive", "--slave", "1", "home", "--method", "35"]);
    assert_eq!(text.trim(), "slave 1: homing attained (method 35), position 0");
    let m = line.json(&["drive", "--slave", "1", "move", "5000", "--velocity", "200000"]);
    let at = m["position"].as_i64().unwrap();
    assert!((at - 5000).abs() <= 10, "{m}");
    let read = line.json(&["sdo", "read", "--slave", "1", "6064"])["value"].as_i64().unwrap();
    assert!((read - 5000).abs() <= 10, "6064h after the move: {read}");
    let st = line.json(&["drive", "--slave", "1", "status"]);
    assert_eq!(st["mode"], 1, "profile position: {st}");
    assert!((st["position"].as_i64().unwrap() - 5000).abs() <= 10, "{st}");
    // A move that cannot finish in time is halted, and the tool says so.
    let (out, _) = line.fails(&[
        "drive",
        "--slave",
        "1",
        "move",
        "900000",
        "--velocity",
        "1000",
        "--wait",
        "0.3",
        "--json",
    ]);
    let e: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(e["error"]["code"], "drive_timeout", "{e}");
    // Halted, or (a cycle lost on a loaded host ends the halt's wait)
    // quick-stopped: either way stopped, and said so.
    let msg = e["error"]["message"].as_str().unwrap();
    assert!(msg.contains("halted") || msg.contains("quick stop sent"), "{e}");
    // A csp sine, one target per 1 ms DC cycle.
    let c = line.json(&["drive", "--slave", "1", "csp-sine", "--amplitude", "500", "--seconds", "0.5"]);
    assert_eq!((c["cycles"].as_u64(), c["bad_wkc"].as_u64()), (Some(500), Some(0)), "{c}");
    assert!(c["max_following"].as_i64().unwrap() < 2000, "within the 6065h window: {c}");
    // Ctrl-C during a move: halted, and said so.
    let child = Command::new("ip")
        .args(["netns", "exec", &line.ns, bin(), "ethercat", "drive", "--iface", &line.inner, "--slave", "1"])
        .args(["move", "900000", "--velocity", "1000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(2500));
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "interrupted: 128 + SIGINT: {err}");
    assert!(
        err.contains(
            "move to 900000: interrupted; the motion was halted (controlword bit 8) and the drive is at rest"
        ) || err.contains("move to 900000: interrupted; halt did not stop it: quick stop sent"),
        "{err}"
    );
    // The generic servo (its own mapping: 1602h/1A02h) moves too, in free run.
    let m = line.json(&["drive", "--slave", "2", "move", "-3000", "--velocity", "100000", "--free-run"]);
    assert!((m["position"].as_i64().unwrap() + 3000).abs() <= 10, "{m}");
}

#[test]
fn a_missing_interface_is_an_error_that_says_what_to_do() {
    let out = Command::new(bin()).args(["ethercat", "scan", "--iface", "nosuchif0"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot open nosuchif0"), "{err}");
    let out = Command::new(bin())
        .args(["ethercat", "sdo", "read", "--iface", "x", "--slave", "0", "1000"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a slave position"));
    let out = Command::new(bin())
        .args(["ethercat", "state", "--iface", "x", "running", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(e["error"]["code"], "usage");
}

/// Each `drive` command is a new master: the line left OP when the last one
/// ended, so the next `enable` resets the iPOS's fault, and the drive (in
/// DC mode) puts the emergency of that reset into its send mailbox on a
/// SYNC0 step, any time between ethercrab's check that the mailbox is
/// empty and the SDO that follows. ethercrab 0.7.1 reads the emergency as
/// the SDO's answer ("Invalid decoded value"); the master sends the SDO
/// again. Failed about one time in three before that, so it runs eight
/// times.
#[test]
fn enable_then_home_survives_the_emergency_of_the_fault_reset() {
    let line = match Line::new(&["ipos"]) {
        Ok(l) => l,
        Err(why) => {
            println!("SKIPPED enable_then_home_survives_the_emergency_of_the_fault_reset: {why}");
            return;
        }
    };
    for _ in 0..8 {
        line.ok(&["drive", "--slave", "1", "enable"]);
        let text = line.ok(&["drive", "--slave", "1", "home", "--method", "35"]);
        assert!(text.contains("homing attained (method 35)"), "{text}");
    }
}
