//! PDO configuration: `GET /api/nodes/{n}/pdo` and
//! `PUT /api/nodes/{n}/pdo/{rx|tx}/{k}`, through the master's one PDO
//! procedure (`Master::try_write_pdo`, as `drivebus pdo map`).

use std::sync::Arc;

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use drivebus_master::{ConfigError, PdoDir, PdoMapEntry, PdoRecord};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::{body, seen_node};
use super::error::{ApiError, ApiResult};

/// The highest PDO number CiA 301 has (1400h..15FFh, 1800h..19FFh).
const MAX_PDO: u16 = 512;

/// The entries a mapping record holds (sub-indices 1..40h).
const MAX_ENTRIES: usize = 64;

fn record_json(web: &Web, num: u16, r: &PdoRecord) -> Json_ {
    let mapping: Vec<Json_> = r
        .mapping
        .iter()
        .map(|m| {
            json!({"index": format!("{:04X}", m.index), "sub": m.sub, "bits": m.bits,
            "name": web.dict.name(m.index, m.sub)})
        })
        .collect();
    json!({"num": num, "cob_id": format!("{:03X}", r.can_id()), "valid": r.valid(),
        "transmission_type": r.transmission_type, "inhibit_time": r.inhibit_time,
        "event_timer": r.event_timer, "mapping": mapping})
}

/// `GET /api/nodes/{n}/pdo`: communication and mapping of RPDO/TPDO 1..4
/// (PDOs the node does not have are left out).
pub async fn list(State(web): State<Arc<Web>>, Path(n): Path<String>) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let mut out = [Vec::new(), Vec::new()];
    for (dir, list) in [PdoDir::Rx, PdoDir::Tx].into_iter().zip(out.iter_mut()) {
        for num in 1..=4u16 {
            let Ok(r) = web.master.read_pdo(node, dir, num).await else { break };
            list.push(record_json(&web, num, &r));
        }
    }
    let [rpdo, tpdo] = out;
    Ok(Json(json!({"node": node, "rpdo": rpdo, "tpdo": tpdo})))
}

/// The body of a PDO write.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PdoWrite {
    /// Hex string (`"181"`, `"0x181"`) or a number; default: the current one.
    cob_id: Option<Json_>,
    /// Default true (bit 31 clear).
    valid: Option<bool>,
    transmission_type: Option<u8>,
    /// 100 µs units; absent: left as it is.
    inhibit_time: Option<u16>,
    /// ms; absent: left as it is.
    event_timer: Option<u16>,
    mapping: Vec<MapEntry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct MapEntry {
    /// Hex (`"6041"`) or a name, or a number.
    index: Json_,
    #[serde(default)]
    sub: Option<Json_>,
    /// Default: the size of the object's type.
    bits: Option<u8>,
}

const SHAPE: &str = r#"{"cob_id": "181", "transmission_type": 255, "inhibit_time": 0, "event_timer": 100, "mapping": [{"index": "6041", "sub": 0, "bits": 16}]} (all but "mapping" optional)"#;

/// `rx`/`rpdo` or `tx`/`tpdo`, and 1..512.
fn which(dir: &str, num: &str) -> ApiResult<(PdoDir, u16)> {
    let dir = match dir.to_ascii_lowercase().as_str() {
        "rx" | "rpdo" => PdoDir::Rx,
        "tx" | "tpdo" => PdoDir::Tx,
        other => {
            return Err(ApiError::bad(format!(
                "`{other}` is not a PDO direction: use /api/nodes/N/pdo/rx/K (RPDO) or /pdo/tx/K (TPDO)"
            )));
        }
    };
    let num = num.parse::<u16>().ok().filter(|k| (1..=MAX_PDO).contains(k)).ok_or_else(|| {
        ApiError::bad(format!("`{num}` is not a PDO number: use 1..{MAX_PDO} (TPDO1 is 1800h/1A00h)"))
    })?;
    Ok((dir, num))
}

/// A number from JSON: a number, or a string in hex (`"181"`, `"0x181"`).
fn hex_or_number(v: &Json_, what: &str) -> ApiResult<u32> {
    let n = match v {
        Json_::Number(n) => n.as_u64().and_then(|n| u32::try_from(n).ok()),
        Json_::String(s) => crate::dict::hex(s),
        _ => None,
    };
    n.ok_or_else(|| {
        ApiError::bad(format!("{what} {v} is not a number: give hex as a string (\"181\") or a number"))
    })
}

