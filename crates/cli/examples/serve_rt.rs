//! Real-time quality of `drivebus serve` as a master sees it over
//! socketcand (issue 11 §4): SYNC → TPDO latency, missed cycles and
//! heartbeat period error.
//!
//! ```sh
//! cargo build --release -p drivebus --example serve_rt
//! target/release/examples/serve_rt --bin target/release/drivebus --drives 4 --hz 1000 --seconds 10
//! target/release/examples/serve_rt --bin target/release/drivebus --drives 16 --hz 250 --seconds 10
//! ```
//!
//! It starts `drivebus serve` with `generic` drives 1..N, makes TPDO1 of
//! each synchronous (1800h:02 = 1, so it goes out on every SYNC), sets the
//! heartbeat to 100 ms (1017h), starts the nodes, then sends SYNC from its
//! own thread at the given rate (absolute deadlines, so the rate does not
//! drift) and timestamps every frame it receives. A drive answers every
//! SYNC with one TPDO, in order, so a drive's k-th TPDO answers the oldest
//! SYNC it has not answered yet; a SYNC still unanswered after
//! `MISSED_AFTER` counts as a missed cycle (its TPDO never came). Matching
//! by order, not by "the last SYNC sent", keeps a late SYNC thread (two
//! SYNCs close together) from being counted against the drives. The client, the server and the drives
//! share the machine: what is measured includes both ends of the TCP
//! connection, as a PLC on a socketcand link would see it.

#![allow(missing_docs)]

use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail};
use drivebus_can::Frame;
use drivebus_master::{Master, MasterConfig, NmtCommand};

struct Args {
    bin: String,
    drives: u8,
    hz: u32,
    seconds: u64,
    port: u16,
}

fn parse_args() -> anyhow::Result<Args> {
    let mut a =
        Args { bin: "target/release/drivebus".into(), drives: 4, hz: 1000, seconds: 10, port: 29_611 };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or_else(|| anyhow!("{k} needs a value"));
        match k.as_str() {
            "--bin" => a.bin = v()?,
            "--drives" => a.drives = v()?.parse()?,
            "--hz" => a.hz = v()?.parse()?,
            "--seconds" => a.seconds = v()?.parse()?,
            "--port" => a.port = v()?.parse()?,
            _ => bail!("usage: serve_rt [--bin PATH] [--drives N] [--hz F] [--seconds S] [--port P]"),
        }
    }
    if !(1..=127).contains(&a.drives) || a.hz == 0 {
        bail!("--drives 1..127, --hz > 0");
    }
    Ok(a)
}

/// The served drives; killed when dropped.
struct Served(Child);

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn serve(a: &Args) -> anyhow::Result<Served> {
    let mut cmd = Command::new(&a.bin);
    cmd.arg("serve").arg("--listen").arg(format!("127.0.0.1:{}", a.port));
    for n in 1..=a.drives {
        cmd.arg("--drive").arg(format!("generic:{n}"));
    }
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::inherit()).spawn().context("spawn serve")?;
    let out = child.stdout.take().ok_or_else(|| anyhow!("no stdout"))?;
    let mut line = String::new();
    std::io::BufRead::read_line(&mut std::io::BufReader::new(out), &mut line)?;
    if !line.contains("listening on") {
        bail!("serve did not start: {line}");
    }
    Ok(Served(child))
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// A SYNC unanswered this long is a missed cycle.
const MISSED_AFTER: Duration = Duration::from_millis(20);

#[derive(Default)]
struct Log {
    /// (node, arrival)
    tpdo: Vec<(u8, Instant)>,
    /// (node, arrival)
    heartbeat: Vec<(u8, Instant)>,
}

