//! `drivebus serve --eds-object`: every drive serves its EDS at 1021h
//! (CiA 301 §7.5.2.21), so `eds export` reads it off the bus; without the
//! flag a faithful personality (here the AKD, whose manual lists no 1021h)
//! has none.

mod common;

use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, connect, sdo_read};
use predicates::prelude::*;
use predicates::str::contains;

fn export(url: &str, node: &str) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .args(["--bus", url, "--node", node, "eds", "export"])
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(60))
        .assert()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn eds_object_flag_gives_every_drive_1021h() {
    let mut srv = Serve::start(&["--drive", "akd:1", "--drive", "dds6:2", "--eds-object"], None);
    let url = srv.url();
    // The EDS as each drive generates it, read segmented (neither has
    // block transfer: `eds export` falls back when the block is refused).
    export(&url, "1").success().stdout(contains("[1000]").and(contains("[6041]")));
    export(&url, "2").success().stdout(contains("[1000]").and(contains("[6041]")));
    // 1022h storage format 0 = ASCII.
    let mut bus = connect(&url).await;
    assert_eq!(sdo_read(&mut bus, 1, 0x1022, 0).await, Ok(0));
    drop(bus);
    assert!(srv.terminate().success());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_the_flag_the_akd_has_no_1021h() {
    let mut srv = Serve::start(&["--drive", "akd:1"], None);
    let mut bus = connect(&srv.url()).await;
    assert_eq!(sdo_read(&mut bus, 1, 0x1021, 0).await, Err(0x0602_0000));
    drop(bus);
    assert!(srv.terminate().success());
}

#[test]
fn serve_help_documents_the_flag() {
    Command::new(common::bin())
        .args(["serve", "--help"])
        .assert()
        .success()
        .stdout(contains("--eds-object").and(contains("1021h")));
}
