//! `drivebus demo`: the main job on the simulated bus (1 Mbit/s, simulated
//! time). An AKD at node 1 and a DDS6 at node 2 boot; the master scans,
//! maps PDOs, starts the nodes, enables and homes both drives through
//! RPDO/TPDO, runs a profile-position move, then streams a CSP sine at
//! 1 kHz SYNC to node 1. Every plotted value arrived in a TPDO.

use std::f64::consts::PI;

use anyhow::{Context, anyhow, bail};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_personality::Profile;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{DemoArgs, Global};
use crate::output::outln;
use crate::sim::SimMaster;
use crate::vdrive::DriveSpec;

/// Bit rate of the demo bus.
const BITRATE: u32 = 1_000_000;
/// SYNC period.
const CYCLE: Duration = Duration::from_millis(1);

/// One 1 ms sample of node 1, from its TPDOs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sample {
    /// Seconds since the nodes were started.
    pub t: f64,
    /// Position demand \[m°\]: 6064h + 60F4h (the AKD has no 6062h, its
    /// manual's object list §7.1.5 has the following error 60F4h).
    pub demand: f64,
    /// 6064h position actual value \[m°\].
    pub position: f64,
    /// 606Ch velocity actual value \[m°/s\].
    pub velocity: f64,
    /// 60F4h following error actual value \[m°\].
    pub following: f64,
    /// Node 2 position actual value \[m°\].
    pub position2: f64,
}

/// What the demo measured.
#[derive(Debug, Default)]
pub struct Report {
    /// Nodes found by the scan: (node, device type, name).
    pub found: Vec<(u8, u32, String)>,
    /// Homing method used per node.
    pub homing: Vec<(u8, i8, f64)>,
    /// Profile-position move: distance \[m°\], time \[s\], max following error \[m°\].
    pub move_distance: f64,
    /// Seconds from new set-point to target reached.
    pub move_time: f64,
    /// Max |60F4h| during the move.
    pub move_ferr_max: f64,
    /// CSP: max |60F4h| and RMS.
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
}

struct Demo {
    m: SimMaster,
    pb: ProgressBar,
    /// Last statusword per node (index 0 = node 1).
    sw: [u16; 2],
    cur: Sample,
    t0: Instant,
    samples: Vec<Sample>,
    sync_counter: u64,
    /// Wall-clock start when pacing in real time.
    realtime: Option<std::time::Instant>,
    /// TPDO COB-IDs of node 1: TPDO1, TPDO2, TPDO3; of node 2: TPDO1, TPDO2.
    cob: [u32; 5],
}

impl Demo {
    /// One SYNC cycle: optional RPDO first, SYNC, run 1 ms, take TPDOs.
    fn tick(&mut self, rpdo: Option<Frame>) {
        if let Some(f) = rpdo {
            self.m.send(f);
        }
        self.m.send(Frame::new(0x080, &[]));
        self.sync_counter += 1;
        self.m.run_for(CYCLE);
        self.absorb();
        if self.sync_counter.is_multiple_of(50) {
            self.pb.set_position(self.sync_counter);
        }
        if let Some(start) = self.realtime {
            let due = start + std::time::Duration::from_nanos(self.m.now().as_nanos());
            if let Some(ahead) = due.checked_duration_since(std::time::Instant::now()) {
                std::thread::sleep(ahead);
            }
        }
    }

    fn absorb(&mut self) {
        for (t, f) in self.m.take() {
            let Some(id) = f.std_id().map(u32::from) else { continue };
            let d = f.raw_data();
            let i32_at = |k: usize| f64::from(i32::from_le_bytes([d[k], d[k + 1], d[k + 2], d[k + 3]]));
            if id == self.cob[0] {
                self.sw[0] = u16::from_le_bytes([d[0], d[1]]);
            } else if id == self.cob[3] {
                self.sw[1] = u16::from_le_bytes([d[0], d[1]]);
            } else if id == self.cob[1] {
                self.cur.position = i32_at(0);
                self.cur.velocity = i32_at(4);
                self.cur.t = t.saturating_duration_since(self.t0).as_nanos() as f64 / 1e9;
                self.samples.push(self.cur);
            } else if id == self.cob[2] {
                // After TPDO2 of the same SYNC (higher COB-ID, later).
                self.cur.following = i32_at(0);
                self.cur.demand = self.cur.position + self.cur.following;
            } else if id == self.cob[4] {
                self.cur.position2 = i32_at(0);
            }
        }
    }

