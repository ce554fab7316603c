//! `drivebus demo --ethercat`: an ethercrab master
//! (`drivebus_ethercat::master`, the code `drivebus ethercat drive` runs)
//! and an emulated iPOS in one process over the in-process link, on
//! simulated time: scan (SII and 1018h), OP with DC SYNC0 at 1 ms,
//! enable, homing, a profile-position move and a csp sine, every value
//! plotted from the process data (6064h, 60F4h).

use std::path::PathBuf;

use anyhow::{Context, anyhow, bail};
use drivebus_can::{Duration, Instant};
use drivebus_ethercat::drive::DriveLine as Line;
use drivebus_ethercat::master::drive::{DriveLine, Feedback};
use drivebus_ethercat::master::{Master, SlaveInfo, Storage, block_on};
use drivebus_ethercat::{Clock, Host};
use drivebus_personality::Profile;
use indicatif::{ProgressBar, ProgressStyle};
use plotters::prelude::{BLUE, GREEN, MAGENTA, RED};

use crate::args::{DemoArgs, Global};
use crate::output::outln;
use crate::plot::{Panel, Phase, Sample, plot_panels};

/// The process-data cycle and SYNC0 period.
const CYCLE: Duration = Duration::from_millis(1);
/// The profile-position move: two turns of the iPOS's 2000-count encoder.
const MOVE: i32 = 4000;
/// Its profile velocity (6081h, iPOS units).
const MOVE_VELOCITY: u32 = 200_000;
/// The csp sine: half a turn, 1 Hz.
const AMPLITUDE: f64 = 1000.0;

/// The demo's plot file unless `--out` says otherwise.
pub const DEFAULT_OUT: &str = "drivebus-demo-ethercat.svg";

const PANELS: [Panel; 3] = [
    (
        "iPOS (slave 1) position",
        "counts",
        &[("actual 6064h", BLUE, |x| x.position), ("demand (6064h + 60F4h)", RED, |x| x.demand)],
    ),
    ("iPOS velocity", "counts/s", &[("from 6064h per cycle", GREEN, |x| x.velocity)]),
    ("iPOS following error", "counts", &[("actual 60F4h", MAGENTA, |x| x.following)]),
];

/// What the demo measured.
#[derive(Debug, Default)]
struct Report {
    found: Vec<SlaveInfo>,
    dc: bool,
    expected_wkc: u16,
    homing: f64,
    homing_position: i32,
    move_time: f64,
    move_position: i32,
    move_ferr_max: f64,
    csp_cycles: u64,
    csp_ferr_max: f64,
    csp_ferr_rms: f64,
    cycles: u64,
    bad_wkc: u64,
    sim_seconds: f64,
    realtime: bool,
    samples: Vec<Sample>,
    phases: Vec<Phase>,
}

/// Runs the demo and prints the summary.
pub async fn run(g: &Global, a: &DemoArgs) -> anyhow::Result<()> {
    if !(0.1..=60.0).contains(&a.sine_seconds) {
        bail!(crate::error::coded("usage", anyhow!("--sine-seconds {} is outside 0.1..60", a.sine_seconds)));
    }
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from(DEFAULT_OUT));
    let show = !a.no_progress && !g.json;
    let (sine, realtime) = (a.sine_seconds, a.realtime);
    let report = tokio::task::spawn_blocking(move || simulate(show, sine, realtime))
        .await
        .map_err(|e| anyhow!("demo task failed: {e}"))??;
    plot_panels(&out, &report.samples, &report.phases, &PANELS)
        .with_context(|| format!("cannot write the plot {}", out.display()))?;
    print_summary(g, &report, &out);
    Ok(())
}

/// Samples with their time on the host's clock.
struct Trace {
    clock: Clock,
    t0: Instant,
    samples: Vec<Sample>,
    last: Option<(f64, i32)>,
}

impl Trace {
    fn t(&self) -> f64 {
        self.clock.now().saturating_duration_since(self.t0).as_nanos() as f64 / 1e9
    }

    fn push(&mut self, fb: &Feedback) {
        let t = self.t();
        let following = f64::from(fb.following.unwrap_or(0));
        let position = f64::from(fb.position);
        let velocity = match self.last {
            Some((t1, p1)) if t > t1 => (position - f64::from(p1)) / (t - t1),
            _ => 0.0,
        };
        self.last = Some((t, fb.position));
        self.samples.push(Sample {
            t,
            demand: position + following,
            position,
            velocity,
            following,
            position2: 0.0,
        });
    }
}

