//! `drivebus drive ...`: CiA 402 device control with the master's `Drive`
//! handle (controlword/statusword by PDO where mapped and the node is
//! operational, else by SDO). Motion a command starts is stopped (halt,
//! else quick stop) when the command fails, times out or is interrupted,
//! and the command says where the axis is and which objects limit it.

use std::future::Future;
use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{
    Drive, DriveError, DriveState, MotionLimits, MotionProgress, Profile, SdoError, StopAction,
    drive::human_secs, drive::mode, mode_name,
};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{DriveCmd, Global};
use crate::conn::{Conn, need_node};
use crate::error::coded;

fn state_name(sw: u16) -> &'static str {
    DriveState::from_statusword(sw).name()
}

/// Explains a drive handle error with the node, the abort meaning or the
/// timeout in force.
fn explain(node: u8, timeout: Duration, e: DriveError) -> anyhow::Error {
    match e {
        DriveError::Sdo(SdoError::Timeout) => coded(
            "sdo_timeout",
            anyhow!(
                "node {node}: SDO timed out: no response within {} ms (is node {node} on the bus and in pre-operational or operational?)",
                timeout.as_millis()
            ),
        ),
        DriveError::Sdo(SdoError::Abort { code, text }) => coded(
            "sdo_abort",
            anyhow!(
                "node {node}: SDO aborted by the device with code 0x{:08X}: {}",
                code.0,
                text.unwrap_or("unknown abort code")
            ),
        ),
        DriveError::Timeout { waiting_for, statusword } => coded(
            "drive_timeout",
            anyhow!(
                "node {node}: timed out waiting for {waiting_for} (statusword {statusword:04X}h: {})",
                state_name(statusword)
            ),
        ),
        other => anyhow::Error::new(other).context(format!("node {node}")),
    }
}

