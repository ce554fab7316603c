//! `POST /api/nodes/{n}/drive/sine`: the CSP sine generator of the drive
//! panel. The demo's sine ([`crate::demo::csp_sine`]) streamed one target
//! per SYNC by the master's `RemoteDrive::stream_csp`; this master produces the
//! SYNC while a sine runs (and writes the interpolation period 60C2h to
//! match). Its end is a `sine` event on the stream.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use drivebus_master::{DriveState, RemoteDrive, drive::mode};
use serde_json::{Value as Json_, json};

use super::Web;
use super::api::{body, seen_node};
use super::error::{ApiError, ApiResult};

/// The sines running, by node (their stop flags), and the SYNC period
/// this server produces for them.
#[derive(Default)]
pub struct SineTable {
    running: Mutex<SineState>,
}

#[derive(Default)]
struct SineState {
    stops: HashMap<u8, Arc<AtomicBool>>,
    /// The SYNC period while this server produces SYNC for sines.
    sync: Option<Duration>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SineRequest {
    #[serde(default)]
    stop: bool,
    amplitude: Option<u32>,
    period_ms: Option<u32>,
    duration_ms: Option<u32>,
    /// The SYNC period when this starts the SYNC producer (default 2 ms).
    cycle_ms: Option<u32>,
}

const SHAPE: &str = r#"{"amplitude": 10000, "period_ms": 1000, "duration_ms": 3000} (optional "cycle_ms", the SYNC period, default 2) or {"stop": true}"#;

/// Starts a sine (202; its end comes as a `sine` event) or stops the
/// running one of node `n`.
pub async fn sine(
    State(web): State<Arc<Web>>,
    Path(n): Path<String>,
    b: Bytes,
) -> ApiResult<(StatusCode, Json<Json_>)> {
    let node = seen_node(&web, &n)?;
    let r: SineRequest = body(&b, SHAPE)?;
    if r.stop {
        let stop = web.sines.running.lock().unwrap_or_else(|e| e.into_inner()).stops.get(&node).cloned();
        let Some(stop) = stop else {
            return Err(ApiError::conflict(format!("node {node} runs no sine")));
        };
        stop.store(true, Ordering::Relaxed);
        return Ok((StatusCode::OK, Json(json!({"node": node, "stopping": true}))));
    }
    let (Some(amplitude), Some(period_ms), Some(duration_ms)) = (r.amplitude, r.period_ms, r.duration_ms)
    else {
        return Err(ApiError::bad(format!(
            "a sine needs \"amplitude\", \"period_ms\" and \"duration_ms\": send {SHAPE}"
        )));
    };
    let cycle_ms = r.cycle_ms.unwrap_or(2);
    if !(1..=100).contains(&cycle_ms) || period_ms < 10 * cycle_ms || !(1..=600_000).contains(&duration_ms) {
        return Err(ApiError::bad(format!(
            "cycle_ms {cycle_ms} must be 1..100, period_ms {period_ms} at least 10 cycles, duration_ms {duration_ms} 1..600000"
        )));
    }
    if amplitude > i32::MAX as u32 / 4 {
        return Err(ApiError::bad(format!("amplitude {amplitude} is above {}", i32::MAX / 4)));
    }
    let d = super::drive::handle(&web, node).await?;
    let state = DriveState::from_statusword(d.statusword().await.map_err(|e| ApiError::drive(node, &e))?);
    if state != DriveState::OperationEnabled {
        return Err(ApiError::conflict(format!(
            "node {node} is in {state}, not operation enabled: send {{\"action\": \"enable\"}} first"
        )));
    }
    let cycle = Duration::from_millis(cycle_ms.into());
    let stop = Arc::new(AtomicBool::new(false));
    {
        let mut t = web.sines.running.lock().unwrap_or_else(|e| e.into_inner());
        if t.stops.contains_key(&node) {
            return Err(ApiError::conflict(format!(
                "node {node} runs a sine already: send {{\"stop\": true}} first"
            )));
        }
        match t.sync {
            Some(p) if p != cycle => {
                return Err(ApiError::conflict(format!(
                    "SYNC runs at {} ms for another sine: use \"cycle_ms\": {}",
                    p.as_millis(),
                    p.as_millis()
                )));
            }
            None if web.master.sync_running() => {
                return Err(ApiError::conflict(
                    "this master produces SYNC already, at a period the page does not set",
                ));
            }
            None => {
                web.master.start_sync(cycle, 0);
                t.sync = Some(cycle);
            }
            Some(_) => {}
        }
        t.stops.insert(node, stop.clone());
    }
    let cycles = u64::from(duration_ms).div_ceil(cycle_ms.into());
    tracing::info!(node, amplitude, period_ms, duration_ms, cycle_ms, "web: CSP sine");
    let plan = (f64::from(amplitude), Duration::from_millis(period_ms.into()), cycle, cycles);
    tokio::spawn(run(web, d, node, plan, stop));
    Ok((
        StatusCode::ACCEPTED,
        Json(json!({"node": node, "started": true, "cycles": cycles, "cycle_ms": cycle_ms})),
    ))
}

async fn run(
    web: Arc<Web>,
    d: RemoteDrive,
    node: u8,
    plan: (f64, Duration, Duration, u64),
    stop: Arc<AtomicBool>,
) {
    let (amplitude, period, cycle, cycles) = plan;
    let r = async {
        // Interpolation period 60C2h = cycle ms · 10^-3 s (where the drive has it).
        let ms = u8::try_from(cycle.as_millis()).unwrap_or(u8::MAX);
        if d.write_raw(0x60C2, 1, &[ms]).await.is_ok() {
            let _ = d.write_raw(0x60C2, 2, &(-3i8).to_le_bytes()).await;
        }
        d.set_mode(mode::CSP).await?;
        let base = d.position().await.unwrap_or(0);
        // Hold the present position for a few cycles first (as the demo).
        d.stream_csp(std::iter::repeat_n(base, 5)).await?;
        let targets = crate::demo::csp_sine(base.into(), amplitude, period, cycle, cycles);
        d.stream_csp(targets.take_while(|_| !stop.load(Ordering::Relaxed))).await
    }
    .await;
    {
        let mut t = web.sines.running.lock().unwrap_or_else(|e| e.into_inner());
        t.stops.remove(&node);
        if t.stops.is_empty() && t.sync.take().is_some() {
            web.master.stop_sync();
        }
    }
    let position = d.position().await;
    let state = d.statusword().await.map(DriveState::from_statusword);
    let result = match r {
        Ok(n) if n as u64 == cycles => json!({"end": "completed", "cycles": n, "position": position}),
        Ok(n) => {
            json!({"end": "stopped", "cycles": n, "position": position, "reason": "stopped from the page"})
        }
        Err(e) => json!({"end": "error", "position": position, "reason": e.to_string()}),
    };
    // Streamed to the end, but the drive left operation enabled meanwhile.
    let result = match state {
        Ok(s) if s != DriveState::OperationEnabled && result["end"] != "error" => {
            json!({"end": "error", "cycles": result["cycles"], "position": position, "reason": format!("the drive is in {s}")})
        }
        _ => result,
    };
    tracing::info!(node, result = %result, "web: CSP sine ended");
    web.event(json!({"type": "event", "event": "sine", "t": web.t(), "node": node, "result": result}));
}