fn simulate(show: bool, sine_seconds: f64, realtime: bool) -> anyhow::Result<Report> {
    static STORAGE: Storage = Storage::new();
    let clock = if realtime { Clock::real() } else { Clock::simulated(Instant::from_millis(1)) };
    let host: Host = Line::new().drive(Profile::Ipos).host(clock.clone()).context("building the iPOS")?;
    let m = Master::on_host(&STORAGE, host).context("starting the master")?;
    let pb = if show { ProgressBar::new_spinner() } else { ProgressBar::hidden() };
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg}").unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let mut r = Report::default();
    let mut trace = Trace { clock: clock.clone(), t0: clock.now(), samples: Vec::new(), last: None };
    let start = clock.now();
    block_on(async {
        pb.set_message("scan: SII and 1018h over CoE");
        let (found, group) = m.scan_group().await?;
        r.found = found;
        pb.set_message("INIT -> OP with DC SYNC0 at 1 ms");
        let mut d = DriveLine::start(&m, group, 1, CYCLE, true, None).await?;
        r.dc = d.dc();
        r.expected_wkc = d.expected_wkc();
        pb.set_message("enable");
        d.enable(Duration::from_secs(2)).await?;
        trace.t0 = clock.now();
        trace.push(&d.fb);

        pb.set_message("homing (method 35)");
        let h0 = trace.t();
        r.homing_position = d.home(35, Duration::from_secs(10), |fb| trace.push(fb)).await?;
        r.homing = trace.t() - h0;
        r.phases.push(Phase { name: "homing", start: h0, end: trace.t() });

        pb.set_message("profile position move");
        let m0 = trace.t();
        let i0 = trace.samples.len();
        r.move_position =
            d.move_to(MOVE, false, Some(MOVE_VELOCITY), Duration::from_secs(20), |fb| trace.push(fb)).await?;
        r.move_time = trace.t() - m0;
        r.move_ferr_max = trace.samples[i0..].iter().map(|s| s.following.abs()).fold(0.0, f64::max);
        for _ in 0..100 {
            d.cycle().await?;
            trace.push(&d.fb);
        }
        r.phases.push(Phase { name: "move", start: m0, end: trace.t() });

        pb.set_message("CSP sine");
        let s0 = trace.t();
        let i0 = trace.samples.len();
        let base = f64::from(d.fb.position);
        let cycles = (sine_seconds * 1000.0).round() as u64;
        let targets = (0..cycles).map(move |k| {
            let t = k as f64 / 1000.0;
            (base + AMPLITUDE * (std::f64::consts::TAU * t).sin()).round() as i32
        });
        r.csp_cycles = d.csp(targets, |_, fb| trace.push(fb)).await?;
        for _ in 0..100 {
            d.cycle().await?;
            trace.push(&d.fb);
        }
        let csp = &trace.samples[i0..];
        r.csp_ferr_max = csp.iter().map(|s| s.following.abs()).fold(0.0, f64::max);
        r.csp_ferr_rms =
            (csp.iter().map(|s| s.following * s.following).sum::<f64>() / csp.len().max(1) as f64).sqrt();
        r.phases.push(Phase { name: "CSP sine", start: s0, end: trace.t() });
        r.cycles = d.cycles;
        r.bad_wkc = d.bad_wkc;
        d.stop().await?;
        Ok::<(), anyhow::Error>(())
    })?;
    pb.finish_and_clear();
    r.realtime = realtime;
    r.sim_seconds = clock.now().saturating_duration_since(start).as_nanos() as f64 / 1e9;
    r.samples = trace.samples;
    Ok(r)
}

fn print_summary(g: &Global, r: &Report, out: &std::path::Path) {
    if g.json {
        let found: Vec<_> = r
            .found
            .iter()
            .map(|s| {
                serde_json::json!({"position": s.position, "name": s.name, "vendor_id": s.identity[0],
                    "product_code": s.identity[1], "revision": s.identity[2], "serial": s.identity[3],
                    "coe_identity_matches": s.coe_identity == Some(s.identity)})
            })
            .collect();
        outln!(
            "{}",
            serde_json::json!({
                "slaves": found, "dc": r.dc, "cycle_us": 1000,
                "homing": {"method": 35, "seconds": r.homing, "position": r.homing_position},
                "move": {"target": MOVE, "position": r.move_position, "seconds": r.move_time, "following_error_max": r.move_ferr_max},
                "csp": {"cycles": r.csp_cycles, "following_error_max": r.csp_ferr_max, "following_error_rms": r.csp_ferr_rms},
                "cycles": r.cycles, "expected_wkc": r.expected_wkc, "bad_wkc": r.bad_wkc, "simulated_seconds": r.sim_seconds,
                "samples": r.samples.len(), "plot": out.display().to_string(),
            })
        );
        return;
    }
    let sync = if r.dc { "DC SYNC0 at 1 ms" } else { "free run at 1 ms" };
    let time = if r.realtime { "real time" } else { "simulated time" };
    outln!(
        "drivebus demo --ethercat — ethercrab master, emulated iPOS on the in-process link, {sync}, {time}"
    );
    for s in &r.found {
        let id = s.identity;
        outln!(
            "  found slave {}: {} vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial {}{}",
            s.position,
            s.name,
            id[0],
            id[1],
            id[2],
            id[3],
            if s.coe_identity == Some(id) { " (1018h = SII)" } else { " (1018h differs from the SII)" }
        );
    }
    outln!();
    outln!("  {:<44} result", "step");
    outln!("  {:<44} {:.3} s, position {}", "homing slave 1 (method 35)", r.homing, r.homing_position);
    outln!(
        "  {:<44} {:.3} s, position {}",
        format!("profile position move slave 1 ({MOVE} counts)"),
        r.move_time,
        r.move_position
    );
    outln!("  {:<44} {:.0} counts", "  following error max", r.move_ferr_max);
    outln!("  {:<44} {} cycles", format!("CSP sine slave 1 ({AMPLITUDE:.0} counts, 1 Hz)"), r.csp_cycles);
    outln!("  {:<44} {:.0} counts", "  following error max", r.csp_ferr_max);
    outln!("  {:<44} {:.1} counts", "  following error RMS", r.csp_ferr_rms);
    outln!("  {:<44} {}", "process-data cycles in OP", r.cycles);
    outln!(
        "  {:<44} {} (expected {} on every cycle)",
        "cycles with a wrong working counter",
        r.bad_wkc,
        r.expected_wkc
    );
    outln!("  {:<44} {:.3} s", time, r.sim_seconds);
    outln!();
    outln!("plot: {} ({} samples from the process data)", out.display(), r.samples.len());
}
