//! REST over the CiA 309-1 services, in the spirit of CiA 309-5: nodes,
//! SDO, NMT, the EMCY history (docs/http-api.md).

use std::sync::Arc;
use std::time::Duration;

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, Query, State};
use drivebus_master::{DriveState, NmtCommand, RemoteState};
use serde::de::DeserializeOwned;
use serde_json::{Value as Json_, json};

use super::Web;
use super::error::{ApiError, ApiResult};
use super::values;

/// A JSON body, or 400 naming what is wrong with it.
pub fn body<T: DeserializeOwned>(b: &Bytes, shape: &str) -> ApiResult<T> {
    serde_json::from_slice(b).map_err(|e| ApiError::bad(format!("malformed JSON body: {e}; send {shape}")))
}

/// The node of the path: a valid ID the master has heard, else 400/404.
pub fn seen_node(web: &Web, n: &str) -> ApiResult<u8> {
    let node = values::node_id(n)?;
    if !web.master.seen_nodes().contains(&node) {
        return Err(ApiError::not_found(format!(
            "node {node} has not been seen on the bus: GET /api/nodes lists the nodes heard (boot-up, heartbeat, SDO)"
        )));
    }
    Ok(node)
}

/// The NMT state as a word.
pub fn nmt_name(s: RemoteState) -> String {
    match s {
        RemoteState::BootUp => "boot-up".into(),
        RemoteState::Stopped => "stopped".into(),
        RemoteState::Operational => "operational".into(),
        RemoteState::PreOperational => "pre-operational".into(),
        RemoteState::Other(c) => format!("unknown ({c:02X}h)"),
    }
}

/// `GET /api/nodes`: every node heard, with 1018h, NMT state, heartbeat
/// age and, for a CiA 402 device (1000h), the state from 6041h.
pub async fn nodes(State(web): State<Arc<Web>>) -> ApiResult<Json<Json_>> {
    let mut out = Vec::new();
    for node in web.master.seen_nodes() {
        let sdo = web.master.sdo(node);
        let status = web.master.node_status(node).unwrap_or_default();
        let age =
            status.last_heartbeat.map(|t| web.master.now().saturating_duration_since(t).as_millis() as u64);
        // A stopped node answers no SDO: no waiting for timeouts.
        let stopped = status.state == Some(RemoteState::Stopped);
        let device_type = if stopped { None } else { sdo.read::<u32>(0x1000, 0).await.ok() };
        let mut identity = serde_json::Map::new();
        let subs = if stopped {
            &[][..]
        } else {
            &[(1, "vendor_id"), (2, "product_code"), (3, "revision"), (4, "serial")][..]
        };
        for &(sub, key) in subs {
            if let Ok(v) = sdo.read::<u32>(0x1018, sub).await {
                identity.insert(key.into(), json!(v));
            }
        }
        let mut drive = Json_::Null;
        if device_type.is_some_and(|t| t & 0xFFFF == 402)
            && let Ok(sw) = sdo.read::<u16>(0x6041, 0).await
        {
            drive = json!({"statusword": sw, "state": DriveState::from_statusword(sw).name()});
        }
        out.push(json!({"node": node, "device_type": device_type, "identity": identity,
            "personality": web.profile(node).map(|p| p.name()),
            "nmt": status.state.map(nmt_name), "heartbeat_age_ms": age, "lost": status.lost, "drive": drive}));
    }
    Ok(Json(json!({ "nodes": out })))
}

/// `?type=u16`: read or write as this type.
#[derive(serde::Deserialize)]
pub struct TypeQuery {
    /// The type name (`u16`, `UNSIGNED16`, ...).
    #[serde(rename = "type")]
    pub ty: Option<String>,
}

async fn read(web: &Web, node: u8, index: u16, sub: u8, ty: Option<&str>) -> ApiResult<Json<Json_>> {
    let sdo = web.master.sdo(node);
    let dt = match ty {
        Some(t) => Some(values::data_type(t)?),
        None => web.dict.data_type(index, sub).or_else(|| sdo.data_type(index, sub)),
    };
    let raw = sdo.upload(index, sub).await.map_err(|e| ApiError::sdo(node, index, sub, &e))?;
    Ok(Json(values::read_answer(node, (index, sub), web.dict.name(index, sub), dt, &raw, "answered")?))
}

/// `GET /api/nodes/{n}/sdo/{index}/{sub}`.
pub async fn sdo_get(
    State(web): State<Arc<Web>>,
    Path((n, index, sub)): Path<(String, String, String)>,
    Query(q): Query<TypeQuery>,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let (index, sub) = values::object(&web.dict, &index, Some(&sub))?;
    read(&web, node, index, sub, q.ty.as_deref()).await
}

