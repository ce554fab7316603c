//! `drivebus demo`: the main job, run by the master library on the
//! simulated bus (1 Mbit/s, simulated time) — the same master code as
//! `drivebus --bus URL ...`: scan, PDO configuration, the CiA 402 `RemoteDrive`
//! handle's enable, homing and profile-position move, and CSP streaming
//! at a 1 kHz SYNC. An AKD at node 1 and a DDS6 at node 2. Every plotted
//! value arrived in a TPDO.

use std::f64::consts::PI;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, anyhow, bail};
use drivebus_master::{
    Frame, Instant, Master, MasterConfig, NmtCommand, PdoDir, PdoMapEntry, PdoRecord, RemoteDrive,
    RemoteState, ScanOptions, SimBus, drive::mode,
};
use drivebus_personality::Profile;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{DemoArgs, Global};
use crate::output::outln;
use crate::plot::{Phase, Sample, plot};
use crate::vdrive::{self, DriveSpec};

/// Bit rate of the demo bus.
const BITRATE: u32 = 1_000_000;
/// SYNC period.
const CYCLE: Duration = Duration::from_millis(1);

/// What the demo measured.
#[derive(Debug, Default)]
pub struct Report {
    /// Nodes found by the scan: (node, device type, name).
    pub found: Vec<(u8, u32, String)>,
    /// Homing method used per node and its seconds.
    pub homing: Vec<(u8, i8, f64)>,
    /// Profile-position move of node 1: distance \[m°\].
    pub move_distance: f64,
    /// Seconds from new set-point to target reached.
    pub move_time: f64,
    /// Max |60F4h| during the move.
    pub move_ferr_max: f64,
    /// CSP: max |60F4h|.
    pub csp_ferr_max: f64,
    /// CSP RMS following error.
    pub csp_ferr_rms: f64,
    /// CSP cycles streamed.
    pub csp_cycles: u64,
    /// Frames on the bus.
    pub frames: u64,
    /// Average bus load over the run (0..1).
    pub bus_load: f64,
    /// Bus load during the CSP phase.
    pub csp_bus_load: f64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// SDO transfers.
    pub sdo: u64,
    /// The samples.
    pub samples: Vec<Sample>,
    /// Homing, move and sine, in plot time.
    pub phases: Vec<Phase>,
}

/// Runs the demo and prints the summary.
pub async fn run(g: &Global, a: &DemoArgs) -> anyhow::Result<()> {
    if a.ethercat {
        if g.machine.is_some() {
            anyhow::bail!(
                "--machine does not apply to `drivebus demo --ethercat` (the EtherCAT twin has no machine file yet)"
            );
        }
        return crate::ethercat::demo::run(g, a).await;
    }
    let out = a.out.clone().unwrap_or_else(|| std::path::PathBuf::from("drivebus-demo.svg"));
    if !(0.1..=60.0).contains(&a.sine_seconds) {
        bail!(crate::error::coded("usage", anyhow!("--sine-seconds {} is outside 0.1..60", a.sine_seconds)));
    }
    let show = !a.no_progress && !g.json;
    let (sine, realtime) = (a.sine_seconds, a.realtime);
    let machine = g.machine.clone();
    let report = tokio::task::spawn_blocking(move || simulate(show, sine, realtime, machine.as_deref()))
        .await
        .map_err(|e| anyhow!("demo task failed: {e}"))??;
    plot(&out, &report.samples, &report.phases)
        .with_context(|| format!("cannot write the plot {}", out.display()))?;
    print_summary(g, &report, &out);
    Ok(())
}

/// The samples, filled by PDO callbacks in frame order.
#[derive(Default)]
struct Trace {
    t0: Option<Instant>,
    cur: Sample,
    samples: Vec<Sample>,
}

fn i32_at(d: &[u8], k: usize) -> f64 {
    d.get(k..k + 4).map_or(0.0, |b| f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])))
}

fn secs(m: &Master, since: Instant) -> f64 {
    m.now().saturating_duration_since(since).as_nanos() as f64 / 1e9
}