    fn rpdo1(node: u8, cw: u16) -> Frame {
        Frame::new(0x200 + u16::from(node), &cw.to_le_bytes())
    }

    /// Ticks until `done(statusword)` for `node`; fails on a fault or after `ms`.
    fn wait_sw(&mut self, node: u8, what: &str, ms: u64, done: impl Fn(u16) -> bool) -> anyhow::Result<u64> {
        let k = usize::from(node - 1);
        for n in 0..ms {
            if done(self.sw[k]) {
                return Ok(n);
            }
            if self.sw[k] & 0x4F == 0x08 {
                let code = self.m.read_int(node, 0x603F, 0, false).unwrap_or(0) as u16;
                bail!(
                    "node {node}: drive fault {code:04X}h ({}) while waiting for {what}",
                    drivebus_emcy::describe(code).unwrap_or("manufacturer specific")
                );
            }
            self.tick(None);
        }
        bail!("node {node}: timed out after {ms} ms waiting for {what} (statusword {:04X}h)", self.sw[k])
    }
}

/// Runs the demo and prints the summary.
pub async fn run(g: &Global, a: &DemoArgs) -> anyhow::Result<()> {
    if !(0.1..=60.0).contains(&a.sine_seconds) {
        bail!("--sine-seconds {} is outside 0.1..60", a.sine_seconds);
    }
    let show = !a.no_progress && !g.json;
    let (sine, realtime) = (a.sine_seconds, a.realtime);
    let report = tokio::task::spawn_blocking(move || simulate(show, sine, realtime))
        .await
        .map_err(|e| anyhow!("demo task failed: {e}"))??;
    plot(&a.out, &report.samples).with_context(|| format!("cannot write the plot {}", a.out.display()))?;
    print_summary(g, &report, &a.out);
    Ok(())
}