fn entry(web: &Web, node: u8, e: &MapEntry) -> ApiResult<PdoMapEntry> {
    let (index, named_sub) = match &e.index {
        Json_::String(s) => web.dict.resolve(s, None).map_err(|err| {
            ApiError::bad(format!("mapping index `{s}`: {err}; give it in hex (\"6041\") or by name"))
        })?,
        v => {
            let i = hex_or_number(v, "mapping index")?;
            let i = u16::try_from(i)
                .map_err(|_| ApiError::bad(format!("mapping index {i:#X} is above FFFFh")))?;
            (i, None)
        }
    };
    let sub = match &e.sub {
        Some(v) => {
            let s = hex_or_number(v, "mapping sub")?;
            u8::try_from(s).map_err(|_| ApiError::bad(format!("mapping sub-index {s:#X} is above FFh")))?
        }
        None => named_sub.unwrap_or(0),
    };
    let bits = match e.bits {
        Some(b) if (1..=64).contains(&b) => b,
        Some(b) => {
            return Err(ApiError::bad(format!(
                "mapping {index:04X}h:{sub:02X}h: {b} bits; an entry is 1..64 bits"
            )));
        }
        None => {
            let dt = web.dict.data_type(index, sub).or_else(|| web.master.sdo(node).data_type(index, sub));
            let bytes = dt.and_then(|t| t.fixed_size()).ok_or_else(|| {
                ApiError::bad(format!(
                    "the size of {index:04X}h:{sub:02X}h is unknown (no EDS entry): add \"bits\": 16 (or 8, 32, ...)"
                ))
            })?;
            (bytes * 8) as u8
        }
    };
    Ok(PdoMapEntry::new(index, sub, bits))
}

/// The device's refusal, and what is in force now.
fn refused(node: u8, dir: PdoDir, num: u16, e: drivebus_master::PdoWriteError) -> ApiError {
    let name = if dir == PdoDir::Rx { "RPDO" } else { "TPDO" };
    let mut err = match e.cause {
        ConfigError::Sdo { index, sub, error } => ApiError::sdo(node, index, sub, &error),
        other => ApiError { status: StatusCode::BAD_GATEWAY, message: other.to_string() },
    };
    let outcome = match (&e.previous, &e.restored) {
        (None, _) => "nothing was changed".to_owned(),
        (Some(_), Ok(())) => format!("the previous configuration of {name}{num} is in force again"),
        (Some(_), Err(re)) => format!(
            "restoring the previous configuration failed too ({re}): {name}{num} may be invalid; GET /api/nodes/{node}/pdo shows it"
        ),
    };
    err.message = format!("node {node}: {name}{num} refused: {}; {outcome}", err.message);
    err
}

/// `PUT /api/nodes/{n}/pdo/{rx|tx}/{k}`: writes the PDO with the CiA 301
/// procedure (invalidate, parameters, mapping, validate); a refusal puts
/// the previous configuration back. Answers the PDO as read back.
pub async fn write(
    State(web): State<Arc<Web>>,
    Path((n, dir, num)): Path<(String, String, String)>,
    b: Bytes,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let (dir, num) = which(&dir, &num)?;
    let w: PdoWrite = body(&b, SHAPE)?;
    if w.mapping.len() > MAX_ENTRIES {
        return Err(ApiError::bad(format!(
            "{} mapping entries: a PDO maps at most {MAX_ENTRIES}; nothing was sent",
            w.mapping.len()
        )));
    }
    let mapping = w.mapping.iter().map(|e| entry(&web, node, e)).collect::<ApiResult<Vec<_>>>()?;
    let cob = w.cob_id.as_ref().map(|v| hex_or_number(v, "cob_id")).transpose()?;
    if let Some(c) = cob
        && c & 0x1FFF_FFFF > 0x7FF
        && c & 0x2000_0000 == 0
    {
        return Err(ApiError::bad(format!(
            "cob_id {c:#X} is above 7FFh: give an 11-bit CAN identifier; nothing was sent"
        )));
    }
    let current = web
        .master
        .read_pdo(node, dir, num)
        .await
        .map_err(|e| ApiError::sdo(node, dir.comm_index(num), 1, &e))?;
    let invalid = if w.valid.unwrap_or(true) { 0 } else { 0x8000_0000 };
    let rec = PdoRecord {
        cob_id: (cob.unwrap_or(current.cob_id) & !0x8000_0000) | invalid,
        transmission_type: w.transmission_type.unwrap_or(current.transmission_type),
        inhibit_time: w.inhibit_time,
        event_timer: w.event_timer,
        sync_start: None,
        mapping,
    };
    tracing::info!(
        node,
        pdo = format_args!("{dir:?}{num}"),
        cob_id = format_args!("{:X}", rec.cob_id),
        entries = rec.mapping.len(),
        "web: PDO write"
    );
    web.master.try_write_pdo(node, dir, num, &rec).await.map_err(|e| refused(node, dir, num, e))?;
    let now = web
        .master
        .read_pdo(node, dir, num)
        .await
        .map_err(|e| ApiError::sdo(node, dir.comm_index(num), 1, &e))?;
    Ok(Json(json!({"node": node, "dir": if dir == PdoDir::Rx { "rx" } else { "tx" }, "written": true,
        "pdo": record_json(&web, num, &now)})))
}