/// The CSP sine: `cycles` targets one `cycle` apart, `base + amplitude ·
/// (1 − cos 2πt/period)`: it starts at `base` at rest and swings to
/// `base + 2·amplitude` (the demo's, and the page's generator).
pub(crate) fn csp_sine(
    base: f64,
    amplitude: f64,
    period: Duration,
    cycle: Duration,
    cycles: u64,
) -> impl Iterator<Item = i32> {
    let (w, dt) = (2.0 * PI / period.as_secs_f64().max(1e-6), cycle.as_secs_f64());
    (0..cycles).map(move |k| (base + amplitude * (1.0 - (w * k as f64 * dt).cos())).round() as i32)
}

fn simulate(show: bool, sine_seconds: f64, realtime: bool, machine: Option<&Path>) -> anyhow::Result<Report> {
    let mut bus = virtual_bus();
    let specs = [DriveSpec { profile: Profile::Akd, node: 1 }, DriveSpec { profile: Profile::Dds6, node: 2 }];
    let machines = vdrive::Machines::load(machine, &specs)?;
    for spec in specs {
        bus.attach(vdrive::build(spec, None, Default::default(), &machines.machine_for(spec)?)?);
    }
    let mut sim =
        SimBus::with_config(bus, MasterConfig { sdo_timeout: Duration::from_secs(1), ..Default::default() });
    sim.set_realtime(realtime);
    let m = sim.master().clone();
    let pb =
        if show { ProgressBar::new(4_000 + (sine_seconds * 1000.0) as u64) } else { ProgressBar::hidden() };
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg:<34} [{bar:30}] {pos}/{len} ms simulated")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let tick = |pb: &ProgressBar, m: &Master| pb.set_position(m.now().as_nanos() / 1_000_000);
    let mut r = Report::default();
    let trace: Arc<Mutex<Trace>> = Arc::default();

    // 1. Boot and scan.
    pb.set_message("boot and scan");
    r.found = sim.block_on(boot_and_scan(&m))??;
    // 2. PDOs, heartbeats, NMT start, SYNC for the trace.
    pb.set_message("configure PDOs, start");
    let (d1, d2, _callbacks) = sim.block_on(configure(&m, trace.clone()))??;
    // 3. Enable both drives through RPDO1/TPDO1.
    pb.set_message("enable drives");
    sim.block_on(async {
        let (a, b) = tokio::join!(d1.enable(), d2.enable());
        a.context("node 1 enable")?;
        b.context("node 2 enable")
    })??;
    tick(&pb, &m);
    // 4. Home both at once.
    pb.set_message("homing");
    let t_plot = |trace: &Arc<Mutex<Trace>>| {
        let t = trace.lock().unwrap_or_else(|e| e.into_inner());
        t.t0.map_or(0.0, |t0| m.now().saturating_duration_since(t0).as_nanos() as f64 / 1e9)
    };
    let (homing, h0) = sim.block_on(home_both(&m, &d1, &d2))??;
    r.homing = homing;
    // Each node's own homing: node 2's may end long before node 1's.
    let h0 = t_plot(&trace) - secs(&m, h0);
    for &(node, _, t) in &r.homing {
        r.phases.push(Phase { name: "homing", node, start: h0, end: h0 + t });
    }
    tick(&pb, &m);
    // 5. Profile-position move: node 1 one turn (0.001° units), node 2
    // 20000 of its own position units.
    pb.set_message("profile position move");
    let m0 = t_plot(&trace);
    let i0 = trace.lock().unwrap_or_else(|e| e.into_inner()).samples.len();
    let start_pos = trace.lock().unwrap_or_else(|e| e.into_inner()).cur.position;
    let (t1, t2) = sim.block_on(move_both(&m, &d1, &d2))??;
    r.move_time = t1;
    r.phases.push(Phase { name: "move", node: 2, start: m0, end: m0 + t2 });
    {
        let t = trace.lock().unwrap_or_else(|e| e.into_inner());
        r.move_distance = t.cur.position - start_pos;
        r.move_ferr_max = t.samples[i0..].iter().map(|s| s.following.abs()).fold(0.0, f64::max);
    }
    sim.run_for(Duration::from_millis(100));
    r.phases.push(Phase { name: "move", node: 1, start: m0, end: t_plot(&trace) });
    tick(&pb, &m);
    // 6. CSP sine on node 1, one target per SYNC (RPDO2).
    pb.set_message("CSP sine at 1 kHz SYNC");
    let cycles = (sine_seconds * 1000.0).round() as u64;
    pb.set_length(m.now().as_nanos() / 1_000_000 + cycles + 120);
    let base = trace.lock().unwrap_or_else(|e| e.into_inner()).cur.position;
    sim.block_on(async {
        d1.set_mode(mode::CSP).await?;
        // Hold the present position for a few cycles first.
        d1.stream_csp(std::iter::repeat_n(base as i32, 5)).await
    })??;
    let busy0 = sim.bus().stats().busy;
    let c0 = sim.now();
    let s0 = t_plot(&trace);
    let i0 = trace.lock().unwrap_or_else(|e| e.into_inner()).samples.len();
    let targets = csp_sine(base, 45_000.0, Duration::from_secs(1), Duration::from_millis(1), cycles);
    let pb2 = pb.clone();
    let m2 = m.clone();
    r.csp_cycles = sim.block_on(async {
        let n = d1.stream_csp(targets.inspect(|_| tick(&pb2, &m2))).await?;
        let sw = d1.statusword().await?;
        if drivebus_master::DriveState::from_statusword(sw) == drivebus_master::DriveState::Fault {
            bail!("node 1 faulted during CSP (statusword {sw:04X}h)");
        }
        Ok(n as u64)
    })??;
    {
        let t = trace.lock().unwrap_or_else(|e| e.into_inner());
        let csp = &t.samples[i0..];
        r.csp_ferr_max = csp.iter().map(|s| s.following.abs()).fold(0.0, f64::max);
        r.csp_ferr_rms =
            (csp.iter().map(|s| s.following * s.following).sum::<f64>() / csp.len().max(1) as f64).sqrt();
    }
    let busy = sim.bus().stats().busy.as_nanos().saturating_sub(busy0.as_nanos()) as f64;
    r.csp_bus_load = busy / sim.now().saturating_duration_since(c0).as_nanos().max(1) as f64;
    r.phases.push(Phase { name: "CSP sine", node: 1, start: s0, end: t_plot(&trace) });
    // 7. Hold a moment, then stop: NMT pre-operational.
    sim.run_for(Duration::from_millis(100));
    m.stop_sync();
    sim.block_on(m.nmt(0, NmtCommand::EnterPreOperational))??;
    sim.run_for(Duration::from_millis(5));
    let st = sim.bus().stats();
    r.frames = st.frames;
    r.sim_seconds = sim.now().as_nanos() as f64 / 1e9;
    r.bus_load = st.busy.as_nanos() as f64 / sim.now().as_nanos().max(1) as f64;
    r.sdo = m.stats().sdo_transfers;
    pb.finish_and_clear();
    r.samples = std::mem::take(&mut trace.lock().unwrap_or_else(|e| e.into_inner()).samples);
    Ok(r)
}

