//! Every command, on the in-process virtual bus (`--bus virtual --sim ...`)
//! or against a `drivebus serve` child, with its error paths.

mod common;

use std::time::Duration;

use assert_cmd::Command;
use predicates::prelude::*;
use predicates::str::contains;

/// `drivebus ARGS` with a time limit.
fn db(args: &[&str]) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(60))
        .assert()
}

const AKD: [&str; 4] = ["--bus", "virtual", "--sim", "akd:1"];

fn with(base: &[&str], rest: &[&str]) -> Vec<String> {
    base.iter().chain(rest).map(|s| s.to_string()).collect()
}

fn dbv(args: Vec<String>) -> assert_cmd::assert::Assert {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    db(&refs)
}

#[test]
fn help_everywhere_has_examples() {
    db(&["--help"]).success().stdout(contains("Examples:").and(contains("serve")));
    for cmd in [
        vec!["serve"],
        vec!["demo"],
        vec!["sdo"],
        vec!["pdo"],
        vec!["drive"],
        vec!["eds"],
        vec!["lss"],
        vec!["scan"],
        vec!["sdo", "read"],
        vec!["sdo", "write"],
        vec!["sdo", "upload"],
        vec!["sdo", "download"],
        vec!["nmt"],
        vec!["pdo", "show"],
        vec!["pdo", "map"],
        vec!["drive", "status"],
        vec!["drive", "enable"],
        vec!["drive", "disable"],
        vec!["drive", "move"],
        vec!["drive", "velocity"],
        vec!["drive", "torque"],
        vec!["drive", "home"],
        vec!["drive", "quickstop"],
        vec!["drive", "reset"],
        vec!["dump"],
        vec!["monitor"],
        vec!["send"],
        vec!["produce"],
        vec!["gen"],
        vec!["stats"],
        vec!["eds", "check"],
        vec!["eds", "show"],
        vec!["eds", "export"],
        vec!["lss", "scan"],
        vec!["lss", "set-node-id"],
        vec!["slcan-pty"],
    ] {
        let mut a = cmd.clone();
        a.push("--help");
        db(&a).success().stdout(contains("Examples:"));
    }
}

#[test]
fn bad_urls_and_unreachable_servers_are_named() {
    db(&["--bus", "foo://x", "scan"])
        .failure()
        .stderr(contains("bad bus URL `foo://x`").and(contains("unknown scheme")));
    db(&["--bus", "can0", "--node", "1", "sdo", "read", "0x1000"])
        .failure()
        .stderr(contains("expected SCHEME://"));
    let port = common::free_port();
    let url = format!("socketcand://127.0.0.1:{port}/can0");
    db(&["--bus", &url, "scan"]).failure().stderr(contains("cannot open").and(contains(url.as_str())));
    db(&["--bus", "socketcan://can0", "scan"]).failure().stderr(contains("socketcan://can0"));
    db(&["--bus", "slcan:///dev/nonexistent-tty?bitrate=1000000", "--node", "1", "sdo", "read", "0x1000"])
        .failure()
        .stderr(
            contains("cannot open `slcan:///dev/nonexistent-tty?bitrate=1000000`")
                .and(contains("No such file")),
        );
    db(&["--bus", "socketcand://127.0.0.1:1/can0", "--sim", "akd:1", "scan"])
        .failure()
        .stderr(contains("--sim hosts drives only on the `virtual` bus"));
}

#[test]
fn scan_finds_the_virtual_drives() {
    db(&["--sim", "akd:1", "--sim", "dds6:2", "scan"])
        .success()
        .stdout(contains("0x00020192").and(contains("0x00440192")).and(contains("M006")));
    let out =
        db(&["--sim", "akd:1", "--sim", "kc1:7", "--json", "scan"]).success().get_output().stdout.clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let nodes: Vec<u64> =
        j["nodes"].as_array().unwrap().iter().map(|n| n["node"].as_u64().unwrap()).collect();
    assert_eq!(nodes, [1, 7]);
    db(&["--bus", "virtual://empty", "scan", "--wait", "50"]).success().stdout(contains("no node answered"));
    db(&["scan", "--from", "9", "--to", "3"]).failure().stderr(contains("--from 9 is above --to 3"));
}

