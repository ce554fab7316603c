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
    let a =
        db(&u, &["--json", "--node", "5", "drive", "move", "50000000", "--velocity", "3000000"]).failure();
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
    db(&u, &["--node", "5", "drive", "move", "50000000", "--velocity", "3000000"]).failure().stderr(
        contains("error: node 5: the positive limit switch is active").and(contains("short of the target")),
    );
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

/// A device whose frames leave `delay` after it produced them: an LSS
/// slave as slow as a Python one over socketcand.
struct Late<D> {
    inner: D,
    delay: drivebus_can::Duration,
    queue: std::collections::VecDeque<(drivebus_can::Instant, drivebus_can::Frame)>,
}

impl<D: drivebus_can::Device + 'static> Late<D> {
    fn hold(&mut self, now: drivebus_can::Instant, frames: Vec<drivebus_can::Frame>) {
        self.queue.extend(frames.into_iter().map(|f| (now + self.delay, f)));
    }
}

impl<D: drivebus_can::Device + 'static> drivebus_can::Device for Late<D> {
    fn start(&mut self, now: drivebus_can::Instant, out: &mut dyn drivebus_can::TxSink) {
        self.inner.start(now, out);
    }
    fn handle_frame(
        &mut self,
        frame: &drivebus_can::Frame,
        now: drivebus_can::Instant,
        _out: &mut dyn drivebus_can::TxSink,
    ) {
        let mut v = Vec::new();
        self.inner.handle_frame(frame, now, &mut v);
        self.hold(now, v);
    }
    fn poll(
        &mut self,
        now: drivebus_can::Instant,
        out: &mut dyn drivebus_can::TxSink,
    ) -> Option<drivebus_can::Instant> {
        let mut v = Vec::new();
        let next = self.inner.poll(now, &mut v);
        self.hold(now, v);
        while self.queue.front().is_some_and(|(t, _)| *t <= now) {
            if let Some((_, f)) = self.queue.pop_front() {
                out.send(f);
            }
        }
        drivebus_can::earliest(next, self.queue.front().map(|(t, _)| *t))
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// An unconfigured LSS slave (node-ID FFh) on a socketcand server,
/// answering `late` after each request; the server, its URL and the host.
fn lss_slave(
    rt: &tokio::runtime::Runtime,
    late: std::time::Duration,
    serial: u32,
) -> (drivebus_transport::socketcand::SocketcandServer, String, Box<dyn std::any::Any>) {
    let (server, addr) =
        rt.block_on(drivebus_transport::socketcand::SocketcandServer::bind("127.0.0.1:0", "can0")).unwrap();
    let mut cfg = drivebus_node::NodeConfig::new(0xFF);
    cfg.lss = true;
    cfg.identity = drivebus_node::Identity { vendor_id: 0xABC, product_code: 0x77, revision: 3, serial };
    let dev = drivebus_node::NodeDevice::new(drivebus_node::Node::new(cfg), drivebus_od::NoHooks);
    let late = Late { inner: dev, delay: late, queue: Default::default() };
    let host = rt.block_on(async { drivebus_transport::host::spawn_on_hub([late], server.hub()) });
    (server, format!("socketcand://{addr}/can0"), Box::new(host))
}

/// `lss scan --timeout 100` said `{"found":false}` after 20 ms with a
/// slave on the bus that answers in 30 ms: the fastscan waited a tenth
/// of --timeout per answer.
#[test]
fn lss_timeout_is_the_wait_for_each_answer() {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let (server, u, _host) = lss_slave(&rt, Duration::from_millis(30), 0x42);
    let a = db(&u, &["--json", "--timeout", "100", "lss", "scan"]).success();
    let j = json_of(&a);
    assert_eq!(j["found"], true, "{j}");
    assert_eq!(j["first"]["serial"], 0x42, "{j}");
    drop(server);
}

/// The next step `lss set-node-id --node N` names (`nmt reset-comm` on
/// the old node-ID) failed: the node boots under its new node-ID.
#[test]
fn the_step_after_lss_set_node_id_works_as_printed() {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let (server, u, _host) = lss_slave(&rt, Duration::ZERO, 0x10);
    db(&u, &["lss", "set-node-id", "10"]).success().stdout(contains("only unconfigured slave"));
    std::thread::sleep(Duration::from_millis(100));
    let a = db(&u, &["--node", "10", "lss", "set-node-id", "11"]).success();
    let text = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert!(text.contains("drivebus --node 10 nmt reset-comm"), "{text}");
    db(&u, &["--node", "10", "nmt", "reset-comm"]).success().stdout(contains("node 11"));
    db(&u, &["--node", "11", "sdo", "read", "1018:04"]).success().stdout(contains("= 16"));
    drop(server);
}

/// Ctrl-C ended an interrupted command with status 1; shells expect
/// 128 + SIGINT.
#[cfg(unix)]
#[test]
fn ctrl_c_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    // No limit switches or hard stops: homing method 17 searches for ever.
    let machine = dir.path().join("endless.toml");
    std::fs::write(
        &machine,
        "[[node]]\nid = 6\nlimits = { enabled = false }\nhard_stops = { enabled = false }\n",
    )
    .unwrap();
    let srv = Serve::start(&["--drive", "generic:6", "--machine", machine.to_str().unwrap()], None);
    let u = srv.url();
    db(&u, &["--node", "6", "drive", "enable"]).success();
    let child = std::process::Command::new(common::bin())
        .args(["--bus", &u, "--node", "6", "drive", "home", "--method", "17", "--wait", "60"])
        .env_remove("DRIVEBUS_BUS")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(2));
    let _ = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted") && err.contains("halted"), "{err}");
}