fn virtual_bus() -> drivebus_master::VirtualBus {
    drivebus_master::VirtualBus::new(drivebus_master::VirtualBusConfig {
        log: false,
        ..drivebus_master::VirtualBusConfig::with_bitrate(BITRATE)
    })
}

async fn boot_and_scan(m: &Master) -> anyhow::Result<Vec<(u8, u32, String)>> {
    let (b1, b2) = (m.expect_bootup(1, Duration::from_secs(1)), m.expect_bootup(2, Duration::from_secs(1)));
    b1.await.map_err(|_| anyhow!("node 1 sent no boot-up message"))?;
    b2.await.map_err(|_| anyhow!("node 2 sent no boot-up message"))?;
    let found = m
        .scan_with(ScanOptions { identity: false, timeout: Duration::from_millis(40), ..Default::default() })
        .await;
    let mut out = Vec::new();
    for n in found {
        let name = match m.sdo(n.node).read::<String>(0x1008, 0).await {
            Ok(t) if !t.is_empty() => t,
            _ => "(no 1008h name)".to_owned(),
        };
        out.push((n.node, n.device_type, name));
    }
    if out.iter().map(|f| f.0).collect::<Vec<_>>() != [1, 2] {
        bail!("scan found nodes {:?}, expected 1 and 2", out.iter().map(|f| f.0).collect::<Vec<_>>());
    }
    Ok(out)
}

