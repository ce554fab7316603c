//! `drivebus serve --device FILE:NODE` and `--sim FILE:NODE`: a device
//! from its EDS or DCF beside the drives — the CiA 401 module of
//! `crates/cia401/eds/io16.eds` and third-party files
//! (`tests/vectors/eds/`) — read with `sdo read`; a malformed file is
//! refused before anything starts, with its file, line and cause.

mod common;

use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, connect, sdo_read, sdo_write};
use predicates::prelude::*;
use predicates::str::contains;

fn root(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn io16() -> String {
    root("crates/cia401/eds/io16.eds")
}

fn cli(args: &[&str]) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(60))
        .assert()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cia401_module_beside_a_drive() {
    let io = format!("{}:3", io16());
    let mut srv = Serve::start(&["--drive", "generic:1", "--device", &io], None);
    assert!(
        srv.line.contains("drives generic:1; devices ") && srv.line.contains("io16.eds:3 (CiA 401)"),
        "{}",
        srv.line
    );
    let url = srv.url();
    cli(&["--bus", &url, "--node", "3", "sdo", "read", "1000"]).success().stdout(contains("0x000F0191"));
    // An output written over SDO is what 6200h reads.
    let mut bus = connect(&url).await;
    assert_eq!(sdo_write(&mut bus, 3, 0x6200, 1, &[0x5A]).await, Ok(()));
    assert_eq!(sdo_read(&mut bus, 3, 0x6200, 1).await, Ok(0x5A));
    assert_eq!(sdo_read(&mut bus, 1, 0x1000, 0).await, Ok(0x0002_0192), "the drive beside it");
    drop(bus);
    // With the file, `sdo read` names and types the whole array.
    let eds = io16();
    cli(&["--bus", &url, "--eds", &eds, "--node", "3", "sdo", "read", "6200"])
        .success()
        .stdout(contains("6200h:01 Write output 8-bit / Write output 1 to 8 = 90 (0x5A) [UNSIGNED8]"));
    assert!(srv.terminate().success());
}

#[test]
fn sim_hosts_third_party_files() {
    // CANopenNode's profile: 1017h default 0, 1018h:1 from the file.
    let f = format!("{}:4", root("tests/vectors/eds/canopennode-DS301_profile.eds"));
    cli(&["--sim", &f, "--node", "4", "sdo", "read", "1017"]).success().stdout(contains("= 0 (0x0000)"));
    // A Lely DCF: its ParameterValue, not its DefaultValue.
    let dcf = root("tests/vectors/eds/lely-co-sdev.dcf");
    let f = format!("{dcf}:2");
    cli(&["--sim", &f, "--eds", &dcf, "--node", "2", "sdo", "read", "2008"])
        .success()
        .stdout(contains("= 3.1415927 [REAL32]"));
}

/// A DCF names its node: `FILE` alone takes `[DeviceComissioning]
/// NodeID` (Lely's co-nmt-slave.dcf: node 2); an EDS has none to give.
#[test]
fn a_dcf_without_node_takes_its_commissioned_node_id() {
    let dcf = root("tests/vectors/eds/lely-co-nmt-slave.dcf");
    cli(&["--sim", &dcf, "--node", "2", "sdo", "read", "1017"]).success().stdout(contains("1017h:00"));
    cli(&["--sim", &io16(), "--node", "3", "sdo", "read", "1000"])
        .failure()
        .stderr(contains("expected FILE:NODE").and(contains("NodeID")));
}

#[test]
fn a_malformed_file_is_refused_with_its_line_before_anything_starts() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.eds");
    std::fs::write(
        &bad,
        "[1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x191\n[1001\n",
    )
    .unwrap();
    let spec = format!("{}:3", bad.display());
    cli(&["serve", "--listen", "127.0.0.1:0", "--device", &spec])
        .failure()
        .stdout(predicate::str::is_empty())
        .stderr(contains("bad.eds: line 6: section header without ']'"));
    cli(&["--sim", &spec, "--node", "3", "sdo", "read", "1000"])
        .failure()
        .stderr(contains("bad.eds: line 6"));
    // A node-ID taken by a drive.
    let io = format!("{}:1", io16());
    cli(&["serve", "--listen", "127.0.0.1:0", "--drive", "akd:1", "--device", &io])
        .failure()
        .stderr(contains("node-ID 1 is already taken"));
}
