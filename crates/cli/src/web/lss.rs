//! LSS (CiA 305) for the bus served: `POST /api/lss/scan`, `/inquire`
//! and `/configure`, through the master's LSS service (as `drivebus lss`).
//! A configured node is addressed by its 1018h (read by SDO), any slave
//! by its LSS address; without either, only the one unconfigured slave.

use std::sync::Arc;
use std::time::Duration;

use axum::Json;
use axum::body::Bytes;
use axum::extract::State;
use axum::http::StatusCode;
use drivebus_master::{Identity, LssError, LssMaster, OnlySlave};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::{body, seen_node};
use super::error::{ApiError, ApiResult};

/// Each LSS answer is waited for this long unless `timeout_ms` says.
const ANSWER_MS: u64 = 100;

/// An LSS address as JSON.
#[derive(serde::Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct Address {
    vendor_id: u32,
    product_code: u32,
    revision: u32,
    serial: u32,
}

fn address_json(a: &Identity) -> Json_ {
    json!({"vendor_id": a.vendor_id, "product_code": a.product_code, "revision": a.revision, "serial": a.serial})
}

/// Which slave, and how long to wait for each answer.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Target {
    /// A configured node: its LSS address is its 1018h.
    node: Option<Json_>,
    address: Option<Address>,
    timeout_ms: Option<u64>,
    /// For `/configure`: the new node-ID (1..127).
    node_id: Option<u8>,
    /// For `/configure`: store node-ID and bit timing in the slave.
    #[serde(default)]
    store: bool,
    /// For `/configure`: the CiA 305 bit timing table index (0: 1 Mbit/s .. 8: auto).
    bit_timing: Option<u8>,
}

const SHAPE: &str = r#"{"node": 5} or {"address": {"vendor_id": 1, "product_code": 2, "revision": 3, "serial": 4}} (for /configure also "node_id": 6, "store": true, "bit_timing": 4; "timeout_ms" optional)"#;

fn target(b: &Bytes) -> ApiResult<Target> {
    if b.iter().all(u8::is_ascii_whitespace) { Ok(Target::default()) } else { body(b, SHAPE) }
}

fn lss(web: &Web, t: &Target) -> ApiResult<LssMaster> {
    let ms = t.timeout_ms.unwrap_or(ANSWER_MS);
    if !(1..=10_000).contains(&ms) {
        return Err(ApiError::bad(format!("timeout_ms {ms}: give 1..10000 (the wait for each LSS answer)")));
    }
    Ok(web.master.lss().timeout(Duration::from_millis(ms)))
}

/// The LSS address of `node` (its 1018h, by SDO) or the one given.
async fn address(web: &Web, t: &Target) -> ApiResult<Option<Identity>> {
    match (&t.node, &t.address) {
        (Some(_), Some(_)) => Err(ApiError::bad("give \"node\" or \"address\", not both")),
        (None, Some(a)) => Ok(Some(Identity::new(a.vendor_id, a.product_code, a.revision, a.serial))),
        (None, None) => Ok(None),
        (Some(n), None) => {
            let n = match n {
                Json_::Number(x) => x.to_string(),
                Json_::String(s) => s.clone(),
                other => other.to_string(),
            };
            let node = seen_node(web, &n)?;
            let sdo = web.master.sdo(node);
            let mut v = [0u32; 4];
            for (i, slot) in v.iter_mut().enumerate() {
                let sub = i as u8 + 1;
                *slot =
                    sdo.read::<u32>(0x1018, sub).await.map_err(|e| ApiError::sdo(node, 0x1018, sub, &e))?;
            }
            Ok(Some(Identity::new(v[0], v[1], v[2], v[3])))
        }
    }
}

/// An LSS failure as the API gives it.
fn lss_error(e: LssError, whom: &str) -> ApiError {
    match e {
        LssError::Timeout => ApiError {
            status: StatusCode::GATEWAY_TIMEOUT,
            message: format!(
                "no LSS answer from {whom}: is it on the bus, and does it support LSS (CiA 305)?"
            ),
        },
        LssError::Refused { error, spec_error } => {
            let why = match error {
                1 => "not supported or out of range".to_owned(),
                2 => "storage access error".to_owned(),
                0xFF => format!("implementation-specific error {spec_error}"),
                e => format!("error {e}"),
            };
            ApiError {
                status: StatusCode::UNPROCESSABLE_ENTITY,
                message: format!(
                    "{whom} refused: {why} (CiA 305 error {error}); the slave was returned to waiting"
                ),
            }
        }
        LssError::InvalidArgument(m) => ApiError::bad(m),
        LssError::Transport(m) => {
            ApiError { status: StatusCode::BAD_GATEWAY, message: format!("{m}: check the bus connection") }
        }
    }
}