type Callbacks = Vec<drivebus_master::PdoCallback>;

/// RPDO1 controlword (event), RPDO2 controlword + target (SYNC); TPDO1
/// statusword + mode display (event), TPDO2 position + velocity, TPDO3
/// following error (every SYNC; the demand is position + following error:
/// the AKD has no 6062h, §7.1.5); the other TPDOs off (an
/// event-driven default with a position in it would send every period).
async fn configure(
    m: &Master,
    trace: Arc<Mutex<Trace>>,
) -> anyhow::Result<(RemoteDrive, RemoteDrive, Callbacks)> {
    let e = PdoMapEntry::new;
    for node in [1u8, 2] {
        let n = u16::from(node);
        m.write_pdo(node, PdoDir::Rx, 1, &PdoRecord::new(0x200 + n, 255, vec![e(0x6040, 0, 16)]))
            .await
            .context("RPDO1")?;
        m.write_pdo(
            node,
            PdoDir::Rx,
            2,
            &PdoRecord::new(0x300 + n, 1, vec![e(0x6040, 0, 16), e(0x607A, 0, 32)]),
        )
        .await
        .context("RPDO2")?;
        m.write_pdo(
            node,
            PdoDir::Tx,
            1,
            &PdoRecord::new(0x180 + n, 255, vec![e(0x6041, 0, 16), e(0x6061, 0, 8)]),
        )
        .await
        .context("TPDO1")?;
        m.write_pdo(
            node,
            PdoDir::Tx,
            2,
            &PdoRecord::new(0x280 + n, 1, vec![e(0x6064, 0, 32), e(0x606C, 0, 32)]),
        )
        .await
        .context("TPDO2")?;
        let last = if node == 1 {
            m.write_pdo(node, PdoDir::Tx, 3, &PdoRecord::new(0x380 + n, 1, vec![e(0x60F4, 0, 32)]))
                .await
                .context("TPDO3")?;
            4
        } else {
            3
        };
        for num in last..=4 {
            if let Ok(mut rec) = m.read_pdo(node, PdoDir::Tx, num).await {
                rec.cob_id |= 0x8000_0000;
                m.write_pdo(node, PdoDir::Tx, num, &rec).await.context("TPDO off")?;
            }
        }
        // 1 ms interpolation period for CSP (60C2h: 1 · 10^-3 s).
        m.sdo(node).write::<u8>(0x60C2, 1, 1).await?;
        m.sdo(node).write::<i8>(0x60C2, 2, -3).await?;
        // A heartbeat tells the RemoteDrive handle the node is operational (RPDOs).
        m.sdo(node).write::<u16>(0x1017, 0, 100).await?;
    }
    let mut cbs = Callbacks::new();
    let t = trace.clone();
    cbs.push(m.on_pdo(0x281, move |f: &Frame, at| {
        let mut t = t.lock().unwrap_or_else(|e| e.into_inner());
        let Some(t0) = t.t0 else { return };
        t.cur.position = i32_at(f.data(), 0);
        t.cur.velocity = i32_at(f.data(), 4);
        t.cur.t = at.saturating_duration_since(t0).as_nanos() as f64 / 1e9;
    }));
    // TPDO3 is the last of a SYNC's node-1 frames (highest COB-ID after
    // 282h): the sample is complete.
    let t = trace.clone();
    cbs.push(m.on_pdo(0x381, move |f: &Frame, _| {
        let mut t = t.lock().unwrap_or_else(|e| e.into_inner());
        if t.t0.is_none() {
            return;
        }
        t.cur.following = i32_at(f.data(), 0);
        t.cur.demand = t.cur.position + t.cur.following;
        let s = t.cur;
        t.samples.push(s);
    }));
    let t = trace.clone();
    cbs.push(m.on_pdo(0x282, move |f: &Frame, _| {
        t.lock().unwrap_or_else(|e| e.into_inner()).cur.position2 = i32_at(f.data(), 0);
    }));
    m.nmt(0, NmtCommand::Start).await?;
    trace.lock().unwrap_or_else(|e| e.into_inner()).t0 = Some(m.now());
    m.start_sync(CYCLE, 0);
    for node in [1u8, 2] {
        while m.wait_for_heartbeat(node, Duration::from_secs(1)).await? != RemoteState::Operational {}
    }
    let d1 = m.drive(1).await?.with_timeout(Duration::from_secs(2));
    let d2 = m.drive(2).await?.with_timeout(Duration::from_secs(2));
    if !(d1.statusword_by_pdo() && d1.controlword_by_pdo()) {
        bail!("node 1: statusword/controlword are not in the PDOs configured");
    }
    Ok((d1, d2, cbs))
}

