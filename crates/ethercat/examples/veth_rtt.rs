//! Round trips on a veth pair: ethercrab 0.7.1 against a line of emulated
//! iPOS drives, beside the floor of the bare veth pair measured the same
//! way. Needs root (network namespace, AF_PACKET).
//!
//! ```sh
//! cargo build --release -p drivebus-ethercat --example veth_rtt
//! sudo target/release/examples/veth_rtt 1 5000
//! sudo target/release/examples/veth_rtt 16 5000
//! ```
//!
//! Creates a network namespace holding one end of a veth pair and serves
//! there (a thread that entered the namespace); the master side is the
//! other end, in this process. Three runs of `CYCLES` cycles at a 1 ms
//! cadence, each printing p50/p99/max of the send-to-reply time:
//!
//! 1. `bare`: a raw AF_PACKET socket sends a frame shaped like ethercrab's
//!    cycle frame (FRMW 8 B, LRW of 22 B per drive, an FPRD of AL status
//!    per drive) and an echo thread on the other end sends it straight
//!    back: the floor of veth + AF_PACKET + two thread wake-ups;
//! 2. `raw`: the same frame from the same raw socket, answered by the
//!    AF_PACKET server with the line of drives (`drivebus ethercat serve`'s
//!    loop): the floor plus the slaves' processing;
//! 3. `ethercrab`: ethercrab brings the line to OP (DC SYNC0 1 ms, csp,
//!    drives enabled) and each cycle's `tx_rx_dc` is timed.

#![allow(unsafe_code)] // setns(2) for the serving thread.

#[path = "../benches/support/ipos_line.rs"]
mod ipos_line;

use drivebus_esc::frame::{DatagramCommand, FrameBuilder, station_address};
use drivebus_ethercat::drive::DriveLine;
use drivebus_ethercat::server::{self, RawSocket};
use drivebus_ethercat::{Clock, Host};
use drivebus_personality::Profile;
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};
use std::os::fd::AsRawFd;
use std::process::Command as Cmd;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

static PDU_STORAGE: PduStorage<16, { PduStorage::element_size(1500) }> = PduStorage::new();

fn ip(args: &[&str]) -> Result<(), String> {
    let o = Cmd::new("ip").args(args).output().map_err(|e| format!("cannot run `ip`: {e}"))?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!("`ip {}`: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim()))
    }
}

/// The namespace and the pair; removed on drop.
struct Wire {
    ns: String,
    outer: String,
    inner: String,
}

impl Wire {
    fn new() -> Result<Wire, String> {
        let id = std::process::id() % 100_000;
        let w = Wire { ns: format!("dbrtt{id}"), outer: format!("dbrtt{id}a"), inner: format!("dbrtt{id}b") };
        ip(&["netns", "add", &w.ns])?;
        ip(&["link", "add", &w.outer, "type", "veth", "peer", "name", &w.inner])?;
        ip(&["link", "set", &w.inner, "netns", &w.ns])?;
        ip(&["link", "set", &w.outer, "up"])?;
        ip(&["netns", "exec", &w.ns, "ip", "link", "set", &w.inner, "up"])?;
        Ok(w)
    }
}