/// The name example of `drivebus --help` did not resolve; a command on
/// the empty in-process bus timed out with no hint that nothing is there;
/// a refused connection printed its cause last and twice.
#[test]
fn help_examples_resolve_and_errors_say_the_cause_first_once() {
    let help = Command::new(common::bin()).arg("--help").assert().success();
    assert!(String::from_utf8_lossy(&help.get_output().stdout).contains("identity/vendor-id"));
    db("virtual", &["--sim", "generic:5", "--node", "5", "sdo", "read", "identity/vendor-id"])
        .success()
        .stdout(contains("1018h:01"));
    db("virtual", &["--node", "5", "--timeout", "50", "sdo", "read", "1000"])
        .failure()
        .stderr(contains("nothing is on the bus").and(contains("--sim")).and(contains("DRIVEBUS_BUS")));
    let port = common::free_port();
    let a = db(&format!("socketcand://127.0.0.1:{port}/can0"), &["scan"]).failure();
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.starts_with("error: Connection refused"), "{err}");
    assert_eq!(err.matches("Connection refused").count(), 1, "{err}");
}

/// A malformed EDS showed its consequences ("line 0: object 1000 is
/// listed but has no section") and not its cause; `eds dcf` wrote an
/// empty `[FileInfo]` that `eds check` passed; an EDS read off a node said
/// `FileName=drivebus.eds` whatever `--out` was.
#[test]
fn eds_files_name_their_cause_and_themselves() {
    let dir = tempfile::tempdir().unwrap();
    let at = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    db("virtual", &["eds", "export", "--profile", "generic", "--out", &at("g.eds")]).success();
    let good = std::fs::read_to_string(at("g.eds")).unwrap();
    let n = good.lines().position(|l| l.trim() == "[1000]").unwrap();
    let bad: String = good
        .lines()
        .enumerate()
        .map(|(i, l)| if i == n { "[1000\n".to_owned() } else { format!("{l}\n") })
        .collect();
    std::fs::write(at("bad.eds"), bad).unwrap();
    db("virtual", &["--eds", &at("bad.eds"), "--sim", "generic:5", "--node", "5", "sdo", "read", "1000"])
        .failure()
        .stderr(contains(format!("bad.eds: line {}: section header without ']'", n + 1)));
    Command::new(common::bin())
        .args(["eds", "check", &at("bad.eds")])
        .assert()
        .failure()
        .stdout(contains(format!("bad.eds:{}: error: section header without ']'", n + 1)));
    db("virtual", &["--sim", "generic:5", "--node", "5", "eds", "dcf", "--out", &at("n5.dcf")]).success();
    let dcf = std::fs::read_to_string(at("n5.dcf")).unwrap();
    assert!(dcf.contains("FileName=n5.dcf") && dcf.contains("EDSVersion=4.0"), "{dcf:.400}");
    Command::new(common::bin())
        .args(["eds", "check", &at("n5.dcf")])
        .assert()
        .success()
        .stdout(contains("0 error(s)"));
    db("virtual", &["--sim", "generic:5", "--node", "5", "eds", "export", "--out", &at("node5.eds")])
        .success();
    let eds = std::fs::read_to_string(at("node5.eds")).unwrap();
    assert!(eds.contains("FileName=node5.eds") && !eds.contains("FileName=drivebus.eds"), "{eds:.400}");
}