fn simulate(show: bool, sine_seconds: f64, realtime: bool) -> anyhow::Result<Report> {
    let specs = [DriveSpec { profile: Profile::Akd, node: 1 }, DriveSpec { profile: Profile::Dds6, node: 2 }];
    let m = SimMaster::new(BITRATE, &specs)?;
    // Estimate; corrected when the CSP phase starts and its length is known.
    let total = 4_000 + (sine_seconds * 1000.0) as u64;
    let pb = if show { ProgressBar::new(total) } else { ProgressBar::hidden() };
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg:<34} [{bar:30}] {pos}/{len} SYNC cycles")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let mut d = Demo {
        m,
        pb,
        sw: [0; 2],
        cur: Sample::default(),
        t0: Instant::ZERO,
        samples: Vec::new(),
        sync_counter: 0,
        realtime: realtime.then(std::time::Instant::now),
        cob: [0; 5],
    };
    let mut r = Report::default();

    // 1. Boot: both drives send their boot-up message.
    d.pb.set_message("boot");
    d.m.run_for(Duration::from_millis(20));
    let boots: Vec<u16> =
        d.m.take().iter().filter_map(|(_, f)| (f.data() == [0]).then(|| f.std_id()).flatten()).collect();
    for n in [0x701u16, 0x702] {
        if !boots.contains(&n) {
            bail!("node {} sent no boot-up message", n - 0x700);
        }
    }

    // 2. Scan: SDO 1000h to every node-ID.
    d.pb.set_message("scan");
    for n in 1..=127u16 {
        d.m.send(Frame::new(0x600 + n, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]));
    }
    d.m.run_for(Duration::from_millis(40));
    for (_, f) in d.m.take() {
        if let Some(id @ 0x581..=0x5FF) = f.std_id()
            && f.raw_data()[0] == 0x43
        {
            let dd = f.raw_data();
            r.found.push((
                (id - 0x580) as u8,
                u32::from_le_bytes([dd[4], dd[5], dd[6], dd[7]]),
                String::new(),
            ));
        }
    }
    for (n, _, name) in &mut r.found {
        let text =
            d.m.read(*n, 0x1008, 0).map(|b| String::from_utf8_lossy(&b).trim_end_matches('\0').to_owned());
        *name = match text {
            Ok(t) if !t.is_empty() => t,
            _ => "(no 1008h name)".to_owned(),
        };
    }
    if r.found.iter().map(|f| f.0).collect::<Vec<_>>() != [1, 2] {
        bail!("scan found nodes {:?}, expected 1 and 2", r.found.iter().map(|f| f.0).collect::<Vec<_>>());
    }

    // 3. PDOs. RPDO1 controlword (event), RPDO2 controlword + target (SYNC);
    // TPDO1 statusword (event), TPDO2 position + velocity, TPDO3 following
    // error (every SYNC; the demand is position + following error).
    d.pb.set_message("configure PDOs");
    for node in [1u8, 2] {
        d.m.map_pdo(node, false, 0, &[0x6040_0010], 255).context("RPDO1")?;
        d.m.map_pdo(node, false, 1, &[0x6040_0010, 0x607A_0020], 1).context("RPDO2")?;
        let t1 = d.m.map_pdo(node, true, 0, &[0x6041_0010, 0x6061_0008], 255).context("TPDO1")?;
        let t2 = d.m.map_pdo(node, true, 1, &[0x6064_0020, 0x606C_0020], 1).context("TPDO2")?;
        if node == 1 {
            let t3 = d.m.map_pdo(node, true, 2, &[0x60F4_0020], 1).context("TPDO3")?;
            d.cob[..3].copy_from_slice(&[t1, t2, t3]);
        } else {
            d.cob[3..].copy_from_slice(&[t1, t2]);
        }
        // The other TPDOs off: an event-driven default mapping with a
        // position in it (AKD TPDO4) would send at every control period.
        for n in if node == 1 { 3u16..4 } else { 2u16..4 } {
            d.m.disable_tpdo(node, n)?;
        }
        // 1 ms interpolation period for CSP (60C2h: 1 · 10^-3 s).
        d.m.write(node, 0x60C2, 1, &[1])?;
        d.m.write(node, 0x60C2, 2, &[(-3i8) as u8])?;
        d.sw[usize::from(node - 1)] = d.m.read_int(node, 0x6041, 0, false)? as u16;
    }

    // 4. Start the nodes.
    d.pb.set_message("NMT start");
    d.m.send(Frame::new(0x000, &[0x01, 0]));
    d.t0 = d.m.now();
    for _ in 0..10 {
        d.tick(None);
    }

    // 5. Enable both drives through RPDO1/TPDO1.
    d.pb.set_message("enable drives");
    for (cw, want) in [(0x06u16, 0x21u16), (0x07, 0x23), (0x0F, 0x27)] {
        for node in [1u8, 2] {
            d.m.send(Demo::rpdo1(node, cw));
        }
        for node in [1u8, 2] {
            d.wait_sw(node, "the next CiA 402 state", 500, |s| s & 0x6F == want)?;
        }
    }

    // 6. Home both drives.
    d.pb.set_message("homing");
    for node in [1u8, 2] {
        d.m.write(node, 0x6060, 0, &[6])?;
        // Index pulse (34) where the drive has it, else the current position (35, 37).
        let method = [34i8, 35, 37]
            .into_iter()
            .find(|&m| d.m.write(node, 0x6098, 0, &[m as u8]).is_ok())
            .ok_or_else(|| anyhow!("node {node} accepts none of homing methods 34, 35, 37"))?;
        r.homing.push((node, method, 0.0));
        // Search the index pulse faster than the drive's default (6099h:2),
        // as fast as the drive's limit allows; a drive without it keeps its own.
        let current = d.m.read_int(node, 0x6099, 2, false).unwrap_or(i64::MAX);
        for v in [90_000u32, 36_000].into_iter().filter(|&v| i64::from(v) > current) {
            if d.m.write(node, 0x6099, 2, &v.to_le_bytes()).is_ok() {
                break;
            }
        }
    }
    for _ in 0..5 {
        d.tick(None);
    }
    for node in [1u8, 2] {
        d.m.send(Demo::rpdo1(node, 0x1F));
    }
    let h0 = d.m.now();
    let mut left = 2;
    for _ in 0..30_000 {
        for k in 0..2 {
            let sw = d.sw[k];
            if r.homing[k].2 > 0.0 {
                continue;
            }
            if sw & 0x2000 != 0 || sw & 0x4F == 0x08 {
                bail!("node {}: homing error (statusword {sw:04X}h)", k + 1);
            }
            if sw & 0x3400 == 0x1400 {
                r.homing[k].2 = d.m.now().saturating_duration_since(h0).as_nanos() as f64 / 1e9;
                left -= 1;
            }
        }
        if left == 0 {
            break;
        }
        d.tick(None);
    }
    if left > 0 {
        bail!("homing did not complete within 30 s (statuswords {:04X}h, {:04X}h)", d.sw[0], d.sw[1]);
    }
    for node in [1u8, 2] {
        d.m.send(Demo::rpdo1(node, 0x0F));
    }

    // 7. Profile-position move: node 1 one turn (0.001° units), node 2
    // 20000 of its own position units at its power-on profile.
    d.pb.set_message("profile position move");
    for (node, target) in [(1u8, 360_000i32), (2, 20_000)] {
        d.m.write(node, 0x6060, 0, &[1])?;
        d.m.write(node, 0x607A, 0, &target.to_le_bytes())?;
    }
    d.m.write(1, 0x6081, 0, &720_000u32.to_le_bytes())?;
    d.m.write(1, 0x6083, 0, &3_600_000u32.to_le_bytes())?;
    d.m.write(1, 0x6084, 0, &3_600_000u32.to_le_bytes())?;
    for _ in 0..5 {
        d.tick(None);
    }
    let start_pos = d.cur.position;
    for node in [1u8, 2] {
        d.m.send(Demo::rpdo1(node, 0x1F));
    }
    let m0 = d.m.now();
    let i0 = d.samples.len();
    d.wait_sw(1, "set-point acknowledge", 500, |s| s & 0x1000 != 0)?;
    d.tick(Some(Demo::rpdo1(1, 0x0F)));
    d.m.send(Demo::rpdo1(2, 0x0F));
    d.wait_sw(1, "target reached", 20_000, |s| s & 0x1400 == 0x0400)?;
    r.move_time = d.m.now().saturating_duration_since(m0).as_nanos() as f64 / 1e9;
    r.move_distance = d.cur.position - start_pos;
    r.move_ferr_max = d.samples[i0..].iter().map(|s| s.following.abs()).fold(0.0, f64::max);
    d.wait_sw(2, "target reached", 20_000, |s| s & 0x1400 == 0x0400)?;
    for _ in 0..100 {
        d.tick(None);
    }

    // 8. CSP sine on node 1, streamed with RPDO2 before each SYNC.
    d.pb.set_message("CSP sine at 1 kHz SYNC");
    d.m.write(1, 0x6060, 0, &[8])?;
    let base = d.cur.position;
    let cycles = (sine_seconds * 1000.0).round() as u64;
    d.pb.set_length(d.sync_counter + cycles + 105);
    let (amp, freq) = (45_000.0, 1.0);
    for _ in 0..5 {
        let b = (base as i32).to_le_bytes();
        d.tick(Some(Frame::new(0x301, &[0x0F, 0x00, b[0], b[1], b[2], b[3]])));
    }
    let busy0 = d.m.bus.stats().busy;
    let c0 = d.m.now();
    let i0 = d.samples.len();
    for k in 0..cycles {
        let t = k as f64 / 1000.0;
        let target = base + amp * (1.0 - (2.0 * PI * freq * t).cos());
        let b = (target.round() as i32).to_le_bytes();
        d.tick(Some(Frame::new(0x301, &[0x0F, 0x00, b[0], b[1], b[2], b[3]])));
        if d.sw[0] & 0x4F == 0x08 {
            bail!("node 1 faulted during CSP (statusword {:04X}h)", d.sw[0]);
        }
    }
    r.csp_cycles = cycles;
    let csp = &d.samples[i0..];
    r.csp_ferr_max = csp.iter().map(|s| s.following.abs()).fold(0.0, f64::max);
    r.csp_ferr_rms =
        (csp.iter().map(|s| s.following * s.following).sum::<f64>() / csp.len().max(1) as f64).sqrt();
    let st = d.m.bus.stats();
    let busy = st.busy.as_nanos().saturating_sub(busy0.as_nanos()) as f64;
    r.csp_bus_load = busy / d.m.now().saturating_duration_since(c0).as_nanos().max(1) as f64;

    // Hold a moment, then stop: NMT pre-operational.
    for _ in 0..100 {
        d.tick(None);
    }
    d.m.send(Frame::new(0x000, &[0x80, 0]));
    d.m.run_for(Duration::from_millis(5));
    let st = d.m.bus.stats();
    r.frames = st.frames;
    r.sim_seconds = d.m.now().as_nanos() as f64 / 1e9;
    r.bus_load = st.busy.as_nanos() as f64 / d.m.now().as_nanos().max(1) as f64;
    r.sdo = d.m.sdo_count;
    d.pb.finish_and_clear();
    r.samples = std::mem::take(&mut d.samples);
    Ok(r)
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
    outln!("drivebus demo — virtual bus at 1 Mbit/s, simulated time");
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