/// Moves the calling thread into network namespace `ns`.
fn enter(ns: &str) -> std::io::Result<()> {
    let f = std::fs::File::open(format!("/var/run/netns/{ns}"))?;
    // SAFETY: a valid namespace descriptor; affects this thread only.
    if unsafe { libc::setns(f.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

impl Drop for Wire {
    fn drop(&mut self) {
        let _ = ip(&["link", "del", &self.outer]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}

/// A thread in the namespace serving on `inner` until `stop`: the line of
/// drives (`host`) or, without one, a bare echo.
fn serve(wire: &Wire, host: Option<Host>, stop: Arc<AtomicBool>) -> JoinHandle<u64> {
    let (ns, inner) = (wire.ns.clone(), wire.inner.clone());
    let (tx, rx) = std::sync::mpsc::channel();
    let h = std::thread::spawn(move || {
        enter(&ns).expect("setns");
        let sock = RawSocket::open(&inner).expect("AF_PACKET socket in the namespace");
        tx.send(()).expect("ready");
        match host {
            Some(h) => server::serve_socket(&sock, &h, &stop).expect("serve").frames,
            None => {
                let mut buf = [0u8; 1600];
                let mut n = 0;
                while !stop.load(Ordering::Acquire) {
                    if let Some(len) =
                        sock.recv(&mut buf, drivebus_can::Duration::from_millis(50)).expect("recv")
                    {
                        sock.send(&buf[..len]).expect("send");
                        n += 1;
                    }
                }
                n
            }
        }
    });
    rx.recv().expect("server thread started");
    h
}

/// A frame shaped like ethercrab's cycle frame for `n` drives.
fn cycle_frame(n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(DatagramCommand::Frmw, 0, station_address(0x1000, 0x0910), &[0; 8]).unwrap();
    b.push(DatagramCommand::Lrw, 1, 0, &vec![0; 22 * n]).unwrap();
    for i in 0..n as u16 {
        b.push(DatagramCommand::Fprd, 2, station_address(0x1000 + i, 0x0130), &[0; 2]).unwrap();
    }
    let len = b.finish();
    buf.truncate(len);
    buf
}

/// `cycles` sends of `frame` at a 1 ms cadence; each time to its reply.
fn raw_round_trips(iface: &str, frame: &[u8], cycles: u32, lost: &mut u32) -> Vec<Duration> {
    let sock = RawSocket::open(iface).expect("AF_PACKET socket");
    let mut buf = [0u8; 1600];
    let mut out = Vec::with_capacity(cycles as usize);
    let mut next = Instant::now();
    for _ in 0..cycles {
        let t = Instant::now();
        sock.send(frame).expect("send");
        // A frame without a reply within 100 ms counts as lost (printed).
        let replied = loop {
            match sock.recv(&mut buf, drivebus_can::Duration::from_millis(100)).expect("recv") {
                Some(n) if n == frame.len() => break true,
                Some(_) if t.elapsed() < Duration::from_millis(100) => continue,
                _ => break false,
            }
        };
        if replied {
            out.push(t.elapsed());
        } else {
            *lost += 1;
        }
        next += Duration::from_millis(1);
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    out
}

fn report(name: &str, mut v: Vec<Duration>) {
    v.sort_unstable();
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize].as_secs_f64() * 1e6;
    println!(
        "{name:<34} n={:<6} p50 {:>7.1} µs  p99 {:>7.1} µs  max {:>8.1} µs",
        v.len(),
        q(0.5),
        q(0.99),
        q(1.0)
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let cycles: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(5000);
    assert!((1..=ipos_line::MAX_SLAVES).contains(&n), "1..=64 drives");
    let wire = match Wire::new() {
        Ok(w) => w,
        Err(why) => {
            eprintln!("veth_rtt: cannot set up a network namespace and veth pair (needs root): {why}");
            std::process::exit(2);
        }
    };
    let frame = cycle_frame(n);
    println!("{n} iPOS drive(s), {cycles} cycles at 1 ms, frame {} B", frame.len());

    // 1. The floor: a bare echo on the other end.
    let stop = Arc::new(AtomicBool::new(false));
    let echo = serve(&wire, None, stop.clone());
    let mut lost = 0;
    report("bare veth echo (floor)", raw_round_trips(&wire.outer, &frame, cycles, &mut lost));
    stop.store(true, Ordering::Release);
    echo.join().expect("echo");

    // 2. The same frame through the line of drives.
    let line = (0..n).fold(DriveLine::new(), |l, _| l.drive(Profile::Ipos));
    let host = line.host(Clock::real()).expect("line");
    let stop = Arc::new(AtomicBool::new(false));
    let server = serve(&wire, Some(host.clone()), stop.clone());
    report(&format!("raw socket → {n} iPOS"), raw_round_trips(&wire.outer, &frame, cycles, &mut lost));
    println!("raw frames without a reply within 100 ms: {lost}");

    // 3. ethercrab's tx_rx_dc against the same line (fresh drives are not
    // needed: the raw frames above only read and wrote nothing mapped).
    let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
    let task = ethercrab::std::tx_rx_task(&wire.outer, tx, rx).expect("ethercrab raw socket");
    std::thread::spawn(move || async_io::block_on(task));
    // Generous timeouts: the host is shared and loaded; a late reply is a
    // long round trip in the figures, not a failed run.
    let timeouts = Timeouts {
        state_transition: Duration::from_secs(20),
        pdu: Duration::from_millis(500),
        eeprom: Duration::from_secs(2),
        mailbox_echo: Duration::from_secs(2),
        mailbox_response: Duration::from_secs(5),
        ..Timeouts::default()
    };
    let md = MainDevice::new(pdu_loop, timeouts, MainDeviceConfig::default());
    let r = async_io::block_on(ipos_line::run(
        &md,
        ethercrab::std::ethercat_now,
        cycles,
        |d| async move {
            async_io::Timer::after(d).await;
        },
        |_| {},
    ))
    .expect("ethercrab brings the line to OP");
    println!("ethercrab: slaves={} enabled={} bad_wkc={}", r.slaves, r.enabled, r.bad_wkc);
    report(&format!("ethercrab tx_rx_dc → {n} iPOS"), r.round_trips);
    stop.store(true, Ordering::Release);
    let frames = server.join().expect("server");
    println!(
        "server answered {frames} frames; load: {}",
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
}