/// Latencies (µs) of one drive's TPDOs against the SYNCs, and the SYNCs it
/// missed.
fn match_drive(syncs: &[Instant], tpdos: &[Instant]) -> (Vec<(usize, f64)>, usize) {
    let (mut lat, mut missed, mut k) = (Vec::new(), 0, 0);
    for &t in tpdos {
        // Skip SYNCs that went unanswered for too long before this TPDO.
        while k < syncs.len() && t.duration_since(syncs[k]) > MISSED_AFTER {
            missed += 1;
            k += 1;
        }
        if k < syncs.len() && syncs[k] <= t {
            lat.push((k, t.duration_since(syncs[k]).as_secs_f64() * 1e6));
            k += 1;
        }
    }
    (lat, missed + syncs.len() - k)
}

/// A stall of the idle thread worth reporting \[ms\].
const HICCUP_MS: f64 = 1.0;

/// A thread that only sleeps 200 µs at a time and records how much later
/// than asked it woke: what the machine (guest, host, neighbours) does to
/// any thread, beside what `serve` does to its own.
struct Hiccups {
    stop: Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<Vec<(f64, f64)>>,
}

impl Hiccups {
    fn start(t0: Instant) -> Hiccups {
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let nap = Duration::from_micros(200);
            let mut found = Vec::new();
            while !flag.load(std::sync::atomic::Ordering::Relaxed) {
                let before = Instant::now();
                std::thread::sleep(nap);
                let after = Instant::now();
                let late = (after - before).saturating_sub(nap).as_secs_f64() * 1e3;
                if late > HICCUP_MS && after > t0 {
                    // (when it woke, ms after the first SYNC; how late, ms)
                    found.push(((after - t0).as_secs_f64() * 1e3, late));
                }
            }
            found
        });
        Hiccups { stop, thread }
    }

    fn stop(self) -> Vec<(f64, f64)> {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        self.thread.join().unwrap_or_default()
    }
}

