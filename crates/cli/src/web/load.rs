//! The bus load the overview shows: `GET /api/bus`, the frames and bits
//! the master heard over the last full second and their share of the
//! bitrate when it is known (`serve --bitrate`, an slcan URL's
//! `?bitrate=`), measured by the transport's `LoadMeter` as `drivebus
//! stats` does.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Json;
use axum::extract::State;
use drivebus_transport::{LoadMeter, LoadReport};
use serde_json::{Value as Json_, json};
use tokio::sync::broadcast;

use super::Web;

/// The meter of the running second and the last full one.
#[derive(Default)]
pub struct BusLoad {
    meter: Mutex<(LoadMeter, Option<LoadReport>)>,
}

/// Counts the frames the master hears and closes a span every second,
/// until the bus closes.
pub async fn keep_measuring(web: Arc<Web>) {
    let mut frames = web.master.subscribe_frames();
    let mut tick = tokio::time::interval(Duration::from_secs(1));
    web.load.meter.lock().unwrap_or_else(|e| e.into_inner()).0.reset(web.master.now());
    tick.tick().await;
    loop {
        tokio::select! {
            f = frames.recv() => match f {
                Ok(f) => web.load.meter.lock().unwrap_or_else(|e| e.into_inner()).0.record(&f, web.master.now()),
                // Frames not counted make the load read low, never high.
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => return,
            },
            _ = tick.tick() => {
                let now = web.master.now();
                let mut m = web.load.meter.lock().unwrap_or_else(|e| e.into_inner());
                let report = m.0.report(now, web.bitrate);
                m.1 = Some(report);
                m.0.reset(now);
            }
        }
    }
}

/// `GET /api/bus`: the last full second's frames, bits and load.
pub async fn bus(State(web): State<Arc<Web>>) -> Json<Json_> {
    let m = web.load.meter.lock().unwrap_or_else(|e| e.into_inner());
    Json(match &m.1 {
        None => {
            json!({"seconds": 0.0, "frames_per_s": null, "bits_per_s": null, "load": null, "bitrate": web.bitrate})
        }
        Some(r) => {
            json!({"seconds": r.seconds, "frames_per_s": r.per_second, "bits_per_s": r.bits_per_second,
            "load": r.load, "bitrate": web.bitrate})
        }
    })
}
