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
use drivebus_ethercat::master::drive::{CyclicDrive, Feedback};
use drivebus_ethercat::master::{LineMaster, PduFrames, SlaveInfo, block_on};
use drivebus_ethercat::{Clock, Host};
use drivebus_personality::Profile;
use indicatif::{ProgressBar, ProgressStyle};
use plotters::prelude::{BLUE, GREEN, MAGENTA, RED};
use std::collections::VecDeque;

use crate::args::{DemoArgs, Global};
use crate::output::outln;
use crate::plot::{Panel, Phase, Sample, Style, plot_panels};

/// The process-data cycle and SYNC0 period.
const CYCLE: Duration = Duration::from_millis(1);
/// The profile-position move: two turns of the iPOS's 2000-count encoder.
const MOVE: i32 = 4000;
/// Its profile velocity (6081h, iPOS units).
const MOVE_VELOCITY: u32 = 200_000;
/// The csp sine: half a turn, 1 Hz.
const AMPLITUDE: f64 = 1000.0;
/// The velocity is 6064h differentiated over this many cycles: over one,
/// the 1-count steps of the encoder make a comb of 0 and ±1000 counts/s.
const VELOCITY_WINDOW: usize = 10;

/// The demo's plot file unless `--out` says otherwise.
pub const DEFAULT_OUT: &str = "drivebus-demo-ethercat.svg";

