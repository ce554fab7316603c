//! `drivebus drive ...`: CiA 402 device control with the master's `Drive`
//! handle (controlword/statusword by PDO where mapped and the node is
//! operational, else by SDO, so it works in pre-operational too).

use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{DriveError, Master, MasterConfig, SdoError};

use crate::args::{DriveCmd, Global};
use crate::link::{need_node, open_bus};
use crate::output::outln;

/// The CiA 402 state from a statusword (CiA 402-2 §6.2 table).
pub fn state_name(sw: u16) -> &'static str {
    match sw & 0x6F {
        0x00 | 0x20 => "not ready to switch on",
        0x40 | 0x60 => "switch on disabled",
        0x21 => "ready to switch on",
        0x23 => "switched on",
        0x27 => "operation enabled",
        0x07 => "quick stop active",
        0x0F | 0x2F => "fault reaction active",
        0x08 | 0x28 => "fault",
        _ => "unknown",
    }
}

/// The name of an operation mode (6060h/6061h).
pub fn mode_name(m: i8) -> &'static str {
    match m {
        1 => "profile position",
        2 => "velocity",
        3 => "profile velocity",
        4 => "profile torque",
        6 => "homing",
        7 => "interpolated position",
        8 => "cyclic sync position",
        9 => "cyclic sync velocity",
        10 => "cyclic sync torque",
        0 => "none",
        _ => "manufacturer specific",
    }
}

/// Explains a drive handle error with the node, the abort meaning or the
/// timeout in force.
fn explain(node: u8, timeout: Duration, e: DriveError) -> anyhow::Error {
    match e {
        DriveError::Sdo(SdoError::Timeout) => anyhow!(
            "node {node}: SDO timed out: no response within {} ms (is node {node} on the bus and in pre-operational or operational?)",
            timeout.as_millis()
        ),
        DriveError::Sdo(SdoError::Abort { code, text }) => anyhow!(
            "node {node}: SDO aborted by the device with code 0x{:08X}: {}",
            code.0,
            text.unwrap_or("unknown abort code")
        ),
        DriveError::Timeout { waiting_for, statusword } => anyhow!(
            "node {node}: timed out waiting for {waiting_for} (statusword {statusword:04X}h: {})",
            state_name(statusword)
        ),
        other => anyhow!("node {node}: {other}"),
    }
}

/// Runs a `drive` subcommand through the master's CiA 402 `Drive` handle.
pub async fn run(g: &Global, c: &DriveCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    let timeout = Duration::from_millis(g.timeout.max(1));
    let (bus, _hosted) = open_bus(g).await?;
    let master = Master::with_config(
        bus,
        MasterConfig { sdo_timeout: timeout, sdo_retries: 0, ..MasterConfig::default() },
    );
    let ex = |e: DriveError| explain(node, timeout, e);
    let d =
        master.drive(node).await.map_err(|e| ex(DriveError::Sdo(e)))?.with_timeout(Duration::from_secs(3));
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
    let done = |msg: String, sw: u16| {
        if g.json {
            outln!(
                "{}",
                serde_json::json!({"node": node, "result": msg, "statusword": sw, "state": state_name(sw)})
            );
        } else {
            outln!("node {node}: {msg} (statusword {sw:04X}h, {})", state_name(sw));
        }
    };
    let require_enabled = || async {
        let sw = d.statusword().await.map_err(ex)?;
        if sw & 0x6F != 0x27 {
            bail!(
                "node {node}: drive is not in operation enabled (it is in {}); run `drivebus --node {node} drive enable` first",
                state_name(sw)
            );
        }
        Ok(())
    };
    match c {
        DriveCmd::Status => {
            let sw = d.statusword().await.map_err(ex)?;
            let mode = read_i(0x6061).await.map(|m| m as i8);
            let pos = read_i(0x6064).await;
            let vel = read_i(0x606C).await;
            let err = read_i(0x603F).await.map(|e| e as u16);
            let reg = d.read_raw(0x1001, 0).await.ok().and_then(|v| v.first().copied());
            if g.json {
                outln!(
                    "{}",
                    serde_json::json!({"node": node, "statusword": sw, "state": state_name(sw), "mode": mode,
                        "position": pos, "velocity": vel, "error_code": err, "error_register": reg,
                        "target_reached": sw & 0x400 != 0, "warning": sw & 0x80 != 0})
                );
            } else {
                outln!("node {node}: {} (statusword {sw:04X}h)", state_name(sw));
                if let Some(m) = mode {
                    outln!("  mode      {m} ({})", mode_name(m));
                }
                if let Some(p) = pos {
                    outln!("  position  {p}");
                }
                if let Some(v) = vel {
                    outln!("  velocity  {v}");
                }
                match err {
                    Some(0) | None => outln!("  errors    none"),
                    Some(e) => outln!(
                        "  error     {e:04X}h {} (register {:02X}h)",
                        drivebus_emcy::describe(e).unwrap_or("manufacturer specific"),
                        reg.unwrap_or(0)
                    ),
                }
            }
        }
        DriveCmd::Enable => {
            d.enable().await.map_err(ex)?;
            done("operation enabled".into(), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Disable => {
            d.disable().await.map_err(ex)?;
            done("operation disabled".into(), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Quickstop => {
            d.quick_stop().await.map_err(ex)?;
            done("quick stop".into(), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Reset => {
            d.fault_reset().await.map_err(ex)?;
            done("fault reset".into(), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Move(a) => {
            require_enabled().await?;
            d.set_mode(1).await.map_err(ex)?;
            if let Some(v) = a.velocity {
                d.write_raw(0x6081, 0, &v.to_le_bytes()).await.map_err(ex)?;
            }
            let t0 = tokio::time::Instant::now();
            d.move_to(a.target, a.relative, None, Duration::from_secs_f64(a.wait.clamp(0.01, 86_400.0)))
                .await
                .map_err(ex)?;
            let pos = read_i(0x6064).await.unwrap_or(0);
            let sw = d.statusword().await.map_err(ex)?;
            done(format!("target reached at {pos} after {:.3} s", t0.elapsed().as_secs_f64()), sw);
        }
        DriveCmd::Velocity(a) => {
            require_enabled().await?;
            d.set_mode(3).await.map_err(ex)?;
            d.velocity(a.value).await.map_err(ex)?;
            d.controlword(0x0F).await.map_err(ex)?;
            done(format!("target velocity {}", a.value), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Torque(a) => {
            let t =
                i16::try_from(a.value).map_err(|_| anyhow!("torque {} is outside -32768..32767", a.value))?;
            require_enabled().await?;
            d.set_mode(4).await.map_err(ex)?;
            d.torque(t).await.map_err(ex)?;
            d.controlword(0x0F).await.map_err(ex)?;
            done(format!("target torque {t} ‰"), d.statusword().await.map_err(ex)?);
        }
        DriveCmd::Home(a) => {
            require_enabled().await?;
            let method = match a.method {
                Some(m) => m,
                None => d.read_raw(0x6098, 0).await.map_err(ex)?.first().map_or(0, |b| *b as i8),
            };
            d.home(method, Duration::from_secs_f64(a.wait.clamp(0.01, 86_400.0))).await.map_err(ex)?;
            let pos = read_i(0x6064).await.unwrap_or(0);
            done(format!("homing attained, position {pos}"), d.statusword().await.map_err(ex)?);
        }
    }
    Ok(())
}
