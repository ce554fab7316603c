//! `ethercat serve --http`: the hosted slaves' objects under the CAN
//! side's URLs, the slave's line position standing for the node:
//! `GET/PUT /api/nodes/{position}/sdo/{index}[/{sub}]` and
//! `GET /api/nodes/{position}/objects?q=` (docs/http-api.md). The server
//! hosts the slaves; the external master owns their mailboxes, so reads
//! and writes go straight to the slave's dictionary through its one
//! write path (`drivebus_ethercat::objects`, the path a CoE SDO download
//! takes). Values, types and errors are the CAN side's (`crate::web`).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, Query, State};
use drivebus_ethercat::Host;
use drivebus_ethercat::objects::{self, ObjectError};
use drivebus_master::DataType;
use drivebus_od::ObjectDictionary;
use serde_json::{Value as Json_, json};

use super::http::Served;
use crate::dict::Dict;
use crate::web::api::{TypeQuery, body};
use crate::web::error::{ApiError, ApiResult};
use crate::web::objects::Search;
use crate::web::values;

/// A slave's dictionary as taken once: names, types, access, limits (the
/// values in it are not read; they age).
pub struct ObjectSlot {
    /// The dictionary's description.
    pub od: ObjectDictionary,
    /// Its names, for objects given by name (then CiA 301/402's).
    pub dict: Dict,
}

/// The slots taken so far, by position.
pub type ObjectSlots = Arc<Mutex<HashMap<usize, Arc<ObjectSlot>>>>;

/// An object of a slave that failed: 404 for no such slave or no
/// dictionary, 409 powered off, the SDO abort as on the CAN side.
pub fn object_error(position: usize, index: u16, sub: u8, e: ObjectError) -> ApiError {
    match e {
        ObjectError::NoSlave { .. } => {
            ApiError::not_found(format!("{e}: GET /api/ethercat lists the slaves"))
        }
        ObjectError::NoDictionary { .. } => ApiError::not_found(e.to_string()),
        ObjectError::PoweredOff { .. } => ApiError::conflict(e.to_string()),
        ObjectError::Abort(a) => ApiError::abort(a, &format!("{index:04X}h:{sub:02X}h on slave {position}")),
    }
}

/// The position of the path: a number from 1.
pub fn position(n: &str) -> ApiResult<usize> {
    n.trim().parse::<usize>().ok().filter(|p| *p >= 1).ok_or_else(|| {
        ApiError::bad(format!(
            "`{n}` is not a slave position: use /api/nodes/P/... with P the line position from 1 (GET /api/ethercat)"
        ))
    })
}

/// The slot of `position`, taken from the slave at first use.
pub fn slot(host: &Host, slots: &ObjectSlots, position: usize) -> ApiResult<Arc<ObjectSlot>> {
    if let Some(s) = slots.lock().unwrap_or_else(|e| e.into_inner()).get(&position) {
        return Ok(s.clone());
    }
    let od = objects::dictionary(host, position).map_err(|e| object_error(position, 0, 0, e))?;
    let eds = drivebus_eds::from_od(&od, drivebus_eds::DeviceInfo::default(), 0, false);
    let s = Arc::new(ObjectSlot { od, dict: Dict { eds: Some(eds) } });
    slots.lock().unwrap_or_else(|e| e.into_inner()).insert(position, s.clone());
    Ok(s)
}

impl ObjectSlot {
    /// The data type of `index:sub`: `ty` when given, else the dictionary's.
    pub fn data_type(&self, index: u16, sub: u8, ty: Option<&str>) -> ApiResult<Option<DataType>> {
        Ok(match ty {
            Some(t) => Some(values::data_type(t)?),
            None => self.od.get(index, sub).map(|e| e.data_type),
        })
    }
}