fn whom(a: &Identity) -> String {
    format!(
        "the slave with vendor {:08X}h product {:08X}h revision {:08X}h serial {:08X}h",
        a.vendor_id, a.product_code, a.revision, a.serial
    )
}

/// `POST /api/lss/scan`: fastscan for the unconfigured slave with the
/// lowest LSS address, and whether more answer; every slave is left as
/// it was.
pub async fn scan(State(web): State<Arc<Web>>, b: Bytes) -> ApiResult<Json<Json_>> {
    let t = target(&b)?;
    let lss = lss(&web, &t)?;
    match lss.probe_unconfigured().await.map_err(|e| lss_error(e, "the unconfigured slaves"))? {
        Some((a, more)) => Ok(Json(json!({"found": true, "first": address_json(&a), "more": more}))),
        None => Ok(Json(json!({"found": false}))),
    }
}

/// `POST /api/lss/inquire` with `{"node": N}` or `{"address": ...}`:
/// switch state selective, inquire the LSS address and node-ID, back to
/// waiting.
pub async fn inquire(State(web): State<Arc<Web>>, b: Bytes) -> ApiResult<Json<Json_>> {
    let t = target(&b)?;
    let lss = lss(&web, &t)?;
    let addr = address(&web, &t).await?.ok_or_else(|| ApiError::bad(format!("give the slave: {SHAPE}")))?;
    let who = whom(&addr);
    lss.switch_selective(&addr).await.map_err(|e| lss_error(e, &who))?;
    let r = async { Ok::<_, LssError>((lss.inquire_identity().await?, lss.inquire_node_id().await?)) }.await;
    lss.switch_global(drivebus_master::LssMode::Waiting).await.map_err(|e| lss_error(e, &who))?;
    let (identity, node_id) = r.map_err(|e| lss_error(e, &who))?;
    Ok(Json(json!({"address": address_json(&identity), "node_id": (node_id != 0xFF).then_some(node_id),
        "configured": node_id != 0xFF})))
}

/// `POST /api/lss/configure` with the new `node_id` (and `store`,
/// `bit_timing`): on the slave given by `node` or `address`, else on the
/// only unconfigured slave (refused when several answer).
pub async fn configure(State(web): State<Arc<Web>>, b: Bytes) -> ApiResult<Json<Json_>> {
    let t = target(&b)?;
    let lss = lss(&web, &t)?;
    let node_id = t.node_id.ok_or_else(|| ApiError::bad(format!("give \"node_id\" (1..127): {SHAPE}")))?;
    if !(1..=127).contains(&node_id) {
        return Err(ApiError::bad(format!("node_id {node_id} is not 1..127; nothing was sent")));
    }
    if t.bit_timing.is_some_and(|i| i > 9) {
        return Err(ApiError::bad("bit_timing is an index of the CiA 305 table, 0..9; nothing was sent"));
    }
    let Some(addr) = address(&web, &t).await? else {
        if t.bit_timing.is_some() {
            return Err(ApiError::bad("bit_timing needs the slave: give \"node\" or \"address\""));
        }
        tracing::info!(node_id, store = t.store, "web: LSS configure the only unconfigured slave");
        return match lss
            .configure_only_slave(node_id, t.store)
            .await
            .map_err(|e| lss_error(e, "the unconfigured slave"))?
        {
            OnlySlave::Configured(a) => {
                Ok(Json(json!({"node_id": node_id, "stored": t.store, "address": address_json(&a),
                "active": "now (an unconfigured slave starts under it)"})))
            }
            OnlySlave::Several(a) => Err(ApiError::conflict(format!(
                "more than one unconfigured LSS slave answers: all would get node-ID {node_id}; nothing was changed. Give one \"address\" (the lowest found: {})",
                address_json(&a)
            ))),
            OnlySlave::NoneFound => Err(ApiError::not_found(
                "no unconfigured LSS slave answered: give a configured node as \"node\", or an \"address\"",
            )),
        };
    };
    let who = whom(&addr);
    tracing::info!(node_id, store = t.store, bit_timing = ?t.bit_timing, slave = %who, "web: LSS configure");
    lss.switch_selective(&addr).await.map_err(|e| lss_error(e, &who))?;
    let r = async {
        if let Some(i) = t.bit_timing {
            lss.configure_bit_timing(i).await?;
        }
        lss.configure_node_id(node_id).await?;
        if t.store {
            lss.store().await?;
        }
        Ok::<_, LssError>(())
    }
    .await;
    lss.switch_global(drivebus_master::LssMode::Waiting).await.map_err(|e| lss_error(e, &who))?;
    r.map_err(|e| lss_error(e, &who))?;
    Ok(Json(
        json!({"node_id": node_id, "stored": t.store, "bit_timing": t.bit_timing, "address": address_json(&addr),
        "active": "at the slave's next NMT reset communication (an unconfigured slave: now)"}),
    ))
}
