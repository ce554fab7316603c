//! `GET/POST /api/nodes/{n}/drive`: the CiA 402 drive panel over the
//! master's `RemoteDrive` (its enable sequence, moves and homing; no second one).

use std::sync::Arc;
use std::time::Duration;

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use drivebus_master::{DriveState, MotionReport, RemoteDrive, drive::mode, mode_name};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::{body, seen_node};
use super::error::{ApiError, ApiResult};

/// How long a move or homing started from the page may take.
const MOTION_LIMIT: Duration = Duration::from_secs(120);

pub(super) async fn handle(web: &Web, node: u8) -> ApiResult<RemoteDrive> {
    let d = web.master.drive(node).await.map_err(|e| ApiError::sdo(node, 0x1A00, 1, &e))?;
    Ok(d.with_timeout(Duration::from_secs(3)))
}

async fn state_json(d: &RemoteDrive, node: u8) -> ApiResult<Json_> {
    let sw = d.statusword().await.map_err(|e| ApiError::drive(node, &e))?;
    let mode = d.read_raw(0x6061, 0).await.ok().and_then(|v| v.first().map(|b| *b as i8));
    Ok(json!({"node": node, "statusword": sw, "state": DriveState::from_statusword(sw).name(),
        "mode": mode, "mode_name": mode.map(mode_name), "position": d.position().await,
        "velocity": d.actual_velocity().await, "target_reached": sw & drivebus_master::drive::sw::TARGET_REACHED != 0,
        "flags": drivebus_master::DriveFlags { statusword: sw, inputs: None, mode }.statusword_text(),
        "switches": d.digital_inputs().await.map(switches_json), "limits": limits_json(d).await}))
}

/// 60FDh as the panel shows it: the CiA 402-2 switch bits and the
/// manufacturer-specific bits 16..31 raw.
fn switches_json(inputs: u32) -> Json_ {
    use drivebus_master::drive::{DI_HOME_SWITCH, DI_INTERLOCK, DI_NEGATIVE_LIMIT, DI_POSITIVE_LIMIT};
    json!({"inputs": inputs, "negative_limit": inputs & DI_NEGATIVE_LIMIT != 0,
        "positive_limit": inputs & DI_POSITIVE_LIMIT != 0, "home_switch": inputs & DI_HOME_SWITCH != 0,
        "interlock": inputs & DI_INTERLOCK != 0, "manufacturer": inputs >> 16})
}

/// A 32-bit object, or `None` when the drive has none (or it is not 4 bytes).
async fn read_u32(d: &RemoteDrive, index: u16, sub: u8) -> Option<u32> {
    let v: [u8; 4] = d.read_raw(index, sub).await.ok()?.as_slice().try_into().ok()?;
    Some(u32::from_le_bytes(v))
}

/// Software position limits 607Dh:01/02 (INTEGER32) and max profile
/// velocity 607Fh (UNSIGNED32); null where the drive has no such object.
async fn limits_json(d: &RemoteDrive) -> Json_ {
    let min = read_u32(d, 0x607D, 1).await.map(|v| v as i32);
    let max = read_u32(d, 0x607D, 2).await.map(|v| v as i32);
    json!({"software_position_min": min, "software_position_max": max,
        "max_profile_velocity": read_u32(d, 0x607F, 0).await})
}

/// `GET /api/nodes/{n}/drive`: state, mode, position, velocity, the
/// switch inputs (60FDh) and the limits (607Dh, 607Fh).
pub async fn status(State(web): State<Arc<Web>>, Path(n): Path<String>) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let d = handle(&web, node).await?;
    Ok(Json(state_json(&d, node).await?))
}

#[derive(serde::Deserialize)]
struct Action {
    action: String,
    target: Option<i32>,
    #[serde(default)]
    relative: bool,
    method: Option<i8>,
    /// Profile velocity 6081h for a move.
    velocity: Option<u32>,
    /// Profile acceleration and deceleration 6083h/6084h for a move.
    acceleration: Option<u32>,
}

const SHAPE: &str = r#"{"action": "enable"} (enable, disable, quick-stop, fault-reset, home with optional "method", move with "target" and optional "relative", "velocity", "acceleration")"#;