fn main() -> anyhow::Result<()> {
    let a = parse_args()?;
    let _served = serve(&a)?;
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build()?;
    let url = format!("socketcand://127.0.0.1:{}/can0", a.port);

    // Configuration through the master.
    rt.block_on(async {
        let m =
            Master::open(&url, MasterConfig { sdo_timeout: Duration::from_secs(2), ..Default::default() })
                .await?;
        for n in 1..=a.drives {
            let sdo = m.sdo(n);
            sdo.write(0x1800, 2, 1u8).await.with_context(|| format!("node {n}: TPDO1 synchronous"))?;
            sdo.write(0x1017, 0, 100u16).await.with_context(|| format!("node {n}: heartbeat"))?;
        }
        m.nmt(0, NmtCommand::Start).await?;
        m.close().await?;
        anyhow::Ok(())
    })?;

    let bus = rt.block_on(drivebus_transport::open(&url))?;
    let (tx, mut rx) = bus.split();
    let start = Instant::now();
    let log = Arc::new(Mutex::new(Log::default()));

    // Receiver: timestamps on arrival, in the runtime.
    let recv = {
        let log = log.clone();
        let drives = a.drives;
        rt.spawn(async move {
            while let Ok(f) = rx.recv().await {
                let t = Instant::now();
                let Some(id) = f.std_id() else { continue };
                let node = (id & 0x7F) as u8;
                if node == 0 || node > drives {
                    continue;
                }
                match id & 0x780 {
                    0x180 => log.lock().unwrap().tpdo.push((node, t)),
                    0x700 => log.lock().unwrap().heartbeat.push((node, t)),
                    _ => {}
                }
            }
        })
    };

    // SYNC on its own thread, absolute deadlines.
    let period = Duration::from_secs_f64(1.0 / f64::from(a.hz));
    let cycles = (a.seconds * u64::from(a.hz)) as usize;
    let sync = Frame::new(0x080, &[]);
    let mut late_sends = 0usize;
    let mut syncs = Vec::with_capacity(cycles);
    let t0 = Instant::now() + Duration::from_millis(200);
    // TPDOs before the first SYNC answered nothing we sent.
    let first_sync = t0;
    let hiccups = Hiccups::start(t0);
    for k in 0..cycles {
        let due = t0 + period * k as u32;
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        } else if now - due > period {
            late_sends += 1;
        }
        syncs.push(Instant::now());
        // The tokio channel takes the frame without a runtime.
        if tx.try_send(sync).is_err() {
            rt.block_on(tx.send(sync))?;
        }
    }
    std::thread::sleep(MISSED_AFTER + Duration::from_millis(20));
    recv.abort();
    let elapsed = start.elapsed();
    let stalls = hiccups.stop();

    let log = log.lock().unwrap();
    let (mut lat, mut missed) = (Vec::new(), 0);
    for n in 1..=a.drives {
        let tpdos: Vec<Instant> =
            log.tpdo.iter().filter(|x| x.0 == n && x.1 >= first_sync).map(|x| x.1).collect();
        let (l, m) = match_drive(&syncs, &tpdos);
        lat.extend(l);
        missed += m;
    }
    // Where the worst cycles fall (start-up, periodic, random) tells what
    // dominates the tail.
    lat.sort_by(|a, b| b.1.total_cmp(&a.1));
    // A worst cycle during which an idle thread of this (other) process
    // was not scheduled either is a stall of the machine, not of `serve`.
    let machine_stall = |k: usize, us: f64| {
        let from = period.as_secs_f64() * 1e3 * k as f64 - 1.0;
        let to = from + 1.0 + us / 1e3;
        stalls.iter().any(|&(at, gap)| at + 1.0 >= from && at - gap <= to)
    };
    let worst: Vec<String> = lat
        .iter()
        .take(5)
        .map(|&(k, us)| {
            let tag = if machine_stall(k, us) { " (machine stall)" } else { "" };
            format!("{us:.0} us at cycle {k}{tag}")
        })
        .collect();
    let mut lat: Vec<f64> = lat.into_iter().map(|x| x.1).collect();
    lat.sort_by(f64::total_cmp);
    let drive_cycles = cycles * usize::from(a.drives);
    let mut hb_err: Vec<f64> = Vec::new();
    for n in 1..=a.drives {
        let times: Vec<Instant> = log.heartbeat.iter().filter(|h| h.0 == n).map(|h| h.1).collect();
        for w in times.windows(2) {
            hb_err.push((w[1].duration_since(w[0]).as_secs_f64() * 1e3 - 100.0).abs());
        }
    }
    hb_err.sort_by(f64::total_cmp);
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "serve_rt: {} drives, SYNC {} Hz, {} cycles in {:.1} s (load {})",
        a.drives,
        a.hz,
        cycles,
        elapsed.as_secs_f64(),
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    println!(
        "SYNC -> TPDO latency (us): p50 {:.0}  p99 {:.0}  max {:.0}  ({} TPDOs)",
        percentile(&lat, 0.5),
        percentile(&lat, 0.99),
        lat.last().copied().unwrap_or(f64::NAN),
        lat.len()
    );
    println!("worst: {}", worst.join(", "));
    let worst_stall = stalls.iter().map(|s| s.1).fold(0.0, f64::max);
    println!(
        "machine stalls (an idle thread of this process late by over {HICCUP_MS} ms): {} , longest {worst_stall:.1} ms",
        stalls.len()
    );
    println!(
        "missed cycles: {} of {} drive-cycles ({:.3} %); SYNCs sent more than a period late: {}",
        missed,
        drive_cycles,
        100.0 * missed as f64 / drive_cycles as f64,
        late_sends
    );
    println!(
        "heartbeat period error (ms, 100 ms): p50 {:.2}  p99 {:.2}  max {:.2}  ({} periods)",
        percentile(&hb_err, 0.5),
        percentile(&hb_err, 0.99),
        hb_err.last().copied().unwrap_or(f64::NAN),
        hb_err.len()
    );
    Ok(())
}
