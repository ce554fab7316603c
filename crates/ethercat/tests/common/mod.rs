//! Network namespace + veth pair with the AF_PACKET server on one end, for
//! the wire-level tests. Everything is removed on drop, even on failure.

use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::server::{self, ServerStats};
use drivebus_ethercat::{BoxDevice, Clock, Host};
use std::process::{Command, Output, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub fn ip(args: &[&str]) -> std::io::Result<Output> {
    Command::new("ip").args(args).stdin(Stdio::null()).output()
}

pub fn ok(args: &[&str]) -> Result<(), String> {
    match ip(args) {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => {
            Err(format!("`ip {}` failed: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim()))
        }
        Err(e) => Err(format!("cannot run `ip`: {e}")),
    }
}

/// Input masks of the four slaves (as `drivebus-ecat-serve` uses).
pub fn masks() -> String {
    (0..4u32).map(|i| format!("{:#x}", 0x5A5A_5A5Au32 ^ (i * 0x0101_0101))).collect::<Vec<_>>().join(",")
}

/// A namespace `ns` holding veth end `inner`; `outer` stays in the root
/// namespace and is served by four digital I/O slaves.
pub struct Wire {
    pub ns: String,
    pub outer: String,
    pub inner: String,
    stop: Arc<AtomicBool>,
    server: Option<JoinHandle<std::io::Result<ServerStats>>>,
    /// The served line, to look at its devices.
    #[allow(dead_code)] // not every test looks
    pub host: Option<Host>,
}

impl Wire {
    /// Sets everything up, or says why it cannot.
    pub fn new(tag: &str) -> Result<Wire, String> {
        let devices: Vec<BoxDevice> = (0..4usize)
            .map(|i| {
                let cfg = DioConfig {
                    channels: if i % 2 == 0 { 8 } else { 16 },
                    mask: 0x5A5A_5A5A ^ (i as u32 * 0x0101_0101),
                    serial: 100 + i as u32,
                    ..DioConfig::default()
                };
                Box::new(dio::slave(&cfg)) as BoxDevice
            })
            .collect();
        Wire::with_devices(tag, devices)
    }

    /// The same with other devices on the served end (drives).
    pub fn with_devices(tag: &str, devices: Vec<BoxDevice>) -> Result<Wire, String> {
        let id = std::process::id() % 100_000;
        let ns = format!("db{tag}{id}");
        let (outer, inner) = (format!("db{tag}{id}a"), format!("db{tag}{id}b"));
        ok(&["netns", "add", &ns]).map_err(|e| format!("cannot create a network namespace: {e}"))?;
        let mut w =
            Wire { ns, outer, inner, stop: Arc::new(AtomicBool::new(false)), server: None, host: None };
        for step in [
            vec!["link", "add", w.outer.as_str(), "type", "veth", "peer", "name", w.inner.as_str()],
            vec!["link", "set", w.inner.as_str(), "netns", w.ns.as_str()],
            vec!["link", "set", w.outer.as_str(), "up"],
            vec!["netns", "exec", w.ns.as_str(), "ip", "link", "set", w.inner.as_str(), "up"],
        ] {
            ok(&step)?;
        }
        let host = Host::line(devices, Clock::real());
        w.host = Some(host.clone());
        // Bind before any master starts, so its first frame is not lost.
        let sock = server::RawSocket::open(&w.outer).map_err(|e| format!("AF_PACKET socket: {e}"))?;
        let stop = w.stop.clone();
        w.server = Some(std::thread::spawn(move || server::serve_socket(&sock, &host, &stop)));
        Ok(w)
    }

    /// Runs `program args…` inside the namespace with a time limit; returns
    /// (success, stdout + stderr).
    pub fn run(&self, program: &str, args: &[&str], limit: Duration) -> (bool, String) {
        let mut all = vec!["netns", "exec", self.ns.as_str(), program];
        all.extend_from_slice(args);
        let mut child = Command::new("ip")
            .args(&all)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        let start = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().expect("wait") {
                break Some(s);
            }
            if start.elapsed() > limit {
                let _ = child.kill();
                break None;
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let out = child.wait_with_output().expect("output");
        let text =
            format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        match status {
            Some(s) => (s.success(), text),
            None => (false, format!("killed after {limit:?}\n{text}")),
        }
    }

    /// Stops the server and returns its counters.
    pub fn stop(&mut self) -> ServerStats {
        self.stop.store(true, Ordering::Release);
        match self.server.take().map(|h| h.join()) {
            Some(Ok(Ok(s))) => s,
            other => panic!("server: {other:?}"),
        }
    }
}

impl Drop for Wire {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.server.take() {
            let _ = h.join();
        }
        let _ = ip(&["link", "del", &self.outer]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}