/// A progress line on a terminal (stderr); nothing otherwise.
fn progress_bar(g: &Global) -> ProgressBar {
    if g.json {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb
}

fn describe_progress(p: &MotionProgress) -> String {
    let num = |v: Option<i32>| v.map_or_else(|| "-".to_owned(), |v| v.to_string());
    format!(
        "waiting for {}: position {}, velocity {}, {}",
        p.waiting_for,
        num(p.position),
        num(p.velocity),
        p.state
    )
}

/// Runs a `drive` subcommand.
pub async fn run(g: &Global, c: &DriveCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    let conn = Conn::open(g).await?;
    let r = run_on(g, &conn, node, c).await;
    // The frames of the command (and of a stop) are on the bus before the report.
    let closed = conn.close().await;
    let msg = r?;
    closed?;
    if let Some((text, json)) = msg {
        crate::output::emit(g.json, json, || text);
    }
    Ok(())
}

type Report = Option<(String, serde_json::Value)>;

fn done(node: u8, msg: String, sw: u16) -> Report {
    Some((
        format!("node {node}: {msg} (statusword {sw:04X}h, {})", state_name(sw)),
        serde_json::json!({"node": node, "result": msg, "statusword": sw, "state": state_name(sw)}),
    ))
}

/// Runs `motion`; on an error, a timeout or Ctrl-C stops the axis and
/// explains where it is and what limits it.
async fn guarded<T>(
    d: &Drive,
    node: u8,
    timeout: Duration,
    what: &str,
    target: Option<i32>,
    homing: bool,
    motion: impl Future<Output = Result<T, DriveError>>,
) -> anyhow::Result<T> {
    let interrupted = crate::serve::wait_for_signal();
    let r = tokio::select! {
        r = motion => r.map_err(|e| explain(node, timeout, e)),
        Ok(()) = interrupted => Err(coded("interrupted", anyhow!("node {node}: {what} interrupted (Ctrl-C)"))),
    };
    let Err(e) = r else { return r };
    let stop = match d.stop_motion(Duration::from_secs(5)).await {
        Ok(s) => match s.action {
            StopAction::NotMoving => "the drive is not in operation enabled: no motion to stop".to_owned(),
            StopAction::Halted => format!(
                "the axis was halted (controlword bit 8) at position {}",
                s.position.map_or_else(|| "unknown".into(), |p| p.to_string())
            ),
            StopAction::QuickStopped => format!(
                "halt did not stop the axis: quick stop, now {} at position {}",
                state_name(s.statusword),
                s.position.map_or_else(|| "unknown".into(), |p| p.to_string())
            ),
        },
        Err(se) => format!("stopping the axis failed too: {se}"),
    };
    let limits = d.motion_limits().await;
    let position = d.position().await;
    let lines = limits.describe(position, target, homing);
    let mut text = stop;
    if !lines.is_empty() {
        text.push_str("; objects that shape this motion:\n  ");
        text.push_str(&lines.join("\n  "));
    }
    Err(e.context(text))
}

async fn run_on(g: &Global, conn: &Conn, node: u8, c: &DriveCmd) -> anyhow::Result<Report> {
    let timeout = conn.timeout;
    let ex = |e: DriveError| explain(node, timeout, e);
    let pb = progress_bar(g);
    let p2 = pb.clone();
    let d = conn
        .master
        .drive(node)
        .await
        .map_err(|e| ex(DriveError::Sdo(e)))?
        .with_timeout(Duration::from_secs(3))
        .on_progress(Duration::from_millis(250), move |p| {
            p2.set_message(describe_progress(p));
            p2.tick();
        });
    let require_enabled = || async {
        let sw = d.statusword().await.map_err(ex)?;
        if DriveState::from_statusword(sw) != DriveState::OperationEnabled {
            return Err(coded(
                "drive_state",
                anyhow!(
                    "node {node}: drive is not in operation enabled (it is in {}); run `drivebus --node {node} drive enable` first",
                    state_name(sw)
                ),
            ));
        }
        Ok(())
    };
    let read_i = |index: u16| {
        let d = &d;
        async move {
            let v = d.read_raw(index, 0).await.ok()?;
            Some(match v.len() {
                1 => i64::from(v[0] as i8),
                2 => i64::from(i16::from_le_bytes([v[0], v[1]])),
                4 => i64::from(i32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                _ => return None,
            })
        }
    };
    let report = match c {
        DriveCmd::Status => {
            let sw = d.statusword().await.map_err(ex)?;
            let mode = read_i(0x6061).await.map(|m| m as i8);
            let pos = read_i(0x6064).await;
            let vel = read_i(0x606C).await;
            let err = read_i(0x603F).await.map(|e| e as u16);
            let reg = d.read_raw(0x1001, 0).await.ok().and_then(|v| v.first().copied());
            let json = serde_json::json!({"node": node, "statusword": sw, "state": state_name(sw), "mode": mode,
                "mode_name": mode.map(mode_name), "position": pos, "velocity": vel, "error_code": err, "error_register": reg,
                "target_reached": sw & 0x400 != 0, "warning": sw & 0x80 != 0});
            let mut t = format!("node {node}: {} (statusword {sw:04X}h)", state_name(sw));
            if let Some(m) = mode {
                t += &format!("\n  mode      {m} ({})", mode_name(m));
            }
            if let Some(p) = pos {
                t += &format!("\n  position  {p}");
            }
            if let Some(v) = vel {
                t += &format!("\n  velocity  {v}");
            }
            t += &match err {
                Some(0) | None => "\n  errors    none".to_owned(),
                Some(e) => format!(
                    "\n  error     {e:04X}h {} (register {:02X}h)",
                    drivebus_master::emcy_description(e).unwrap_or("manufacturer specific"),
                    reg.unwrap_or(0)
                ),
            };
            Some((t, json))
        }
        DriveCmd::Enable => {
            d.enable().await.map_err(ex)?;
            done(node, "operation enabled".into(), d.statusword().await.map_err(ex)?)
        }
        DriveCmd::Disable => {
            d.disable().await.map_err(ex)?;
            done(node, "operation disabled".into(), d.statusword().await.map_err(ex)?)
        }
        DriveCmd::Quickstop => {
            d.quick_stop().await.map_err(ex)?;
            done(node, "quick stop".into(), d.statusword().await.map_err(ex)?)
        }
        DriveCmd::Stop => {
            let s = d.stop_motion(Duration::from_secs(5)).await.map_err(ex)?;
            let what = match s.action {
                StopAction::NotMoving => "not in operation enabled: nothing to stop",
                StopAction::Halted => "halted",
                StopAction::QuickStopped => "halt did not stop the axis: quick stop",
            };
            let pos = s.position.map_or_else(String::new, |p| format!(" at position {p}"));
            done(node, format!("{what}{pos}"), s.statusword)
        }
        DriveCmd::Reset => {
            let reset = d.fault_reset().await.map_err(ex)?;
            let sw = d.statusword().await.map_err(ex)?;
            let msg = if reset { "fault reset" } else { "no fault to reset: left as it is" };
            done(node, msg.into(), sw)
        }
        DriveCmd::Move(a) => {
            require_enabled().await?;
            d.set_mode(mode::PP).await.map_err(ex)?;
            if let Some(v) = a.velocity {
                d.write_raw(0x6081, 0, &v.to_le_bytes()).await.map_err(ex)?;
            }
            if let Some(acc) = a.acceleration {
                d.write_raw(0x6083, 0, &acc.to_le_bytes()).await.map_err(ex)?;
                d.write_raw(0x6084, 0, &acc.to_le_bytes()).await.map_err(ex)?;
            }
            let wait = crate::error::seconds("--wait", a.wait)?.max(Duration::from_millis(10));
            let from = d.position().await;
            let target = match (a.relative, from) {
                (true, Some(p)) => Some(p.saturating_add(a.target)),
                (true, None) => None,
                (false, _) => Some(a.target),
            };
            preflight(&d.motion_limits().await, node, from, target, wait)?;
            let t0 = conn.master.now();
            let r = guarded(
                &d,
                node,
                timeout,
                "the move",
                target,
                false,
                d.move_to(a.target, a.relative, None::<Profile>, wait),
            )
            .await;
            pb.finish_and_clear();
            r?;
            let pos = read_i(0x6064).await.unwrap_or(0);
            let secs = conn.master.now().saturating_duration_since(t0).as_secs_f64();
            done(
                node,
                format!("target reached at {pos} after {secs:.3} s"),
                d.statusword().await.map_err(ex)?,
            )
        }
        DriveCmd::Velocity(a) => {
            require_enabled().await?;
            let r = guarded(&d, node, timeout, "setting the velocity", None, false, async {
                d.set_mode(mode::PV).await?;
                d.velocity(a.value).await?;
                d.controlword(0x0F).await
            })
            .await;
            r?;
            done(node, format!("target velocity {}", a.value), d.statusword().await.map_err(ex)?)
        }
        DriveCmd::Torque(a) => {
            let t = i16::try_from(a.value)
                .map_err(|_| coded("usage", anyhow!("torque {} is outside -32768..32767", a.value)))?;
            require_enabled().await?;
            guarded(&d, node, timeout, "setting the torque", None, false, async {
                d.set_mode(mode::TQ).await?;
                d.torque(t).await?;
                d.controlword(0x0F).await
            })
            .await?;
            done(node, format!("target torque {t} ‰"), d.statusword().await.map_err(ex)?)
        }
        DriveCmd::Home(a) => {
            require_enabled().await?;
            let method = match a.method {
                Some(m) => m,
                None => d.read_raw(0x6098, 0).await.map_err(ex)?.first().map_or(0, |b| *b as i8),
            };
            let wait = crate::error::seconds("--wait", a.wait)?.max(Duration::from_millis(10));
            let r = guarded(&d, node, timeout, "homing", None, true, d.home(method, wait)).await;
            pb.finish_and_clear();
            r?;
            let pos = read_i(0x6064).await.unwrap_or(0);
            done(
                node,
                format!("homing attained (method {method}), position {pos}"),
                d.statusword().await.map_err(ex)?,
            )
        }
    };
    pb.finish_and_clear();
    Ok(report)
}

/// Refuses a move that cannot finish within `wait` at the drive's own
/// profile, before it starts, naming the objects to change.
fn preflight(
    l: &MotionLimits,
    node: u8,
    from: Option<i32>,
    target: Option<i32>,
    wait: Duration,
) -> anyhow::Result<()> {
    let (Some(p), Some(t)) = (from, target) else { return Ok(()) };
    if let Some((lo, hi)) = l.software_limits
        && lo < hi
        && (t < lo || t > hi)
    {
        bail!(coded(
            "refused",
            anyhow!(
                "node {node}: target {t} is outside the software position limits 607Dh ({lo} .. {hi}); nothing was moved"
            )
        ));
    }
    let Some(secs) = l.move_seconds(f64::from(t) - f64::from(p)) else { return Ok(()) };
    if secs > wait.as_secs_f64() {
        let v = l.effective_velocity().unwrap_or(0);
        let need = format!("at least {}", human_secs(secs));
        return Err(coded(
            "refused",
            anyhow!(
                "node {node}: the move from {p} to {t} would take {need} at {v} units/s (6081h profile velocity{}), longer than --wait {} s; nothing was moved. Give --velocity (and --acceleration), raise 6081h/6083h, or --wait.\n  {}",
                if l.max_profile_velocity.is_some_and(|m| m > 0 && Some(m) < l.profile_velocity) {
                    ", capped by 607Fh"
                } else {
                    ""
                },
                wait.as_secs_f64(),
                l.describe(from, target, false).join("\n  ")
            ),
        ));
    }
    Ok(())
}
