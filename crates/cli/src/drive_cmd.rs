//! `drivebus drive ...`: CiA 402 device control with the master's `RemoteDrive`
//! handle (controlword/statusword by PDO where mapped and the node is
//! operational, else by SDO). Motion a command starts is stopped (halt,
//! else quick stop) when the command fails, times out or is interrupted,
//! and the command says where the axis is and which objects limit it.

use std::future::Future;
use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{
    DriveError, DriveFlags, DriveState, MotionEnd, MotionLimits, MotionProgress, MotionReport, MoveProfile,
    RemoteDrive, SdoError, StopAction, drive::cw, drive::human_secs, drive::mode, drive::sw as bit,
    mode_name,
};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{DriveCmd, Global, HomeArgs, MoveArgs};
use crate::conn::{Conn, need_node};
use crate::error::{coded, coded_with};

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
        DriveError::Stopped(r) => stopped(node, &r),
        DriveError::Transport(why) | DriveError::Sdo(SdoError::Transport(why)) => {
            coded("bus_lost", anyhow!("node {node}: the bus connection was lost: {why}"))
        }
        other => anyhow!("node {node}: {other}"),
    }
}

/// What to do after a motion that ended short of its goal.
fn next_step(node: u8, r: &MotionReport) -> String {
    match r.end {
        MotionEnd::LimitSwitch { positive } => format!(
            "; the drive refuses motion further {}: move back with `drivebus --node {node} drive move TARGET` {} the switch",
            if positive { "in the positive direction" } else { "in the negative direction" },
            if positive { "below" } else { "above" }
        ),
        MotionEnd::SoftwareLimit => "; give a target inside 607Dh".to_owned(),
        MotionEnd::HomingError if r.homing_method == Some(0) || !r.homing_methods.is_empty() => {
            "; give one of them with --method M".to_owned()
        }
        MotionEnd::Fault | MotionEnd::FollowingError => {
            format!("; `drivebus --node {node} drive reset` clears a fault, `drive enable` enables again")
        }
        MotionEnd::QuickStop | MotionEnd::Disabled => {
            format!("; `drivebus --node {node} drive enable` enables again")
        }
        _ => String::new(),
    }
}

/// A motion that ended elsewhere than its goal: the cause first, then
/// where the axis is, then what to do; `--json` gets the report's fields.
fn stopped(node: u8, r: &MotionReport) -> anyhow::Error {
    let what = if r.homing_method.is_some() { "homing" } else { "the move" };
    let mut text = format!("node {node}: {}: {what} stopped at ", r.reason());
    text += &r.position.map_or_else(|| "an unknown position".to_owned(), |p| p.to_string());
    if let (Some(t), Some(left)) = (r.target, r.short_of_target()) {
        text += &format!(", {} short of the target {t}", left.abs());
    }
    text += &format!(
        ", after {:.3} s (statusword {:04X}h, {}){}",
        r.duration.as_secs_f64(),
        r.statusword,
        state_name(r.statusword),
        next_step(node, r)
    );
    coded_with(r.end.code(), Report::from(node, r).0, anyhow!(text))
}

/// The fields of a motion's end for `--json` (success and failure alike).
struct Report(serde_json::Value);