/// `POST /api/nodes/{n}/drive`: enable, disable, quick-stop, fault-reset
/// answer when done; home and move answer 202 once started and report
/// their end as a `motion` event on the stream.
pub async fn action(
    State(web): State<Arc<Web>>,
    Path(n): Path<String>,
    b: Bytes,
) -> ApiResult<(StatusCode, Json<Json_>)> {
    let node = seen_node(&web, &n)?;
    let a: Action = body(&b, SHAPE)?;
    if !["enable", "disable", "quick-stop", "fault-reset", "home", "move"].contains(&a.action.as_str()) {
        return Err(ApiError::bad(format!("`{}` is not a drive action: send {SHAPE}", a.action)));
    }
    if a.action == "move" && a.target.is_none() {
        return Err(ApiError::bad(format!("a move needs \"target\" (a position, i32): send {SHAPE}")));
    }
    let d = handle(&web, node).await?;
    tracing::info!(node, action = %a.action, target = ?a.target, "web: drive");
    let ex = |e| ApiError::drive(node, &e);
    match a.action.as_str() {
        "enable" => d.enable().await.map_err(ex)?,
        "disable" => d.disable().await.map_err(ex)?,
        "quick-stop" => d.quick_stop().await.map_err(ex)?,
        "fault-reset" => {
            d.fault_reset().await.map_err(ex)?;
        }
        _ => return start_motion(web, d, node, a).await,
    }
    Ok((StatusCode::OK, Json(state_json(&d, node).await?)))
}

async fn start_motion(
    web: Arc<Web>,
    d: RemoteDrive,
    node: u8,
    a: Action,
) -> ApiResult<(StatusCode, Json<Json_>)> {
    let sw = d.statusword().await.map_err(|e| ApiError::drive(node, &e))?;
    let state = DriveState::from_statusword(sw);
    if state != DriveState::OperationEnabled {
        return Err(ApiError::conflict(format!(
            "node {node} is in {state}, not operation enabled: send {{\"action\": \"enable\"}} first"
        )));
    }
    let homing = a.action == "home";
    let method = match a.method {
        Some(m) => m,
        None if homing => {
            d.read_raw(0x6098, 0).await.ok().and_then(|v| v.first().map(|b| *b as i8)).unwrap_or(0)
        }
        None => 0,
    };
    if !homing {
        let ex = |e| ApiError::drive(node, &e);
        d.set_mode(mode::PP).await.map_err(ex)?;
        if let Some(v) = a.velocity {
            d.write_raw(0x6081, 0, &v.to_le_bytes()).await.map_err(ex)?;
        }
        if let Some(acc) = a.acceleration {
            d.write_raw(0x6083, 0, &acc.to_le_bytes()).await.map_err(ex)?;
            d.write_raw(0x6084, 0, &acc.to_le_bytes()).await.map_err(ex)?;
        }
    }
    let (target, relative) = (a.target.unwrap_or(0), a.relative);
    let w = web.clone();
    tokio::spawn(async move {
        let r = if homing {
            d.home(method, MOTION_LIMIT).await
        } else {
            d.move_to(target, relative, None, MOTION_LIMIT).await
        };
        let end = match &r {
            Ok(rep) => report(rep),
            Err(drivebus_master::DriveError::Stopped(rep)) => report(rep),
            Err(e) => json!({"end": "error", "reason": e.to_string()}),
        };
        tracing::info!(node, result = %end, "web: motion ended");
        w.event(json!({"type": "event", "event": "motion", "t": w.t(), "node": node, "result": end}));
    });
    Ok((
        StatusCode::ACCEPTED,
        Json(json!({"node": node, "action": a.action, "target": a.target,
        "relative": relative, "method": homing.then_some(method), "started": true})),
    ))
}

fn report(r: &MotionReport) -> Json_ {
    json!({"end": r.end.code(), "position": r.position, "reason": r.reason()})
}

/// The standard homing methods of CiA 402-2 (6098h 1..35 and 37).
const CIA402_HOMING: [i8; 36] = {
    let mut m = [0i8; 36];
    let mut i = 0;
    while i < 35 {
        m[i] = i as i8 + 1;
        i += 1;
    }
    m[35] = 37;
    m
};

/// `GET /api/nodes/{n}/drive/homing`: the homing methods the drive offers
/// (60E3h), else those the personality (hosted or identified) accepts (its manual), else
/// the CiA 402 list; with 6098h, the method set now.
pub async fn homing(State(web): State<Arc<Web>>, Path(n): Path<String>) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let d = handle(&web, node).await?;
    let offered = d.homing_methods().await;
    let (methods, source) = if !offered.is_empty() {
        (offered, "60E3h".to_owned())
    } else if let Some(p) = web.profile(node) {
        (p.info().homing_methods.to_vec(), format!("the {} manual", p.name()))
    } else {
        (CIA402_HOMING.to_vec(), "CiA 402".to_owned())
    };
    let current = d.read_raw(0x6098, 0).await.ok().and_then(|v| v.first().map(|b| *b as i8));
    Ok(Json(json!({"node": node, "methods": methods, "source": source, "current": current})))
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_cia402_homing_list_is_1_to_35_and_37() {
        assert_eq!(super::CIA402_HOMING[0], 1);
        assert_eq!(super::CIA402_HOMING[34], 35);
        assert_eq!(super::CIA402_HOMING[35], 37);
        assert!(!super::CIA402_HOMING.contains(&36));
    }
}
