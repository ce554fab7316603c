//! ethercrab over a real veth pair: this test creates a network namespace
//! and a veth pair, serves four digital I/O slaves with the AF_PACKET
//! server on the root-namespace end, and runs the `drivebus-ecat-probe`
//! binary (ethercrab's own raw-socket transport) inside the namespace on
//! the other end — 5000 free-run cycles, then 5000 cycles with DC SYNC0 at
//! 1 ms, all in real time.
//!
//! Needs root (CAP_NET_ADMIN, CAP_NET_RAW) and `ip`. When the namespace
//! cannot be created the test prints exactly why and stops; the namespace
//! and the links are removed even when it fails.

use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, server};
use std::process::{Command, Output, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

fn ip(args: &[&str]) -> std::io::Result<Output> {
    Command::new("ip").args(args).stdin(Stdio::null()).output()
}

fn ok(args: &[&str]) -> Result<(), String> {
    match ip(args) {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => {
            Err(format!("`ip {}` failed: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim()))
        }
        Err(e) => Err(format!("cannot run `ip`: {e}")),
    }
}

/// Removes the namespace and the veth pair on drop.
struct Cleanup {
    ns: String,
    link: String,
}

impl Drop for Cleanup {
    fn drop(&mut self) {
        let _ = ip(&["link", "del", &self.link]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}

fn masks() -> Vec<String> {
    (0..4u32).map(|i| format!("{:#x}", 0x5A5A_5A5Au32 ^ (i * 0x0101_0101))).collect()
}

/// Runs the probe in the namespace with a hard time limit.
fn probe(ns: &str, iface: &str, extra: &[&str], limit: Duration) -> (bool, String) {
    let masks = masks().join(",");
    let mut args = vec![
        "netns",
        "exec",
        ns,
        env!("CARGO_BIN_EXE_drivebus-ecat-probe"),
        "--interface",
        iface,
        "--slaves",
        "4",
        "--masks",
        &masks,
        "--cycles",
        "5000",
    ];
    args.extend_from_slice(extra);
    let mut child = Command::new("ip")
        .args(&args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn probe");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait probe") {
            break Some(s);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let out = child.wait_with_output().expect("probe output");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    match status {
        Some(s) => (s.success(), text),
        None => (false, format!("probe killed after {limit:?}\n{text}")),
    }
}

#[test]
fn ethercrab_over_veth_in_a_network_namespace() {
    let id = std::process::id() % 100_000;
    let ns = format!("dbecat{id}");
    let (a, b) = (format!("dbe{id}a"), format!("dbe{id}b"));
    if let Err(why) = ok(&["netns", "add", &ns]) {
        println!(
            "SKIPPED ethercrab_over_veth_in_a_network_namespace: cannot create a network namespace: {why}"
        );
        return;
    }
    let _cleanup = Cleanup { ns: ns.clone(), link: a.clone() };
    for step in [
        vec!["link", "add", a.as_str(), "type", "veth", "peer", "name", b.as_str()],
        vec!["link", "set", b.as_str(), "netns", ns.as_str()],
        vec!["link", "set", a.as_str(), "up"],
        vec!["netns", "exec", ns.as_str(), "ip", "link", "set", b.as_str(), "up"],
    ] {
        ok(&step).unwrap_or_else(|e| panic!("{e}"));
    }

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
    let host = Host::line(devices, Clock::real());
    let stop = Arc::new(AtomicBool::new(false));
    // Bind before the master starts, so its first frame is not lost.
    let sock = server::RawSocket::open(&a).unwrap_or_else(|e| panic!("AF_PACKET socket on {a}: {e}"));
    let server = {
        let (host, stop) = (host.clone(), stop.clone());
        std::thread::spawn(move || server::serve_socket(&sock, &host, &stop))
    };

    let (free_ok, free_out) = probe(&ns, &b, &[], Duration::from_secs(120));
    let (dc_ok, dc_out) = probe(&ns, &b, &["--dc-us", "1000"], Duration::from_secs(120));
    stop.store(true, Ordering::Release);
    let stats = server.join().expect("server thread").expect("server");
    println!("free run:\n{free_out}\nDC:\n{dc_out}\nserver: {stats:?}");
    assert!(free_ok, "free run over veth failed:\n{free_out}");
    assert!(dc_ok, "DC over veth failed:\n{dc_out}");
    assert!(free_out.contains("slaves=4 cycles=5000 expected_wkc=12 bad_wkc=0 bad_data=0"), "{free_out}");
    assert!(dc_out.contains("slaves=4 cycles=5000 expected_wkc=12 bad_wkc=0 bad_data=0"), "{dc_out}");
    assert!(free_out.contains("DB-DIO16"), "names from the SII: {free_out}");
    assert!(stats.frames > 10_000);
}