impl Report {
    fn from(node: u8, r: &MotionReport) -> Report {
        Report(serde_json::json!({
            "node": node,
            "outcome": r.end.code(),
            "position": r.position,
            "target": r.target,
            "duration": (r.duration.as_secs_f64() * 1000.0).round() / 1000.0,
            "statusword": r.statusword,
            "state": state_name(r.statusword),
            "reason": r.reason(),
            "inputs": r.inputs,
            "error_code": r.error_code,
            "homing_method": r.homing_method,
            "homing_methods": (!r.homing_methods.is_empty()).then_some(&r.homing_methods),
        }))
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

type Printed = Option<(String, serde_json::Value)>;

/// A command's report: `msg` in words; for `--json` the outcome `code`,
/// the statusword and state, and `fields`.
fn done(node: u8, code: &str, msg: String, sw: u16, fields: serde_json::Value) -> Printed {
    let mut json =
        serde_json::json!({"node": node, "outcome": code, "statusword": sw, "state": state_name(sw)});
    if let (Some(j), serde_json::Value::Object(f)) = (json.as_object_mut(), fields) {
        j.extend(f);
    }
    Some((format!("node {node}: {msg} (statusword {sw:04X}h, {})", state_name(sw)), json))
}

/// Runs `motion`; on an error, a timeout or Ctrl-C stops the axis and
/// explains where it is and what limits it.
async fn guarded<T>(
    d: &RemoteDrive,
    node: u8,
    timeout: Duration,
    what: &str,
    target: Option<i32>,
    homing: bool,
    motion: impl Future<Output = Result<T, DriveError>>,
) -> anyhow::Result<T> {
    let interrupted = crate::serve::wait_for_signal();
    let r = tokio::select! {
        r = motion => match r {
            // The axis stands already (at a limit, halted, faulted): nothing to stop.
            Err(DriveError::Stopped(s)) => return Err(stopped(node, &s)),
            r => r.map_err(|e| explain(node, timeout, e)),
        },
        Ok(()) = interrupted => Err(coded("interrupted", anyhow!("node {node}: {what} interrupted (Ctrl-C)"))),
    };
    let Err(e) = r else { return r };
    let (code, _) = crate::error::describe(&e);
    let cause = crate::error::render(&e);
    if code == "bus_lost" {
        return Err(coded(
            code,
            anyhow!("{cause} during {what}; the axis could not be stopped from here: it may still be moving"),
        ));
    }
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
    let mut text = format!("{cause}; {stop}");
    if !lines.is_empty() {
        text.push_str("; objects that shape this motion:\n  ");
        text.push_str(&lines.join("\n  "));
    }
    Err(coded(code, anyhow!(text)))
}

async fn run_on(g: &Global, conn: &Conn, node: u8, c: &DriveCmd) -> anyhow::Result<Printed> {
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
    let report = match c {
        DriveCmd::Status => status(&d, node, ex).await?,
        DriveCmd::Enable => {
            d.enable().await.map_err(ex)?;
            done(
                node,
                "operation_enabled",
                "operation enabled".into(),
                d.statusword().await.map_err(ex)?,
                serde_json::json!({}),
            )
        }
        DriveCmd::Disable => {
            d.disable().await.map_err(ex)?;
            done(
                node,
                "disabled",
                "operation disabled".into(),
                d.statusword().await.map_err(ex)?,
                serde_json::json!({}),
            )
        }
        DriveCmd::Quickstop => {
            d.quick_stop().await.map_err(ex)?;
            done(
                node,
                "quick_stop",
                "quick stop".into(),
                d.statusword().await.map_err(ex)?,
                serde_json::json!({}),
            )
        }
        DriveCmd::Stop => stop(&d, node, ex).await?,
        DriveCmd::Reset => {
            let reset = d.fault_reset().await.map_err(ex)?;
            let sw = d.statusword().await.map_err(ex)?;
            let (code, msg) = if reset {
                ("fault_reset", "fault reset")
            } else {
                ("no_fault", "no fault to reset: left as it is")
            };
            done(node, code, msg.into(), sw, serde_json::json!({}))
        }
        DriveCmd::Move(a) => move_axis(&d, node, timeout, a, &pb, ex).await?,
        DriveCmd::Velocity(a) => velocity(&d, node, timeout, a.value, ex).await?,
        DriveCmd::Torque(a) => torque(&d, node, timeout, a.value, ex).await?,
        DriveCmd::Home(a) => home(&d, node, timeout, a, &pb, ex).await?,
    };
    pb.finish_and_clear();
    Ok(report)
}

/// `drive stop`: halt, then quick stop if the axis goes on.
async fn stop(
    d: &RemoteDrive,
    node: u8,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    let s = d.stop_motion(Duration::from_secs(5)).await.map_err(ex)?;
    let (code, what) = match s.action {
        StopAction::NotMoving => ("not_moving", "not in operation enabled: nothing to stop"),
        StopAction::Halted => ("halted", "halted"),
        StopAction::QuickStopped => ("quick_stopped", "halt did not stop the axis: quick stop"),
    };
    let pos = s.position.map_or_else(String::new, |p| format!(" at position {p}"));
    Ok(done(node, code, format!("{what}{pos}"), s.statusword, serde_json::json!({"position": s.position})))
}

/// `drive velocity V`: profile velocity mode at V.
async fn velocity(
    d: &RemoteDrive,
    node: u8,
    timeout: Duration,
    value: i32,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    require_enabled(d, node, &ex).await?;
    let r = guarded(d, node, timeout, "setting the velocity", None, false, async {
        d.set_mode(mode::PV).await?;
        d.velocity(value).await?;
        d.controlword(cw::ENABLE_OPERATION).await
    })
    .await;
    r?;
    let sw = d.statusword().await.map_err(ex)?;
    Ok(done(
        node,
        "target_velocity",
        format!("target velocity {}", value),
        sw,
        serde_json::json!({"velocity": value}),
    ))
}

/// `drive torque T` (per mille of the rated torque): profile torque mode.
async fn torque(
    d: &RemoteDrive,
    node: u8,
    timeout: Duration,
    value: i32,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    let t = i16::try_from(value)
        .map_err(|_| coded("usage", anyhow!("torque {} is outside -32768..32767", value)))?;
    require_enabled(d, node, &ex).await?;
    guarded(d, node, timeout, "setting the torque", None, false, async {
        d.set_mode(mode::TQ).await?;
        d.torque(t).await?;
        d.controlword(cw::ENABLE_OPERATION).await
    })
    .await?;
    let sw = d.statusword().await.map_err(ex)?;
    Ok(done(node, "target_torque", format!("target torque {t} ‰"), sw, serde_json::json!({"torque": t})))
}

/// `drive home [--method M]`: the drive's 6098h unless given.
async fn home(
    d: &RemoteDrive,
    node: u8,
    timeout: Duration,
    a: &HomeArgs,
    pb: &ProgressBar,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    require_enabled(d, node, &ex).await?;
    let method = match a.method {
        Some(m) => m,
        None => d.read_raw(0x6098, 0).await.map_err(ex)?.first().map_or(0, |b| *b as i8),
    };
    let wait = crate::error::seconds("--wait", a.wait)?.max(Duration::from_millis(10));
    let r = guarded(d, node, timeout, "homing", None, true, d.home(method, wait)).await;
    pb.finish_and_clear();
    Ok(reached(node, &r?))
}

/// Refuses a motion command unless the drive is in operation enabled.
async fn require_enabled(
    d: &RemoteDrive,
    node: u8,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<()> {
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
}

/// A signed integer object of 1, 2 or 4 bytes; `None` when it cannot be read.
async fn read_int(d: &RemoteDrive, index: u16) -> Option<i64> {
    let v = d.read_raw(index, 0).await.ok()?;
    Some(match v.len() {
        1 => i64::from(v[0] as i8),
        2 => i64::from(i16::from_le_bytes([v[0], v[1]])),
        4 => i64::from(i32::from_le_bytes([v[0], v[1], v[2], v[3]])),
        _ => return None,
    })
}

/// `drive status`: state, mode, position, velocity, flags, inputs, error.
async fn status(
    d: &RemoteDrive,
    node: u8,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    let sw = d.statusword().await.map_err(&ex)?;
    let mode = read_int(d, 0x6061).await.map(|m| m as i8);
    let pos = read_int(d, 0x6064).await;
    let vel = read_int(d, 0x606C).await;
    let err = read_int(d, 0x603F).await.map(|e| e as u16);
    let reg = d.read_raw(0x1001, 0).await.ok().and_then(|v| v.first().copied());
    let inputs = d.digital_inputs().await;
    let flags = DriveFlags { statusword: sw, inputs, mode };
    let bits = flags.statusword_text();
    let active = inputs.map(DriveFlags::inputs_text).unwrap_or_default();
    let json = serde_json::json!({"node": node, "statusword": sw, "state": state_name(sw), "mode": mode,
        "mode_name": mode.map(mode_name), "position": pos, "velocity": vel, "error_code": err, "error_register": reg,
        "target_reached": sw & bit::TARGET_REACHED != 0, "warning": sw & bit::WARNING != 0,
        "internal_limit": sw & bit::INTERNAL_LIMIT != 0, "bit13": sw & bit::MODE_13 != 0, "statusword_flags": bits, "inputs": inputs,
        "negative_limit_switch": inputs.map(|i| i & 1 != 0), "positive_limit_switch": inputs.map(|i| i & 2 != 0),
        "home_switch": inputs.map(|i| i & 4 != 0)});
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
    if !bits.is_empty() {
        t += &format!("\n  flags     {}", bits.join(", "));
    }
    if !active.is_empty() {
        t += &format!("\n  inputs    {active}");
    }
    t += &match err {
        Some(0) | None if bits.is_empty() => "\n  errors    none".to_owned(),
        Some(0) | None => "\n  errors    none in 603Fh".to_owned(),
        Some(e) => format!(
            "\n  error     {e:04X}h {} (register {:02X}h)",
            drivebus_master::emcy_description(e).unwrap_or("manufacturer specific"),
            reg.unwrap_or(0)
        ),
    };
    Ok(Some((t, json)))
}

/// `drive move`: a profile position move, checked against the limits
/// before anything is written.
async fn move_axis(
    d: &RemoteDrive,
    node: u8,
    timeout: Duration,
    a: &MoveArgs,
    pb: &ProgressBar,
    ex: impl Fn(DriveError) -> anyhow::Error,
) -> anyhow::Result<Printed> {
    require_enabled(d, node, &ex).await?;
    let wait = crate::error::seconds("--wait", a.wait)?.max(Duration::from_millis(10));
    let from = d.position().await;
    let target = match (a.relative, from) {
        (true, Some(p)) => Some(p.saturating_add(a.target)),
        (true, None) => None,
        (false, _) => Some(a.target),
    };
    // Checked with the profile the move would run at, before anything
    // is written: a refused move leaves the drive as it was.
    let mut limits = d.motion_limits().await;
    if let Some(v) = a.velocity {
        limits.profile_velocity = Some(v);
    }
    if let Some(acc) = a.acceleration {
        limits.profile_acceleration = Some(acc);
        limits.profile_deceleration = Some(acc);
    }
    preflight(&limits, node, from, target, wait)?;
    d.set_mode(mode::PP).await.map_err(&ex)?;
    if let Some(v) = a.velocity {
        d.write_raw(0x6081, 0, &v.to_le_bytes()).await.map_err(&ex)?;
    }
    if let Some(acc) = a.acceleration {
        d.write_raw(0x6083, 0, &acc.to_le_bytes()).await.map_err(&ex)?;
        d.write_raw(0x6084, 0, &acc.to_le_bytes()).await.map_err(&ex)?;
    }
    let r = guarded(
        d,
        node,
        timeout,
        "the move",
        target,
        false,
        d.move_to(a.target, a.relative, None::<MoveProfile>, wait),
    )
    .await;
    pb.finish_and_clear();
    Ok(reached(node, &r?))
}

/// The report of a motion that did what it was asked.
fn reached(node: u8, r: &MotionReport) -> Printed {
    let at = r.position.map_or_else(|| "an unknown position".to_owned(), |p| p.to_string());
    let what = match r.homing_method {
        Some(m) => format!("homing attained (method {m}), position {at}"),
        None => format!("target reached at {at} after {:.3} s", r.duration.as_secs_f64()),
    };
    Some((
        format!("node {node}: {what} (statusword {:04X}h, {})", r.statusword, state_name(r.statusword)),
        Report::from(node, r).0,
    ))
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