#[test]
fn sdo_read_values_types_and_errors() {
    dbv(with(&AKD, &["--node", "1", "sdo", "read", "0x1000", "0"]))
        .success()
        .stdout(contains("1000h:00 Device type = 131474 (0x00020192) [UNSIGNED32]"));
    dbv(with(&AKD, &["--node", "1", "sdo", "read", "1008h", "--type", "str"]))
        .success()
        .stdout(contains("M006"));
    let out = dbv(with(&AKD, &["--node", "1", "--json", "sdo", "read", "0x1000", "0", "--type", "u32"]))
        .success()
        .get_output()
        .stdout
        .clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(j["value"], 0x20192);
    assert_eq!(j["type"], "UNSIGNED32");
    // No such node: the SDO timeout, named.
    dbv(with(&AKD, &["--node", "9", "--timeout", "200", "sdo", "read", "0x1000", "0"]))
        .failure()
        .stderr(contains("node 9: SDO read 1000h:00 timed out: no response within 200 ms"));
    // SDO abort: code and meaning.
    dbv(with(&AKD, &["--node", "1", "sdo", "read", "0x2FFF", "0x7F"]))
        .failure()
        .stderr(contains("0x06020000").and(contains("Object does not exist")));
    dbv(with(&AKD, &["--node", "1", "sdo", "read", "0xZZ"])).failure().stderr(contains("is not an object"));
    dbv(with(&AKD, &["--node", "1", "sdo", "read", "0x1000", "0", "--type", "u17"]))
        .failure()
        .stderr(contains("unknown type `u17`"));
    dbv(with(&AKD, &["sdo", "read", "0x1000"])).failure().stderr(contains("needs --node"));
    db(&["--node", "0", "sdo", "read", "0x1000"]).failure().stderr(contains("--node"));
}

#[test]
fn sdo_write_typed_and_by_eds() {
    dbv(with(&AKD, &["--node", "1", "sdo", "write", "0x1017", "0", "100", "--type", "u16"]))
        .success()
        .stdout(contains("wrote 1017h:00 = 100"));
    // Standard objects are typed without --type or an EDS (CiA 301: UNSIGNED16).
    dbv(with(&AKD, &["--node", "1", "sdo", "write", "0x1017", "0", "100"]))
        .success()
        .stdout(contains("UNSIGNED16"));
    dbv(with(&AKD, &["--node", "1", "sdo", "write", "0x2FFF", "0", "100"]))
        .failure()
        .stderr(contains("give --type"));
    dbv(with(&AKD, &["--node", "1", "sdo", "write", "0x1017", "0", "abc", "--type", "u16"]))
        .failure()
        .stderr(contains("bad value"));
    dbv(with(&AKD, &["--node", "1", "sdo", "write", "0x1000", "0", "5", "--type", "u32"]))
        .failure()
        .stderr(contains("0x06010002").and(contains("read only")));
    // Names and types from an EDS file.
    let dir = tempfile::tempdir().unwrap();
    let eds = dir.path().join("akd.eds");
    db(&["eds", "export", "--profile", "akd", "--out", eds.to_str().unwrap()]).success();
    let e = eds.to_str().unwrap();
    dbv(with(&AKD, &["--node", "1", "--eds", e, "sdo", "write", "0x1017", "0", "250"]))
        .success()
        .stdout(contains("UNSIGNED16"));
    dbv(with(&AKD, &["--node", "1", "--eds", e, "sdo", "read", "0x1000", "0"]))
        .success()
        .stdout(contains("[UNSIGNED32]").and(contains("131474")));
    db(&["--eds", "/nonexistent.eds", "--node", "1", "sdo", "read", "0x1000"])
        .failure()
        .stderr(contains("cannot read EDS file"));
}