/// Homing method: index pulse (34) where the drive has it, else the
/// current position (35, 37); the zero search at up to 90°/s.
async fn prepare_homing(m: &Master, node: u8) -> anyhow::Result<i8> {
    let sdo = m.sdo(node);
    let mut method = None;
    for candidate in [34i8, 35, 37] {
        if sdo.write(0x6098, 0, candidate).await.is_ok() {
            method = Some(candidate);
            break;
        }
    }
    let method = method.ok_or_else(|| anyhow!("node {node} accepts none of homing methods 34, 35, 37"))?;
    let current = sdo.read::<u32>(0x6099, 2).await.map_or(u64::MAX, u64::from);
    for v in [90_000u32, 36_000].into_iter().filter(|&v| u64::from(v) > current) {
        if sdo.write(0x6099, 2, v).await.is_ok() {
            break;
        }
    }
    Ok(method)
}

/// Homes both nodes at once: (node, method, seconds) each, and when they started.
async fn home_both(
    m: &Master,
    d1: &RemoteDrive,
    d2: &RemoteDrive,
) -> anyhow::Result<(Vec<(u8, i8, f64)>, Instant)> {
    let k1 = prepare_homing(m, 1).await?;
    let k2 = prepare_homing(m, 2).await?;
    let h0 = m.now();
    let (a, b) =
        tokio::join!(async { d1.home(k1, Duration::from_secs(30)).await.map(|_| secs(m, h0)) }, async {
            d2.home(k2, Duration::from_secs(30)).await.map(|_| secs(m, h0))
        });
    Ok((vec![(1, k1, a.context("node 1 homing")?), (2, k2, b.context("node 2 homing")?)], h0))
}

/// Moves both nodes at once: the seconds each took to reach its target.
async fn move_both(m: &Master, d1: &RemoteDrive, d2: &RemoteDrive) -> anyhow::Result<(f64, f64)> {
    d1.set_mode(mode::PP).await?;
    d2.set_mode(mode::PP).await?;
    let profile =
        drivebus_master::MoveProfile { velocity: 720_000, acceleration: 3_600_000, deceleration: 3_600_000 };
    let t0 = m.now();
    let one = async {
        d1.move_to(360_000, false, Some(profile), Duration::from_secs(20)).await.map(|_| secs(m, t0))
    };
    let two = async { d2.move_to(20_000, false, None, Duration::from_secs(20)).await.map(|_| secs(m, t0)) };
    let (a, b) = tokio::join!(one, two);
    Ok((a.context("node 1 move")?, b.context("node 2 move")?))
}

