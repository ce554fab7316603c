//! Issue 15 §1: a client whose server dies. `drive move` waited past
//! `--wait` until Ctrl-C; `dump` and `gateway --listen` kept running on
//! the closed connection (`monitor` said so already, with other words). Each must end within its timeout, say what was
//! lost and exit non-zero.

mod common;

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::Serve;

/// A client process, killed if the test ends (or fails) while it runs.
struct Client(Option<Child>);

impl Drop for Client {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn spawn(url: &str, args: &[&str]) -> Client {
    Client(Some(spawn_child(url, args)))
}

fn spawn_child(url: &str, args: &[&str]) -> Child {
    Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn drivebus")
}

/// Waits for `child` until `by`; its stderr, or a failure if it still runs.
fn ended_by(mut client: Client, by: Instant, what: &str) -> (std::process::ExitStatus, String) {
    let mut child = client.0.take().expect("running");
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            return (st, String::from_utf8_lossy(&out.stderr).into_owned());
        }
        if Instant::now() > by {
            let _ = child.kill();
            panic!("`{what}` still runs after its server died");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn every_client_notices_a_dead_server() {
    let mut srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let ok = |args: &[&str]| assert!(spawn_child(&u, args).wait().unwrap().success(), "{args:?}");
    ok(&["--node", "5", "nmt", "start"]);
    ok(&["--node", "5", "drive", "enable"]);
    // A move of 5 s (within --wait 6), a trace and a gateway, all waiting.
    let mv = spawn(&u, &["--node", "5", "drive", "move", "500000", "--velocity", "100000", "--wait", "6"]);
    let dump = spawn(&u, &["dump"]);
    let gw = spawn(&u, &["gateway", "--listen", "127.0.0.1:0"]);
    let mon = spawn(&u, &["monitor", "--watch", "statusword"]);
    std::thread::sleep(Duration::from_millis(1500));
    let _ = srv.child.kill();
    let _ = srv.child.wait();
    // Well before --wait runs out: the loss itself ends them.
    let by = Instant::now() + Duration::from_secs(4);
    for (child, what) in [(mv, "drive move"), (dump, "dump"), (gw, "gateway --listen"), (mon, "monitor")] {
        let (st, err) = ended_by(child, by, what);
        assert!(!st.success(), "{what}: {st}");
        assert!(err.contains("lost") && err.contains("server closed the connection"), "{what}: {err}");
    }
}