#[test]
fn sdo_upload_and_download_files() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("name.bin");
    dbv(with(&AKD, &["--node", "1", "sdo", "upload", "0x1008", "0", f.to_str().unwrap()]))
        .success()
        .stdout(contains("read 4 bytes"));
    assert_eq!(std::fs::read(&f).unwrap(), b"M006");
    let hb = dir.path().join("hb.bin");
    std::fs::write(&hb, 300u16.to_le_bytes()).unwrap();
    dbv(with(&AKD, &["--node", "1", "sdo", "download", "0x1017", "0", hb.to_str().unwrap()]))
        .success()
        .stdout(contains("wrote 2 bytes"));
    let big = dir.path().join("big.bin");
    std::fs::write(&big, vec![0x55u8; 300]).unwrap();
    dbv(with(&AKD, &["--node", "1", "sdo", "download", "0x1017", "0", big.to_str().unwrap(), "--block"]))
        .failure()
        .stderr(contains("SDO write 1017h:00"));
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    dbv(with(&AKD, &["--node", "1", "sdo", "download", "0x1017", "0", empty.to_str().unwrap()]))
        .failure()
        .stderr(contains("is empty"));
    dbv(with(&AKD, &["--node", "1", "sdo", "download", "0x1017", "0", "/nonexistent.bin"]))
        .failure()
        .stderr(contains("cannot read"));
    dbv(with(
        &AKD,
        &["--node", "5", "--timeout", "200", "sdo", "upload", "0x1008", "0", f.to_str().unwrap()],
    ))
    .failure()
    .stderr(contains("timed out"));
}

#[test]
fn nmt_commands_confirm_or_explain() {
    dbv(with(&AKD, &["--node", "1", "nmt", "reset"])).success().stdout(contains("boot-up received"));
    dbv(with(&AKD, &["--node", "1", "nmt", "reset-comm"])).success().stdout(contains("boot-up received"));
    dbv(with(&AKD, &["--node", "1", "nmt", "start"])).success().stdout(contains("node answers SDO"));
    dbv(with(&AKD, &["--node", "1", "nmt", "preop"])).success();
    dbv(with(&AKD, &["--node", "1", "nmt", "stop"])).success().stdout(contains("NMT stop sent to node 1"));
    dbv(with(&AKD, &["nmt", "start", "--all"])).success().stdout(contains("all nodes"));
    dbv(with(&AKD, &["nmt", "start"])).failure().stderr(contains("give --node N or --all"));
    dbv(with(&AKD, &["--node", "4", "--timeout", "200", "nmt", "reset"]))
        .failure()
        .stderr(contains("no boot-up message"));
    dbv(with(&AKD, &["--node", "4", "--timeout", "200", "nmt", "start"]))
        .failure()
        .stderr(contains("timed out"));
    dbv(with(&AKD, &["--node", "1", "nmt", "sleep"])).failure().stderr(contains("invalid value"));
}

#[test]
fn pdo_show_and_map() {
    dbv(with(&AKD, &["--node", "1", "pdo", "show"]))
        .success()
        .stdout(contains("RPDO1").and(contains("TPDO1")).and(contains("6041h:00")));
    let out =
        dbv(with(&AKD, &["--node", "1", "--json", "pdo", "show"])).success().get_output().stdout.clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert!(j["pdos"].as_array().unwrap().len() >= 2);
    dbv(with(&AKD, &["--node", "1", "pdo", "map", "tpdo", "2", "0x6041:0:16", "0x6064:0:32", "--type", "1"]))
        .success()
        .stdout(contains("TPDO2 mapped 2 entries"));
    // An object alone takes its size from the dictionary.
    dbv(with(&AKD, &["--node", "1", "pdo", "map", "tpdo", "2", "statusword", "6064"]))
        .success()
        .stdout(contains("TPDO2 mapped 2 entries"));
    dbv(with(&AKD, &["--node", "1", "pdo", "map", "tpdo", "2", "6041:0:99"]))
        .failure()
        .stderr(contains("BITS must be 1..64"));
    dbv(with(&AKD, &["--node", "1", "pdo", "map", "tpdo", "2", "2FFF"]))
        .failure()
        .stderr(contains("INDEX:SUB:BITS"));
    dbv(with(&AKD, &["--node", "1", "pdo", "map", "rpdo", "1", "0x1000:0:32"]))
        .failure()
        .stderr(contains("SDO write 1600h:01").and(contains("0x0604")).and(contains("in force again")));
    dbv(with(&AKD, &["--node", "6", "--timeout", "200", "pdo", "show"]))
        .failure()
        .stderr(contains("timed out"));
}