const PANELS: [Panel; 3] = [
    Panel {
        title: "iPOS (slave 1) position",
        unit: "counts",
        node: 1,
        series: &[
            ("demand (6064h + 60F4h)", RED, Style::Demand, |x| x.demand),
            ("actual 6064h", BLUE, Style::Actual, |x| x.position),
        ],
    },
    Panel {
        title: "iPOS velocity",
        unit: "counts/s",
        node: 1,
        series: &[("from 6064h over 10 ms", GREEN, Style::Actual, |x| x.velocity)],
    },
    Panel {
        title: "iPOS following error",
        unit: "counts",
        node: 1,
        series: &[("actual 60F4h", MAGENTA, Style::Actual, |x| x.following)],
    },
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

/// The csp set-point of cycle `k`: A·(1 − cos 2πt) starts (and, after whole
/// seconds, ends) at rest, where A·sin 2πt would start with a step to 2πA
/// counts/s that the drive can only follow with a following-error spike.
fn sine_target(base: f64, k: u64) -> i32 {
    let t = k as f64 * CYCLE.as_secs_f64();
    (base + AMPLITUDE * (1.0 - (std::f64::consts::TAU * t).cos())).round() as i32
}

/// Samples with their time on the host's clock.
struct Trace {
    clock: Clock,
    t0: Instant,
    samples: Vec<Sample>,
    /// The last `VELOCITY_WINDOW` + 1 (time, position) pairs.
    last: VecDeque<(f64, i32)>,
}

impl Trace {
    fn t(&self) -> f64 {
        self.clock.now().saturating_duration_since(self.t0).as_nanos() as f64 / 1e9
    }

    fn push(&mut self, fb: &Feedback) {
        let t = self.t();
        let following = f64::from(fb.following.unwrap_or(0));
        let position = f64::from(fb.position);
        self.last.push_back((t, fb.position));
        if self.last.len() > VELOCITY_WINDOW + 1 {
            self.last.pop_front();
        }
        let velocity = match self.last.front() {
            Some(&(t1, p1)) if t > t1 => (position - f64::from(p1)) / (t - t1),
            _ => 0.0,
        };
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
    static STORAGE: PduFrames = PduFrames::new();
    let clock = if realtime { Clock::real() } else { Clock::simulated(Instant::from_millis(1)) };
    let host: Host = Line::new().drive(Profile::Ipos).host(clock.clone()).context("building the iPOS")?;
    let m = LineMaster::on_host(&STORAGE, host).context("starting the master")?;
    let pb = if show { ProgressBar::new_spinner() } else { ProgressBar::hidden() };
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg}").unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let mut r = Report::default();
    let mut trace =
        Trace { clock: clock.clone(), t0: clock.now(), samples: Vec::new(), last: VecDeque::new() };
    let start = clock.now();
    block_on(async {
        pb.set_message("scan: SII and 1018h over CoE");
        let (found, group) = m.scan_group().await?;
        r.found = found;
        pb.set_message("INIT -> OP with DC SYNC0 at 1 ms");
        let mut d = CyclicDrive::start(&m, group, 1, CYCLE, true, None).await?;
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
        r.phases.push(Phase { name: "homing", node: 1, start: h0, end: trace.t() });

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
        r.phases.push(Phase { name: "move", node: 1, start: m0, end: trace.t() });

        pb.set_message("CSP sine");
        let s0 = trace.t();
        let i0 = trace.samples.len();
        let base = f64::from(d.fb.position);
        let cycles = (sine_seconds * 1000.0).round() as u64;
        let targets = (0..cycles).map(move |k| sine_target(base, k));
        r.csp_cycles = d.csp(targets, |_, fb| trace.push(fb)).await?;
        for _ in 0..100 {
            d.cycle().await?;
            trace.push(&d.fb);
        }
        let csp = &trace.samples[i0..];
        r.csp_ferr_max = csp.iter().map(|s| s.following.abs()).fold(0.0, f64::max);
        r.csp_ferr_rms =
            (csp.iter().map(|s| s.following * s.following).sum::<f64>() / csp.len().max(1) as f64).sqrt();
        r.phases.push(Phase { name: "CSP sine", node: 1, start: s0, end: trace.t() });
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The recorded run: the sine starts at rest (no velocity step, no
    /// following-error spike), and the velocity trace is no comb.
    #[test]
    fn the_sine_starts_smoothly_and_the_velocity_is_readable() {
        let r = simulate(false, 1.0, false).unwrap();
        let sine = r.phases.iter().find(|p| p.name == "CSP sine").unwrap();
        let csp: Vec<&Sample> = r.samples.iter().filter(|s| s.t >= sine.start && s.t <= sine.end).collect();
        assert!(csp.len() > 900, "{}", csp.len());
        // The first 10 ms: A·(1 − cos 2πt) reaches 2πA·sin(2π·0.01) ≈ 390
        // counts/s (A·sin 2πt would start at 2πA ≈ 6300 counts/s).
        let v_max = csp.iter().take(10).map(|s| s.velocity.abs()).fold(0.0, f64::max);
        assert!(v_max < 700.0, "velocity step at the start of the sine: {v_max} counts/s");
        // No following-error spike as it starts (A·sin 2πt gave 12 counts
        // there against 2-3 in the rest of the sine).
        let f_start = csp.iter().take(50).map(|s| s.following.abs()).fold(0.0, f64::max);
        let f_rest = csp.iter().skip(100).map(|s| s.following.abs()).fold(0.0, f64::max);
        assert!(f_start <= f_rest + 2.0, "following-error spike at the start: {f_start} (then {f_rest})");
        // No comb: the 1-cycle difference of 1-count steps jumps by 1000 counts/s.
        let jump = csp.windows(2).map(|w| (w[1].velocity - w[0].velocity).abs()).fold(0.0, f64::max);
        assert!(jump < 600.0, "velocity jumps by {jump} counts/s between samples");
        // And it is the velocity: the peak 2πA counts/s of the sine.
        let peak = csp.iter().map(|s| s.velocity.abs()).fold(0.0, f64::max);
        assert!((5000.0..7500.0).contains(&peak), "{peak}");
    }

    #[test]
    fn the_sine_set_points_start_at_rest() {
        assert_eq!(sine_target(100.0, 0), 100);
        assert!((sine_target(100.0, 1) - 100).abs() <= 1);
        assert_eq!(sine_target(100.0, 500), 2100);
    }
}