fn print_summary(g: &Global, r: &Report, out: &std::path::Path) {
    if g.json {
        let found: Vec<_> = r
            .found
            .iter()
            .map(|(n, dt, name)| serde_json::json!({"node": n, "device_type": dt, "name": name}))
            .collect();
        outln!(
            "{}",
            serde_json::json!({
                "nodes": found,
                "homing": r.homing.iter().map(|(n, m, t)| serde_json::json!({"node": n, "method": m, "seconds": t})).collect::<Vec<_>>(),
                "move": {"distance_mdeg": r.move_distance, "seconds": r.move_time, "following_error_max_mdeg": r.move_ferr_max},
                "csp": {"cycles": r.csp_cycles, "following_error_max_mdeg": r.csp_ferr_max, "following_error_rms_mdeg": r.csp_ferr_rms, "bus_load": r.csp_bus_load},
                "frames": r.frames, "bus_load": r.bus_load, "sdo_transfers": r.sdo, "simulated_seconds": r.sim_seconds,
                "samples": r.samples.len(), "plot": out.display().to_string(),
            })
        );
        return;
    }
    outln!("drivebus demo — virtual bus at 1 Mbit/s, simulated time, master library");
    for (n, dt, name) in &r.found {
        outln!("  found node {n}: device type 0x{dt:08X} {name}");
    }
    outln!();
    outln!("  {:<40} result", "step");
    for (n, m, t) in &r.homing {
        outln!("  {:<40} {t:.3} s", format!("homing node {n} (method {m})"));
    }
    outln!(
        "  {:<40} {:.3} s",
        format!("profile position move node 1 ({:.1}°)", r.move_distance / 1000.0),
        r.move_time
    );
    outln!("  {:<40} {:.3}°", "  following error max", r.move_ferr_max / 1000.0);
    outln!("  {:<40} {} cycles", "CSP sine node 1 (45° amplitude, 1 Hz)", r.csp_cycles);
    outln!("  {:<40} {:.3}°", "  following error max", r.csp_ferr_max / 1000.0);
    outln!("  {:<40} {:.3}°", "  following error RMS", r.csp_ferr_rms / 1000.0);
    outln!("  {:<40} {:.1} %", "  bus load during CSP", r.csp_bus_load * 100.0);
    outln!("  {:<40} {}", "frames on the bus", r.frames);
    outln!("  {:<40} {:.1} %", "bus load (average)", r.bus_load * 100.0);
    outln!("  {:<40} {}", "SDO transfers", r.sdo);
    outln!("  {:<40} {:.3} s", "simulated time", r.sim_seconds);
    outln!();
    outln!("plot: {} ({} samples from TPDOs)", out.display(), r.samples.len());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each node's panel shades that node's phases: node 2 homes on its
    /// own schedule (its index pulse is elsewhere), not in node 1's span.
    #[test]
    fn every_node_has_its_own_phases() {
        let r = simulate(false, 0.2, false, None).unwrap();
        let of = |node: u8, name: &str| -> Vec<Phase> {
            r.phases.iter().filter(|p| p.node == node && p.name == name).copied().collect()
        };
        let (h1, h2) = (of(1, "homing"), of(2, "homing"));
        assert_eq!((h1.len(), h2.len()), (1, 1), "{:?}", r.phases);
        for (node, h) in [(1, h1[0]), (2, h2[0])] {
            let took = r.homing.iter().find(|x| x.0 == node).unwrap().2;
            assert!((h.end - h.start - took).abs() < 1e-6, "node {node}: {h:?} vs {took} s");
        }
        assert!((h1[0].end - h2[0].end).abs() > 0.1, "the two homings end apart: {h1:?} {h2:?}");
        assert_eq!((of(1, "move").len(), of(2, "move").len()), (1, 1));
        assert_eq!((of(1, "CSP sine").len(), of(2, "CSP sine").len()), (1, 0), "the sine is node 1's");
    }
}