#[test]
fn eds_check_show_export() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("kc1.eds");
    db(&["eds", "export", "--profile", "kc1", "-o", good.to_str().unwrap()])
        .success()
        .stdout(contains("wrote"));
    db(&["eds", "check", good.to_str().unwrap()]).success().stdout(contains("0 error(s)"));
    let bad = dir.path().join("bad.eds");
    std::fs::write(
        &bad,
        "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x20192\n\n[1017]\nParameterName=HB\nObjectType=0x7\nDataType=0x0006\nAccessType=zz\n",
    )
    .unwrap();
    db(&["eds", "check", bad.to_str().unwrap()]).code(1).stdout(contains("error"));
    let out = db(&["--json", "eds", "check", bad.to_str().unwrap()]).code(1).get_output().stdout.clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert!(j["errors"].as_u64().unwrap() > 0);
    db(&["eds", "check", "/nonexistent.eds"]).failure().stderr(contains("cannot read EDS file"));
    db(&["eds", "show", "--profile", "akd"]).success().stdout(contains("6041").and(contains("UNSIGNED16")));
    db(&["eds", "show", good.to_str().unwrap()]).success().stdout(contains("1000"));
    db(&["eds", "show", "--profile", "nope"]).failure().stderr(contains("unknown profile `nope`"));
    db(&["eds", "show"]).failure().stderr(contains("give a file"));
    db(&["eds", "export", "--profile", "dds6"]).success().stdout(contains("[1000]"));
    db(&["--eds", good.to_str().unwrap(), "eds", "export"]).success().stdout(contains("[1000]"));
    db(&["eds", "export"]).failure().stderr(contains("nothing to export"));
    // Over the bus: 1021h; the virtual drives have none, which is named.
    dbv(with(&AKD, &["--node", "1", "eds", "export"])).failure().stderr(contains("1021h"));
    db(&["--sim", "generic:5", "--node", "5", "eds", "export"]).success().stdout(contains("[1000]"));
}

#[test]
fn lss_scan_and_set_node_id_errors() {
    db(&["--sim", "generic:5", "--timeout", "100", "lss", "scan"])
        .success()
        .stdout(contains("no unconfigured LSS slave"));
    db(&["--sim", "akd:1", "--timeout", "200", "lss", "set-node-id", "9"])
        .failure()
        .stderr(contains("no LSS slave answered"));
    db(&["lss", "set-node-id", "9", "--vendor", "1"]).failure().stderr(contains("give all of"));
    db(&["lss", "set-node-id", "0"]).failure();
}

#[test]
fn demo_runs_and_writes_the_plot() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("demo.svg");
    db(&["demo", "--no-progress", "--sine-seconds", "0.5", "--out", svg.to_str().unwrap()])
        .success()
        .stdout(contains("following error RMS").and(contains("frames on the bus")).and(contains("bus load")));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg") && text.contains("Node 1 following error"));
    // Node 2 on its own axis in its own units; the phases named.
    assert!(text.contains("Node 2 (DDS6) position") && text.contains("position units"));
    for phase in ["homing", "move", "CSP sine"] {
        assert!(text.contains(&format!(">\n{phase}\n</text>")), "phase {phase} marked");
    }
    let out = db(&["--json", "demo", "--sine-seconds", "0.2", "--out", svg.to_str().unwrap()])
        .success()
        .get_output()
        .stdout
        .clone();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(j["csp"]["cycles"], 200);
    assert!(j["move"]["seconds"].as_f64().unwrap() > 0.0);
    db(&["demo", "--realtime", "--no-progress", "--sine-seconds", "0.1", "--out", svg.to_str().unwrap()])
        .success()
        .stdout(contains("100 cycles"));
    db(&["demo", "--sine-seconds", "0"]).failure().stderr(contains("--sine-seconds"));
    db(&["demo", "--sine-seconds", "0.2", "--out", "/nonexistent/dir/x.svg"])
        .failure()
        .stderr(contains("cannot write the plot"));
}