/// `GET /api/nodes/{n}/sdo/{object}`: sub-index 0 or the named entry.
pub async fn sdo_get_object(
    State(web): State<Arc<Web>>,
    Path((n, index)): Path<(String, String)>,
    Query(q): Query<TypeQuery>,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let (index, sub) = values::object(&web.dict, &index, None)?;
    read(&web, node, index, sub, q.ty.as_deref()).await
}

#[derive(serde::Deserialize)]
struct Write {
    value: Json_,
    #[serde(rename = "type")]
    ty: Option<String>,
}

async fn write(web: &Web, node: u8, index: u16, sub: u8, b: &Bytes) -> ApiResult<Json<Json_>> {
    let w: Write =
        body(b, r#"{"value": 6, "type": "u16"} ("type" optional for objects the dictionary knows)"#)?;
    let sdo = web.master.sdo(node);
    let dt = match &w.ty {
        Some(t) => values::data_type(t)?,
        None => web.dict.data_type(index, sub).or_else(|| sdo.data_type(index, sub)).ok_or_else(|| {
            ApiError::bad(format!(
                "the data type of {index:04X}h:{sub:02X}h is unknown (no EDS entry): add \"type\": \"u16\" (or i32, ...) to the body"
            ))
        })?,
    };
    let value = values::from_json(dt, &w.value)?;
    let data = value.encode(dt).map_err(|a| ApiError::bad(format!("{value} as {}: {a}", dt.name())))?;
    if let Some(od) = super::objects::dictionary(web, node)
        && let Some(e) = od.get(index, sub)
        && e.data_type == dt
    {
        super::objects::check_limits(e, index, sub, &value, &data)?;
    }
    tracing::info!(node, index = format_args!("{index:04X}"), sub, value = %value, "web: SDO write");
    sdo.download(index, sub, &data).await.map_err(|e| ApiError::sdo(node, index, sub, &e))?;
    Ok(Json(json!({"node": node, "index": format!("{index:04X}"), "sub": sub, "type": dt.name(),
        "value": values::to_json(&value), "written": true})))
}

/// `PUT /api/nodes/{n}/sdo/{index}/{sub}` with `{"value":..., "type":...}`.
pub async fn sdo_put(
    State(web): State<Arc<Web>>,
    Path((n, index, sub)): Path<(String, String, String)>,
    b: Bytes,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let (index, sub) = values::object(&web.dict, &index, Some(&sub))?;
    write(&web, node, index, sub, &b).await
}

/// `PUT /api/nodes/{n}/sdo/{object}`.
pub async fn sdo_put_object(
    State(web): State<Arc<Web>>,
    Path((n, index)): Path<(String, String)>,
    b: Bytes,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let (index, sub) = values::object(&web.dict, &index, None)?;
    write(&web, node, index, sub, &b).await
}

#[derive(serde::Deserialize)]
struct Nmt {
    command: String,
}

/// `POST /api/nodes/{n}/nmt` with `{"command": "start|stop|preop|reset|reset-comm"}`.
pub async fn nmt(State(web): State<Arc<Web>>, Path(n): Path<String>, b: Bytes) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let c: Nmt = body(&b, r#"{"command": "start"} (start, stop, preop, reset, reset-comm)"#)?;
    let cmd = match c.command.as_str() {
        "start" => NmtCommand::Start,
        "stop" => NmtCommand::Stop,
        "preop" | "pre-operational" => NmtCommand::EnterPreOperational,
        "reset" | "reset-node" => NmtCommand::ResetNode,
        "reset-comm" | "reset-communication" => NmtCommand::ResetCommunication,
        other => {
            return Err(ApiError::bad(format!(
                "`{other}` is not an NMT command: use start, stop, preop, reset or reset-comm"
            )));
        }
    };
    tracing::info!(node, command = %c.command, "web: NMT");
    let wait = Duration::from_secs(5);
    let r = match cmd {
        NmtCommand::ResetNode => web.master.reset_node(node, wait).await.map_err(|e| e.to_string()),
        NmtCommand::ResetCommunication => {
            web.master.reset_communication(node, wait).await.map_err(|e| e.to_string())
        }
        _ => web.master.nmt(node, cmd).await.map_err(|e| e.to_string()),
    };
    r.map_err(|e| ApiError {
        status: axum::http::StatusCode::GATEWAY_TIMEOUT,
        message: format!("NMT {} to node {node}: {e}; check the node is on the bus", c.command),
    })?;
    Ok(Json(json!({"node": node, "command": c.command, "sent": true})))
}

/// `GET /api/emcy`: the EMCYs since start (the last 256), oldest first.
pub async fn emcy(State(web): State<Arc<Web>>) -> Json<Json_> {
    let h = web.emcy.lock().unwrap_or_else(|e| e.into_inner());
    Json(json!({ "emcy": h.iter().cloned().collect::<Vec<_>>() }))
}
