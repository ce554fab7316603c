//! Issue 15 §1 "no false success": each test is one report of the tool
//! that said something other than what happened (it failed before the
//! fix), run as the binary against `drivebus serve` over socketcand.

mod common;

use std::time::Duration;

use assert_cmd::Command;
use common::Serve;
use predicates::prelude::*;
use predicates::str::contains;

fn db(url: &str, args: &[&str]) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(90))
        .assert()
}

/// The `--json` object a command printed (success or error).
fn json_of(a: &assert_cmd::assert::Assert) -> serde_json::Value {
    let out = &a.get_output().stdout;
    serde_json::from_slice(out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(out)))
}

/// `drive move` onto the generic drive's positive limit switch said
/// "target reached" with exit 0, and `drive status` "errors none".
#[test]
fn a_move_stopped_by_a_limit_switch_fails_and_says_where() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "drive", "enable"]).success();
    let a = db(&u, &["--json", "--node", "5", "drive", "move", "50000000", "--velocity", "3000000"]).failure();
    let j = json_of(&a);
    let e = &j["error"];
    assert_eq!(e["code"], "limit_switch", "{j}");
    assert_eq!(e["outcome"], "limit_switch", "{j}");
    assert_eq!(e["target"], 50_000_000, "{j}");
    let pos = e["position"].as_i64().unwrap();
    assert!(pos < 10_000_000, "{j}");
    assert!(e["message"].as_str().unwrap().starts_with("node 5: the positive limit switch is active"), "{j}");
    db(&u, &["--node", "5", "drive", "status"]).success().stdout(
        contains("internal limit active (bit 11)")
            .and(contains("positive limit switch (60FDh bit 1)"))
            .and(contains("errors    none\n").not()),
    );
    // Back inside: a real arrival, in fields.
    let a = db(&u, &["--json", "--node", "5", "drive", "move", "0", "--velocity", "3000000"]).success();
    let j = json_of(&a);
    assert_eq!(j["outcome"], "target_reached", "{j}");
    assert!(j["position"].as_i64().unwrap().abs() < 1000, "{j}");
    assert!(j["duration"].as_f64().unwrap() > 0.0, "{j}");
    assert!(j["statusword"].is_u64() && j["reason"].is_string(), "{j}");
    assert!(j.get("result").is_none(), "no prose result: {j}");
    // Text: the same on stderr, cause first.
    db(&u, &["--node", "5", "drive", "move", "50000000", "--velocity", "3000000"])
        .failure()
        .stderr(contains("error: node 5: the positive limit switch is active").and(contains("short of the target")));
}

/// `drive home` with 6098h = 0 failed as "homing error (statusword
/// 2637h)" without the method or what 60E3h offers.
#[test]
fn a_homing_error_names_the_method_and_the_offered_ones() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "drive", "enable"]).success();
    db(&u, &["--node", "5", "sdo", "write", "6098", "0", "0"]).success();
    db(&u, &["--node", "5", "drive", "home"]).failure().stderr(
        contains("6098h homing method is 0").and(contains("60E3h offers methods")).and(contains("--method")),
    );
}

/// A move refused before it started said "nothing was moved" but had
/// written `--velocity` to 6081h already.
#[test]
fn a_refused_move_writes_nothing() {
    let srv = Serve::start(&["--drive", "akd:1"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "drive", "enable"]).success();
    let before = db(&u, &["--json", "--node", "1", "sdo", "read", "6081"]).success();
    let before = json_of(&before)["value"].clone();
    db(&u, &["--node", "1", "drive", "move", "900000", "--velocity", "1", "--wait", "5"])
        .failure()
        .stderr(contains("nothing was moved"));
    let after = db(&u, &["--json", "--node", "1", "sdo", "read", "6081"]).success();
    assert_eq!(json_of(&after)["value"], before, "6081h unchanged");
}
