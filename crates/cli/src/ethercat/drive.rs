//! `drivebus ethercat drive`: a CiA 402 drive over the process data
//! (`drivebus_ethercat::master::drive`).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::anyhow;
use drivebus_can::Duration;
use drivebus_ethercat::master::codes::{State, mode};
use drivebus_ethercat::master::drive::{CyclicDrive, CyclicDriveError, Feedback};
use drivebus_ethercat::master::{self, LineMaster};

use super::line::{master_err, with_master};
use super::{EcatDriveAction, EcatDriveArgs};
use crate::args::Global;
use crate::error::{coded, seconds};
use crate::output::outln;

/// Ctrl-C during a drive command: the motion loop halts and reports.
static STOP: AtomicBool = AtomicBool::new(false);

/// A drive error with its `--json` code.
fn drive_err(e: CyclicDriveError) -> anyhow::Error {
    match e {
        CyclicDriveError::Master(m) => master_err(m),
        e => {
            let code = match &e {
                CyclicDriveError::Timeout { .. } => "drive_timeout",
                CyclicDriveError::Interrupted { .. } => "interrupted",
                CyclicDriveError::Fault { .. } => "drive_fault",
                CyclicDriveError::Homing { .. } => "homing_error",
                _ => "drive_error",
            };
            coded(code, anyhow::Error::new(e))
        }
    }
}

/// What a drive command reports.
enum Done {
    Status { statusword: u16, mode: i64, position: i64, error_code: i64 },
    Enabled(Feedback, bool),
    Disabled(Feedback),
    Homed { method: i8, position: i32 },
    Moved { target: i32, position: i32, seconds: f64 },
    Csp { cycles: u64, max_following: i64, bad_wkc: u64 },
}

/// Progress on a terminal: position and state, a few times a second.
struct Progress {
    on: bool,
    n: u64,
}

impl Progress {
    fn show(&mut self, what: &str, fb: &Feedback) {
        self.n += 1;
        if self.on && self.n.is_multiple_of(100) {
            let st = fb.state().map_or("?", State::name);
            eprint!("\r{what}: position {:>10}  statusword {:04X}h ({st})    ", fb.position, fb.statusword);
        }
    }

    fn end(&self) {
        if self.on && self.n >= 100 {
            eprintln!();
        }
    }
}

/// Runs the command.
pub async fn run(g: &Global, a: &EcatDriveArgs) -> anyhow::Result<()> {
    let (Some(iface), Some(pos)) = (a.iface.clone(), a.slave) else {
        return Err(coded(
            "usage",
            anyhow!("give --iface IFACE and --slave N (the drive's line position from 1)"),
        ));
    };
    let line = super::EcatLine { iface };
    let cycle = Duration::from_micros(a.cycle_us);
    let wait = match &a.action {
        EcatDriveAction::Home { wait, .. } | EcatDriveAction::Move { wait, .. } => {
            Some(seconds("--wait", *wait)?)
        }
        EcatDriveAction::CspSine { seconds: s, frequency, .. } => {
            seconds("--seconds", *s)?;
            if !(frequency.is_finite() && *frequency > 0.0 && *frequency <= 100.0) {
                return Err(coded("usage", anyhow!("--frequency: give 0 to 100 Hz")));
            }
            None
        }
        _ => None,
    };
    let action = match &a.action {
        EcatDriveAction::Status => Action::Status,
        EcatDriveAction::Enable => Action::Op(OpAction::Enable),
        EcatDriveAction::Disable => Action::Op(OpAction::Disable),
        EcatDriveAction::Home { method, .. } => Action::Op(OpAction::Home(*method)),
        EcatDriveAction::Move { target, velocity, relative, .. } => {
            Action::Op(OpAction::Move(*target, *velocity, *relative))
        }
        EcatDriveAction::CspSine { amplitude, frequency, seconds } => Action::Op(OpAction::Csp(
            *amplitude,
            *frequency,
            (seconds * 1e6 / a.cycle_us as f64).round() as u64,
        )),
    };
    let wait = wait.unwrap_or(std::time::Duration::from_secs(30));
    // Ctrl-C sets the flag; the motion loop halts the drive and says so.
    let watcher = tokio::spawn(async {
        if tokio::signal::ctrl_c().await.is_ok() {
            STOP.store(true, Ordering::Relaxed);
        }
    });
    let progress = !g.json && std::io::stderr().is_terminal();
    let dc = !a.free_run;
    let r = with_master(g, &line, async move |m: &LineMaster| {
        act(m, pos, cycle, dc, action, wait, progress).await
    })
    .await;
    watcher.abort();
    let done = r?;
    report(g, pos, a.cycle_us, &done);
    Ok(())
}

#[derive(Clone, Copy)]
enum Action {
    Status,
    Op(OpAction),
}

/// What runs in OP.
#[derive(Clone, Copy)]
enum OpAction {
    Enable,
    Disable,
    Home(i8),
    Move(i32, Option<u32>, bool),
    Csp(u32, f64, u64),
}

