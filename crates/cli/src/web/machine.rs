//! Machine inputs and faults of the drives this process hosts (`serve
//! --drive ... --http`): `GET /api/nodes/{n}/machine` (what is in force),
//! `POST /api/nodes/{n}/machine/input` and `/machine/fault`, carried out by the control interface
//! (`crate::control::Control`, as `serve --control` and `drivebus
//! control`), so they go through the drive's machine schedule.

use std::sync::Arc;

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, State};
use drivebus_personality::machine::{Change, InForce, MachineError};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::body;
use super::error::{ApiError, ApiResult};
use super::values;
use crate::control::{Control, ControlRequest};

/// The body of an input change (as a machine file's `[[node.inputs]]`).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct InputBody {
    input: String,
    line: Option<u8>,
    value: f64,
    duration: Option<f64>,
}

/// The body of a fault (as a machine file's `[[node.faults]]`), or `clear`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FaultBody {
    kind: String,
    switch: Option<String>,
    duration: Option<f64>,
}

/// The control of the node's host, or 404 when this process hosts no
/// such drive.
async fn hosted<'a>(web: &'a Web, n: &str) -> ApiResult<(u8, &'a Control)> {
    let node = values::node_id(n)?;
    match web.control.as_deref() {
        Some(c) if c.serves(node).await => Ok((node, c)),
        _ => Err(ApiError::not_found(format!(
            "node {node} is not a drive this process hosts: machine inputs and faults are for `drivebus serve --drive ... --http` drives (docs/machine.md)"
        ))),
    }
}

fn check_duration(d: Option<f64>) -> ApiResult<()> {
    match d {
        Some(s) if !(s.is_finite() && s > 0.0) => Err(ApiError::bad(format!(
            "duration {s}: give seconds above 0, or leave it out (until changed again)"
        ))),
        _ => Ok(()),
    }
}

/// Carries out `req` with the control interface's reason for a refusal:
/// 400 when the machine refuses the value (a line it does not have),
/// 409 when the node cannot take it now (powered off).
async fn run(control: &Control, req: ControlRequest) -> ApiResult<()> {
    control.handle(req).await.map_err(|e| {
        if e.downcast_ref::<MachineError>().is_some() {
            ApiError::bad(format!("{e:#}; nothing was changed (docs/machine.md gives the ranges)"))
        } else {
            ApiError::conflict(format!("{e:#}"))
        }
    })
}

/// `POST /api/nodes/{n}/machine/input` with
/// `{"input": "digital", "line": 3, "value": 1, "duration": 0.5}`.
pub async fn input(State(web): State<Arc<Web>>, Path(n): Path<String>, b: Bytes) -> ApiResult<Json<Json_>> {
    let (node, control) = hosted(&web, &n).await?;
    let i: InputBody = body(&b, r#"{"input": "digital", "line": 3, "value": 1} ("duration" in s optional)"#)?;
    // Checked before anything changes: the names and ranges of docs/machine.md.
    Change::input(&i.input, i.line, i.value).map_err(|e| ApiError::bad(format!("input: {e}")))?;
    check_duration(i.duration)?;
    tracing::info!(node, input = %i.input, line = ?i.line, value = i.value, duration = ?i.duration, "web: machine input");
    let req = ControlRequest::Input {
        node,
        input: i.input.clone(),
        line: i.line,
        value: i.value,
        duration: i.duration,
    };
    run(control, req).await?;
    Ok(Json(
        json!({"node": node, "input": i.input, "line": i.line, "value": i.value, "duration": i.duration, "set": true}),
    ))
}

/// `POST /api/nodes/{n}/machine/fault` with
/// `{"kind": "trip", "switch": "positive_limit", "duration": 2}` or
/// `{"kind": "clear"}`.
pub async fn fault(State(web): State<Arc<Web>>, Path(n): Path<String>, b: Bytes) -> ApiResult<Json<Json_>> {
    let (node, control) = hosted(&web, &n).await?;
    let f: FaultBody = body(
        &b,
        r#"{"kind": "trip", "switch": "positive_limit"} or {"kind": "clear"} ("duration" in s optional)"#,
    )?;
    Change::fault(&f.kind, f.switch.as_deref()).map_err(|e| ApiError::bad(format!("fault: {e}")))?;
    check_duration(f.duration)?;
    tracing::info!(node, kind = %f.kind, switch = ?f.switch, duration = ?f.duration, "web: machine fault");
    let req =
        ControlRequest::Fault { node, kind: f.kind.clone(), switch: f.switch.clone(), duration: f.duration };
    run(control, req).await?;
    Ok(Json(json!({"node": node, "kind": f.kind, "switch": f.switch, "duration": f.duration, "set": true})))
}

/// One change in force as the API gives it: named as in the POST bodies.
fn in_force_json(f: &InForce) -> Json_ {
    let timing = |mut j: Json_| {
        j["active_s"] = json!(f.active);
        j["remaining_s"] = json!(f.remaining);
        j
    };
    match f.change {
        Change::Fault(k) => {
            let (kind, switch) = k.names();
            timing(json!({"kind": kind, "switch": switch}))
        }
        Change::Input(i) => {
            let (input, line, value) = i.names();
            timing(json!({"input": input, "line": line, "value": value}))
        }
        Change::ClearFaults => Json_::Null,
    }
}

/// `GET /api/nodes/{n}/machine`: the machine's faults and input changes
/// in force now (the machine file's and those made at run time), in the
/// order they began.
pub async fn state(State(web): State<Arc<Web>>, Path(n): Path<String>) -> ApiResult<Json<Json_>> {
    let (node, control) = hosted(&web, &n).await?;
    let now = control.in_force(node).await.map_err(|e| ApiError::conflict(format!("{e:#}")))?;
    let (faults, inputs): (Vec<&InForce>, Vec<&InForce>) =
        now.iter().partition(|f| matches!(f.change, Change::Fault(_)));
    Ok(Json(json!({
        "node": node,
        "faults": faults.into_iter().map(in_force_json).collect::<Vec<_>>(),
        "inputs": inputs.into_iter().map(in_force_json).collect::<Vec<_>>(),
    })))
}