fn read(s: &Served, n: &str, index: &str, sub: Option<&str>, ty: Option<&str>) -> ApiResult<Json<Json_>> {
    let p = position(n)?;
    let slot = slot(&s.host, &s.slots, p)?;
    let (index, sub) = values::object(&slot.dict, index, sub)?;
    let dt = slot.data_type(index, sub, ty)?;
    let raw = objects::read(&s.host, p, index, sub).map_err(|e| object_error(p, index, sub, e))?;
    Ok(Json(values::read_answer(p, (index, sub), slot.dict.name(index, sub), dt, &raw, "holds")?))
}

#[derive(serde::Deserialize)]
struct Write {
    value: Json_,
    #[serde(rename = "type")]
    ty: Option<String>,
}

fn write(s: &Served, n: &str, index: &str, sub: Option<&str>, b: &Bytes) -> ApiResult<Json<Json_>> {
    let p = position(n)?;
    let slot = slot(&s.host, &s.slots, p)?;
    let (index, sub) = values::object(&slot.dict, index, sub)?;
    let w: Write =
        body(b, r#"{"value": 6, "type": "u16"} ("type" optional for objects the dictionary knows)"#)?;
    let dt = slot.data_type(index, sub, w.ty.as_deref())?.ok_or_else(|| {
        ApiError::not_found(format!(
            "slave {p} has no object {index:04X}h:{sub:02X}h (SDO abort 06020000h): GET /api/nodes/{p}/objects lists its objects"
        ))
    })?;
    let value = values::from_json(dt, &w.value)?;
    let data = value.encode(dt).map_err(|a| ApiError::bad(format!("{value} as {}: {a}", dt.name())))?;
    tracing::info!(position = p, index = format_args!("{index:04X}"), sub, value = %value, "web: EtherCAT object write");
    objects::write(&s.host, p, index, sub, &data).map_err(|e| object_error(p, index, sub, e))?;
    Ok(Json(json!({"node": p, "index": format!("{index:04X}"), "sub": sub, "type": dt.name(),
        "value": values::to_json(&value), "written": true})))
}

/// `GET /api/nodes/{position}/sdo/{index}/{sub}`.
pub async fn sdo_get(
    State(s): State<Served>,
    Path((n, index, sub)): Path<(String, String, String)>,
    Query(q): Query<TypeQuery>,
) -> ApiResult<Json<Json_>> {
    read(&s, &n, &index, Some(&sub), q.ty.as_deref())
}

/// `GET /api/nodes/{position}/sdo/{object}`: sub-index 0 or the named entry.
pub async fn sdo_get_object(
    State(s): State<Served>,
    Path((n, index)): Path<(String, String)>,
    Query(q): Query<TypeQuery>,
) -> ApiResult<Json<Json_>> {
    read(&s, &n, &index, None, q.ty.as_deref())
}

/// `PUT /api/nodes/{position}/sdo/{index}/{sub}` with `{"value", "type"}`.
pub async fn sdo_put(
    State(s): State<Served>,
    Path((n, index, sub)): Path<(String, String, String)>,
    b: Bytes,
) -> ApiResult<Json<Json_>> {
    write(&s, &n, &index, Some(&sub), &b)
}

/// `PUT /api/nodes/{position}/sdo/{object}`.
pub async fn sdo_put_object(
    State(s): State<Served>,
    Path((n, index)): Path<(String, String)>,
    b: Bytes,
) -> ApiResult<Json<Json_>> {
    write(&s, &n, &index, None, &b)
}

/// `GET /api/nodes/{position}/objects?q=velocity`: the slave's dictionary.
pub async fn list(
    State(s): State<Served>,
    Path(n): Path<String>,
    Query(q): Query<Search>,
) -> ApiResult<Json<Json_>> {
    let p = position(&n)?;
    let slot = slot(&s.host, &s.slots, p)?;
    let found = crate::web::objects::entries(&slot.od, q.q.as_deref().unwrap_or_default());
    Ok(Json(json!({"node": p, "objects": found})))
}
