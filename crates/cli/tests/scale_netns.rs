//! Beyond one machine (issue 17 §5, docs/scale.md): one `ethercat serve`
//! per line is the unit of scale. N lines, N = the number of cores, each
//! in its own network namespace exactly as a container runs it
//! (deploy/with-veth.sh makes the veth pair, the server takes one end, a
//! master the other), all at once: every master brings its drive to OP
//! with DC and cycles it at 1 ms; the test prints each line's figures.
//!
//! Needs root (CAP_NET_ADMIN, CAP_NET_RAW) and `ip`; without them it
//! prints why and stops. Namespaces and servers are removed on drop.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod netns;
use netns::ip;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_drivebus")
}

/// One line: its namespace and its server.
struct Line {
    ns: String,
    serve: Option<Child>,
}

impl Line {
    /// The namespace, the veth pair in it and `ethercat serve` on ecat0.
    fn start(i: usize) -> Result<Line, String> {
        let ns = format!("dbsc{i}x{}", std::process::id() % 100_000);
        ip(&["netns", "add", &ns]).map_err(|e| format!("cannot create a network namespace: {e}"))?;
        let mut line = Line { ns, serve: None };
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/with-veth.sh");
        let mut child = Command::new("ip")
            .args(["netns", "exec", &line.ns, "sh"])
            .arg(script)
            .args(["ecat0", "ecat1", bin(), "ethercat", "serve", "--iface", "ecat0", "--drive", "ipos"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("spawn serve: {e}"))?;
        let mut ready = String::new();
        BufReader::new(child.stdout.take().ok_or("no stdout")?)
            .read_line(&mut ready)
            .map_err(|e| e.to_string())?;
        if !ready.contains("ready on ecat0") {
            let _ = child.kill();
            let out = child.wait_with_output().map_err(|e| e.to_string())?;
            return Err(format!("serve in {}: {ready:?} {}", line.ns, String::from_utf8_lossy(&out.stderr)));
        }
        line.serve = Some(child);
        Ok(line)
    }

    /// The master in the namespace: OP, `seconds` of CSP at 1 ms.
    fn master(&self, seconds: &str) -> Child {
        Command::new("ip")
            .args(["netns", "exec", &self.ns, bin(), "ethercat", "--json", "drive", "--iface", "ecat1"])
            .args(["--slave", "1", "csp-sine", "--amplitude", "500", "--seconds", seconds])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn the master")
    }
}

impl Drop for Line {
    fn drop(&mut self) {
        if let Some(mut c) = self.serve.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = ip(&["netns", "del", &self.ns]);
    }
}

#[test]
fn one_line_per_core_each_in_its_namespace_reaches_op_and_cycles() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut lines = Vec::new();
    for i in 0..cores {
        match Line::start(i) {
            Ok(l) => lines.push(l),
            Err(why) => {
                println!("SKIPPED one_line_per_core_each_in_its_namespace_reaches_op_and_cycles: {why}");
                return;
            }
        }
    }
    let seconds = 2.0;
    let t0 = Instant::now();
    let masters: Vec<Child> = lines.iter().map(|l| l.master(&seconds.to_string())).collect();
    let mut worst_bad = 0;
    for (i, m) in masters.into_iter().enumerate() {
        let out = m.wait_with_output().unwrap();
        let wall = t0.elapsed();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "line {i}: {text} {}", String::from_utf8_lossy(&out.stderr));
        let j: serde_json::Value =
            serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"));
        let cycles = j["cycles"].as_u64().unwrap();
        let bad = j["bad_wkc"].as_u64().unwrap();
        println!(
            "line {}/{cores} ({}): {cycles} cycles of 1 ms in OP, {bad} with a bad working counter, \
             max following error {} inc; master done after {:.2} s",
            i + 1,
            lines[i].ns,
            j["max_following"],
            wall.as_secs_f64()
        );
        assert_eq!(cycles, (seconds * 1000.0) as u64, "line {i}: every cycle ran: {j}");
        worst_bad = worst_bad.max(bad);
    }
    // A cycle whose frame came back late or not at all counts as bad; a
    // line per core must keep that to a trace.
    assert!(worst_bad * 100 <= (seconds * 1000.0) as u64, "{worst_bad} bad cycles on a line");
    assert!(t0.elapsed() < Duration::from_secs(60));
}
