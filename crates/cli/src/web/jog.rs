//! `POST /api/nodes/{n}/drive/jog`: jog in profile velocity while a
//! button is held. The page repeats `{"velocity": V}` while held and sends
//! `{"velocity": 0}` on release; a jog not repeated within [`WATCHDOG`] is
//! stopped by the server, so motion never outlives a vanished page.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, State};
use drivebus_master::{DriveState, RemoteDrive, drive::mode};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::{body, seen_node};
use super::error::{ApiError, ApiResult};

/// A jog the page does not repeat within this time is stopped.
pub const WATCHDOG: Duration = Duration::from_millis(500);
/// How often the watchdog looks.
const CHECK: Duration = Duration::from_millis(20);

/// The running jogs, by node.
#[derive(Default)]
pub struct JogTable {
    running: Mutex<HashMap<u8, Running>>,
    /// Numbers the jogs, so a watchdog only stops its own.
    next: AtomicU64,
}

struct Running {
    id: u64,
    velocity: i32,
    /// Last refresh.
    seen: Instant,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct JogRequest {
    velocity: i32,
    /// Profile acceleration and deceleration 6083h/6084h, at the start.
    acceleration: Option<u32>,
}

const SHAPE: &str =
    r#"{"velocity": 5000} every < 500 ms while held (optional "acceleration"), {"velocity": 0} to stop"#;

/// Starts, refreshes or (velocity 0) stops the jog of node `n`.
pub async fn jog(State(web): State<Arc<Web>>, Path(n): Path<String>, b: Bytes) -> ApiResult<Json<Json_>> {
    let node = seen_node(&web, &n)?;
    let r: JogRequest = body(&b, SHAPE)?;
    let ex = |e| ApiError::drive(node, &e);
    if r.velocity == 0 {
        let was = web.jogs.running.lock().unwrap_or_else(|e| e.into_inner()).remove(&node);
        if was.is_some() {
            end(&web, &super::drive::handle(&web, node).await?, node, "released", None).await;
        }
        return Ok(Json(json!({"node": node, "jogging": false})));
    }
    // A refresh: only the deadline (and a changed speed); no bus traffic
    // for the repeats of a held button.
    let refreshed = {
        let mut t = web.jogs.running.lock().unwrap_or_else(|e| e.into_inner());
        t.get_mut(&node).map(|j| {
            j.seen = Instant::now();
            std::mem::replace(&mut j.velocity, r.velocity)
        })
    };
    match refreshed {
        Some(old) if old == r.velocity => {}
        Some(_) => {
            let d = super::drive::handle(&web, node).await?;
            d.write_raw(0x60FF, 0, &r.velocity.to_le_bytes()).await.map_err(ex)?;
        }
        None => start(web.clone(), super::drive::handle(&web, node).await?, node, &r).await?,
    }
    Ok(Json(
        json!({"node": node, "jogging": true, "velocity": r.velocity, "watchdog_ms": WATCHDOG.as_millis() as u64}),
    ))
}

async fn start(web: Arc<Web>, d: RemoteDrive, node: u8, r: &JogRequest) -> ApiResult<()> {
    let ex = |e| ApiError::drive(node, &e);
    let state = DriveState::from_statusword(d.statusword().await.map_err(ex)?);
    if state != DriveState::OperationEnabled {
        return Err(ApiError::conflict(format!(
            "node {node} is in {state}, not operation enabled: send {{\"action\": \"enable\"}} first"
        )));
    }
    tracing::info!(node, velocity = r.velocity, "web: jog");
    d.write_raw(0x60FF, 0, &0i32.to_le_bytes()).await.map_err(ex)?;
    d.set_mode(mode::PV).await.map_err(ex)?;
    if let Some(acc) = r.acceleration {
        d.write_raw(0x6083, 0, &acc.to_le_bytes()).await.map_err(ex)?;
        d.write_raw(0x6084, 0, &acc.to_le_bytes()).await.map_err(ex)?;
    }
    let id = web.jogs.next.fetch_add(1, Ordering::Relaxed);
    web.jogs
        .running
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(node, Running { id, velocity: r.velocity, seen: Instant::now() });
    d.velocity(r.velocity).await.map_err(ex)?;
    tokio::spawn(watchdog(web, d, node, id));
    Ok(())
}

/// Stops jog `id` when it is not refreshed within [`WATCHDOG`]; ends
/// when it was released or replaced.
async fn watchdog(web: Arc<Web>, d: RemoteDrive, node: u8, id: u64) {
    loop {
        tokio::time::sleep(CHECK).await;
        let late = {
            let mut t = web.jogs.running.lock().unwrap_or_else(|e| e.into_inner());
            match t.get(&node) {
                Some(j) if j.id == id => {
                    let late = j.seen.elapsed() > WATCHDOG;
                    if late {
                        t.remove(&node);
                    }
                    late
                }
                _ => return,
            }
        };
        if late {
            let why = format!("not refreshed within {} ms: the page is gone or hidden", WATCHDOG.as_millis());
            tracing::warn!(node, "web: jog stopped by the watchdog");
            end(&web, &d, node, "watchdog", Some(why)).await;
            return;
        }
    }
}

/// Velocity 0 (the drive decelerates with 6084h), then a `jog` event.
async fn end(web: &Web, d: &RemoteDrive, node: u8, how: &str, reason: Option<String>) {
    let reason = match d.write_raw(0x60FF, 0, &0i32.to_le_bytes()).await {
        Ok(()) => reason,
        // Still stopped, by quick stop.
        Err(e) => {
            let qs = d.quick_stop().await.map(|_| "quick stop instead").unwrap_or("quick stop failed too");
            Some(format!("velocity 0 not written: {e}; {qs}"))
        }
    };
    let position = d.position().await;
    tracing::info!(node, end = how, "web: jog ended");
    web.event(json!({"type": "event", "event": "jog", "t": web.t(), "node": node,
        "result": {"end": how, "position": position, "reason": reason}}));
}