/// One value of a sample to draw.
type Series = (&'static str, plotters::style::RGBColor, Box<dyn Fn(&Sample) -> f64>);
/// Title, unit, series.
type Panel = (&'static str, &'static str, Vec<Series>);

/// Writes the SVG: position, velocity and following error against time.
pub fn plot(path: &std::path::Path, s: &[Sample]) -> anyhow::Result<()> {
    use plotters::prelude::*;
    if s.is_empty() {
        bail!("no samples to plot");
    }
    let root = SVGBackend::new(path, (1000, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let areas = root.split_evenly((3, 1));
    let t_end = s.last().map_or(1.0, |x| x.t).max(0.001);
    let range = |f: &dyn Fn(&Sample) -> f64| {
        let (lo, hi) = s.iter().map(f).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
        let pad = ((hi - lo) * 0.05).max(1e-3);
        (lo - pad)..(hi + pad)
    };
    let panels: [Panel; 3] = [
        (
            "Position: node 1 actual and demand [°], node 2 actual",
            "degrees",
            vec![
                ("node 1 actual 6064h", BLUE, Box::new(|x: &Sample| x.position / 1000.0)),
                ("node 1 demand (6064h + 60F4h)", RED, Box::new(|x: &Sample| x.demand / 1000.0)),
                (
                    "node 2 actual 6064h (1000 of its units)",
                    GREEN,
                    Box::new(|x: &Sample| x.position2 / 1000.0),
                ),
            ],
        ),
        (
            "Velocity actual 606Ch (node 1)",
            "degrees/s",
            vec![("node 1", BLUE, Box::new(|x: &Sample| x.velocity / 1000.0))],
        ),
        (
            "Following error 60F4h (node 1)",
            "degrees",
            vec![("node 1", MAGENTA, Box::new(|x: &Sample| x.following / 1000.0))],
        ),
    ];
    for (area, (title, unit, series)) in areas.iter().zip(panels.iter()) {
        let mut lo = f64::MAX;
        let mut hi = f64::MIN;
        for (_, _, f) in series {
            let r = range(f.as_ref());
            lo = lo.min(r.start);
            hi = hi.max(r.end);
        }
        let mut chart = ChartBuilder::on(area)
            .caption(*title, ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_end, lo..hi)
            .map_err(|e| anyhow!("{e}"))?;
        chart.configure_mesh().x_desc("time [s]").y_desc(*unit).draw().map_err(|e| anyhow!("{e}"))?;
        for (name, color, f) in series {
            let c = *color;
            chart
                .draw_series(LineSeries::new(s.iter().map(|x| (x.t, f(x))), c))
                .map_err(|e| anyhow!("{e}"))?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
    }
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}