async fn act(
    m: &LineMaster,
    pos: usize,
    cycle: Duration,
    dc: bool,
    action: Action,
    wait: std::time::Duration,
    progress: bool,
) -> anyhow::Result<Done> {
    m.check_position(pos).await.map_err(master_err)?;
    let group = m.init().await.map_err(master_err)?;
    let action = match action {
        Action::Op(a) => a,
        Action::Status => {
            // Over CoE in PRE-OP: nothing moves, nothing is enabled.
            let sd = m.slave(&group, pos).map_err(master_err)?;
            let rd = async |i: u16| -> anyhow::Result<i64> {
                let d = master::sdo_read(&sd, pos, i, 0).await.map_err(master_err)?;
                let u = d.iter().take(8).rev().fold(0u64, |a, &b| (a << 8) | u64::from(b));
                Ok(match d.len() {
                    1 => i64::from(u as u8 as i8),
                    2 => i64::from(u as u16),
                    4 => i64::from(u as u32 as i32),
                    _ => u as i64,
                })
            };
            return Ok(Done::Status {
                statusword: rd(0x6041).await? as u16,
                mode: rd(0x6061).await?,
                position: rd(0x6064).await?,
                error_code: rd(0x603F).await.unwrap_or(0),
            });
        }
    };
    let mut d = CyclicDrive::start(m, group, pos, cycle, dc, Some(&STOP)).await.map_err(drive_err)?;
    let dc = d.dc();
    let mut p = Progress { on: progress, n: 0 };
    let r = match action {
        OpAction::Enable => d.enable(Duration::from_secs(3)).await.map(|()| Done::Enabled(d.fb, dc)),
        OpAction::Disable => d.disable(Duration::from_secs(3)).await.map(|()| Done::Disabled(d.fb)),
        OpAction::Home(method) => d
            .home(method, wait, |fb| p.show("homing", fb))
            .await
            .map(|position| Done::Homed { method, position }),
        OpAction::Move(target, velocity, relative) => {
            let t0 = d.cycles;
            let r = d.move_to(target, relative, velocity, wait, |fb| p.show("move", fb)).await;
            let secs = (d.cycles - t0) as f64 * cycle.as_secs_f64();
            r.map(|position| Done::Moved { target, position, seconds: secs })
        }
        OpAction::Csp(amplitude, freq, cycles) => {
            let base = d.fb.position;
            let dt = cycle.as_secs_f64();
            let targets = (0..cycles).map(move |k| {
                let phase = std::f64::consts::TAU * freq * k as f64 * dt;
                (f64::from(base) + f64::from(amplitude) * phase.sin()).round() as i32
            });
            let mut worst = 0i64;
            let r = d
                .csp(targets, |t, fb| {
                    p.show("csp", fb);
                    worst = worst.max((i64::from(t) - i64::from(fb.position)).abs());
                })
                .await;
            r.map(|cycles| Done::Csp { cycles, max_following: worst, bad_wkc: d.bad_wkc })
        }
    };
    p.end();
    // Leave OP whatever happened; an error of the command comes first.
    let stopped = d.stop().await;
    let done = r.map_err(drive_err)?;
    stopped.map_err(drive_err)?;
    Ok(done)
}

fn report(g: &Global, pos: usize, cycle_us: u64, d: &Done) {
    let state = |sw: u16| State::from_statusword(sw).map_or("unknown state", State::name);
    let sync = |dc: bool| if dc { format!("DC SYNC0 every {cycle_us} µs") } else { "free run".to_owned() };
    let (json, text) = match d {
        Done::Status { statusword, mode: md, position, error_code } => (
            serde_json::json!({"slave": pos, "statusword": statusword, "state": state(*statusword),
                "mode": md, "mode_name": mode::name(*md as i8), "position": position, "error_code": error_code}),
            format!(
                "statusword {statusword:04X}h ({})\nmode       {md} ({})\nposition   {position}\nerror code {error_code:04X}h",
                state(*statusword),
                mode::name(*md as i8)
            ),
        ),
        Done::Enabled(fb, dc) => (
            serde_json::json!({"slave": pos, "statusword": fb.statusword, "state": state(fb.statusword), "position": fb.position, "dc": dc}),
            format!(
                "slave {pos}: operation enabled (statusword {:04X}h, {}), position {}, {}",
                fb.statusword,
                state(fb.statusword),
                fb.position,
                sync(*dc)
            ),
        ),
        Done::Disabled(fb) => (
            serde_json::json!({"slave": pos, "statusword": fb.statusword, "state": state(fb.statusword)}),
            format!("slave {pos}: {} (statusword {:04X}h)", state(fb.statusword), fb.statusword),
        ),
        Done::Homed { method, position } => (
            serde_json::json!({"slave": pos, "homing": "attained", "method": method, "position": position}),
            format!("slave {pos}: homing attained (method {method}), position {position}"),
        ),
        Done::Moved { target, position, seconds } => (
            serde_json::json!({"slave": pos, "target": target, "position": position, "seconds": seconds}),
            format!("slave {pos}: target reached at {position} (target {target}) in {seconds:.3} s"),
        ),
        Done::Csp { cycles, max_following, bad_wkc } => (
            serde_json::json!({"slave": pos, "cycles": cycles, "max_following": max_following, "bad_wkc": bad_wkc}),
            format!(
                "slave {pos}: csp sine {cycles} cycles, |target - position| max {max_following}, {bad_wkc} cycles with a wrong working counter"
            ),
        ),
    };
    if g.json {
        outln!("{json}");
    } else {
        outln!("{text}");
    }
}
