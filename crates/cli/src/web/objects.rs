//! `GET /api/nodes/{n}/objects`: the node's object dictionary as its EDS
//! describes it (names, types, access, limits, defaults), searchable; and
//! the EDS limits a write is checked against before anything is sent.

use std::sync::Arc;

use axum::Json;
use axum::extract::{Path, Query, State};
use drivebus_master::{DataType, Value};
use drivebus_od::{ObjectDictionary, SubObject};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::seen_node;
use super::error::{ApiError, ApiResult};
use super::values;

/// At most this many entries per answer (the AKD's EDS has ~700).
const MAX_ENTRIES: usize = 2000;

/// `?q=`: a case-insensitive part of the name, or a hex index prefix.
#[derive(serde::Deserialize)]
pub struct Search {
    /// The text searched for.
    pub q: Option<String>,
}

fn limit(dt: DataType, b: &Option<Vec<u8>>) -> Json_ {
    b.as_deref().and_then(|b| Value::decode(dt, b).ok()).map_or(Json_::Null, |v| values::to_json(&v))
}

/// The node's dictionary: the master's (a hosted drive's EDS), else
/// `--eds` read for this node-ID.
pub fn dictionary(web: &Web, node: u8) -> Option<Arc<ObjectDictionary>> {
    web.master
        .eds(node)
        .or_else(|| web.dict.eds.as_ref().and_then(|e| drivebus_eds::to_od(e, node).ok()).map(Arc::new))
}

/// `GET /api/nodes/{n}/objects?q=velocity`.
pub async fn list(
    State(web): State<Arc<Web>>,
    Path(n): Path<String>,
    Query(s): Query<Search>,
) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let od = dictionary(&web, node).ok_or_else(|| {
        ApiError::not_found(format!(
            "no EDS for node {node}: `drivebus ui --eds FILE` gives one (hosted drives have theirs)"
        ))
    })?;
    Ok(Json(json!({"node": node, "objects": entries(&od, s.q.as_deref().unwrap_or_default())})))
}

/// The entries of `od` whose object or entry name contains `q` (any
/// case) or whose index starts with it, one per sub-index, at most
/// [`MAX_ENTRIES`]: names, types, access, limits and defaults.
pub fn entries(od: &ObjectDictionary, q: &str) -> Vec<Json_> {
    let q = q.trim().to_lowercase();
    let hex_q = q.trim_start_matches("0x").trim_end_matches('h').to_uppercase();
    let mut out = Vec::new();
    for o in od.objects() {
        let index = format!("{:04X}", o.index);
        let object_hit = q.is_empty() || index.starts_with(&hex_q) || o.name.to_lowercase().contains(&q);
        for e in o.subs() {
            if !object_hit && !e.name.to_lowercase().contains(&q) {
                continue;
            }
            if out.len() == MAX_ENTRIES {
                return out;
            }
            out.push(json!({"index": index, "sub": e.sub, "object": o.name, "name": e.name,
                "type": e.data_type.name(), "unit": drivebus_objects::unit(o.index, e.sub),
                "access": e.access.name(), "pdo": e.pdo_mappable,
                "low": limit(e.data_type, &e.low_limit), "high": limit(e.data_type, &e.high_limit),
                "default": Value::decode(e.data_type, &e.default).ok().map(|v| values::to_json(&v))}));
        }
    }
    out
}

/// A write outside the EDS's LowLimit/HighLimit, refused before sending.
pub fn check_limits(e: &SubObject, index: u16, sub: u8, value: &Value, data: &[u8]) -> ApiResult<()> {
    if e.data_type.num_kind().is_none() {
        return Ok(());
    }
    match e.validate(data) {
        Ok(()) => Ok(()),
        Err(_) => Err(ApiError::bad(format!(
            "{value} is out of range for {index:04X}h:{sub:02X}h ({}): the EDS allows {} to {}; nothing was sent",
            e.name,
            limit(e.data_type, &e.low_limit),
            limit(e.data_type, &e.high_limit)
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::Access;

    #[test]
    fn limits_refuse_what_the_eds_does_not_allow() {
        let e = SubObject::new(0, "Latch control register", DataType::Unsigned16, Access::Rw, Value::U16(0))
            .limits(Value::U16(0), Value::U16(15));
        assert!(check_limits(&e, 0x20A4, 0, &Value::U16(15), &15u16.to_le_bytes()).is_ok());
        let err = check_limits(&e, 0x20A4, 0, &Value::U16(16), &16u16.to_le_bytes()).unwrap_err();
        assert_eq!(err.status, axum::http::StatusCode::BAD_REQUEST);
        assert!(err.message.contains("allows 0 to 15"), "{}", err.message);
    }
}
