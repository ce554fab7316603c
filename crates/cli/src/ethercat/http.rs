//! `ethercat serve --http ADDR`: the line's state as its slaves hold it,
//! `GET /api/ethercat` (docs/http-api.md), its ESM events and object
//! samples on the WebSocket `GET /api/stream` (`http_stream.rs`), the
//! slaves' objects under the CAN side's URLs (`http_objects.rs`: the only
//! writes), and the page (`crate::web`'s files) showing the line view,
//! the object form, the dictionary browser and the scope.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use axum::extract::State;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::response::Response;
use axum::routing::get;
use drivebus_ethercat::Host;
use drivebus_ethercat::master::{self, AlState};
use serde_json::json;

use super::http_objects::{self, ObjectSlots};
use super::http_stream::{self, Subscription};
use crate::web::Queue;
use crate::web::error::ApiError;

/// How often a stream compares the slaves' AL status registers: a
/// change shorter than this (a state passed on the way) is not seen.
const ESM_POLL: Duration = Duration::from_millis(20);

/// What the handlers share.
#[derive(Clone)]
pub struct Served {
    /// The line.
    pub host: Host,
    /// Time zero of `t` in the stream.
    pub start: Instant,
    /// The slaves' dictionaries as taken once.
    pub slots: ObjectSlots,
    /// Required on an address other than loopback (the API writes).
    pub token: Option<Arc<str>>,
}

impl Served {
    /// Milliseconds since the server started.
    pub fn t(&self) -> f64 {
        self.start.elapsed().as_secs_f64() * 1000.0
    }
}

/// A running server: its task (the caller aborts it), where it listens
/// and the token every request needs on an address other than loopback.
pub struct Started {
    /// The server task.
    pub task: tokio::task::JoinHandle<()>,
    /// Where it listens.
    pub addr: SocketAddr,
    /// `?token=` for every request, when required.
    pub token: Option<Arc<str>>,
}

/// Binds `addr` and serves `host`'s line until the task is aborted.
pub async fn start(host: Host, addr: &str) -> anyhow::Result<Started> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on --http {addr}: is the port free? (port 0 picks one)"))?;
    let local = listener.local_addr()?;
    let token: Option<Arc<str>> = (!local.ip().is_loopback()).then(|| crate::web::new_token().into());
    let served = Served { host, start: Instant::now(), slots: ObjectSlots::default(), token: token.clone() };
    let app = crate::web::page_routes(crate::web::ServedBus::Ethercat)
        .route("/api/ethercat", get(line))
        .route("/api/stream", get(upgrade))
        .route(
            "/api/nodes/{n}/sdo/{index}",
            get(http_objects::sdo_get_object).put(http_objects::sdo_put_object),
        )
        .route("/api/nodes/{n}/sdo/{index}/{sub}", get(http_objects::sdo_get).put(http_objects::sdo_put))
        .route("/api/nodes/{n}/objects", get(http_objects::list))
        .fallback(|| async { ApiError::not_found("no such page or endpoint: see docs/http-api.md") })
        .layer(axum::middleware::from_fn_with_state(served.clone(), auth))
        .with_state(served);
    let task = tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, app).await {
            tracing::error!(error = %e, "web server stopped");
        }
    });
    Ok(Started { task, addr: local, token })
}

/// 401 without the token, when one is required.
async fn auth(
    State(s): State<Served>,
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> Response {
    crate::web::check_token(s.token.as_deref(), req, next).await
}

async fn line(State(s): State<Served>) -> axum::Json<serde_json::Value> {
    axum::Json(line_json(&s.host))
}

/// The ESM of one slave as the API gives it (`state`, `error`, the code
/// and its text).
fn esm_json(position: usize, (al_status, code): (u16, u16)) -> serde_json::Value {
    let bits = (al_status & 0x0F) as u8;
    json!({"position": position, "state": master::state_text(AlState::from_code(bits).ok_or(bits)),
        "error": al_status & 0x10 != 0, "al_status_code": code, "al_status_text": master::al_status_text(code)})
}

/// `GET /api/stream`: upgrades to the line's event stream.
async fn upgrade(State(s): State<Served>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |socket| stream(s, socket))
}

/// Sends the line's ESM now (`line`), then an `esm` event per slave whose
/// AL status or code changed, and the samples of the objects the client
/// subscribes, through the bounded queue of `crate::web` (a slow client
/// loses the oldest, counted in `status`).
async fn stream(s: Served, mut socket: WebSocket) {
    let queue = Queue::new();
    let watch = tokio::spawn(watch_esm(s.clone(), queue.clone()));
    let _abort = AbortOnDrop(watch);
    let mut subscription: Option<Subscription> = None;
    let mut status = tokio::time::interval(Duration::from_secs(1));
    loop {
        tokio::select! {
            m = socket.recv() => match m {
                Some(Ok(Message::Text(t))) => match http_stream::message(&s, &queue, t.as_str()) {
                    Ok(Some(sub)) => {
                        // The old one ends before the new one's answer.
                        drop(subscription.take());
                        queue.push(&json!({"type": "subscribed", "channels": sub.channels}));
                        subscription = Some(sub);
                    }
                    Ok(None) => {}
                    Err(e) => queue.push(&json!({"type": "error", "error": e})),
                },
                Some(Ok(_)) => {}
                Some(Err(_)) | None => return,
            },
            _ = queue.ready() => {
                for m in queue.take() {
                    if socket.send(Message::Text(m.into())).await.is_err() {
                        return;
                    }
                }
            }
            _ = status.tick() => {
                let st = json!({"type": "status", "t": s.t(),
                    "dropped": queue.dropped.load(std::sync::atomic::Ordering::Relaxed),
                    "channels": subscription.as_ref().map_or(0, |c| c.channels)});
                if socket.send(Message::Text(st.to_string().into())).await.is_err() {
                    return;
                }
            }
        }
    }
}

struct AbortOnDrop(tokio::task::JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// Polls the AL status registers every [`ESM_POLL`] and queues the changes.
async fn watch_esm(s: Served, queue: Arc<Queue>) {
    let mut last = s.host.al_states();
    let slaves: Vec<_> = last.iter().enumerate().map(|(i, &al)| esm_json(i + 1, al)).collect();
    queue.push(&json!({"type": "line", "t": s.t(), "slaves": slaves}));
    let mut tick = tokio::time::interval(ESM_POLL);
    loop {
        tick.tick().await;
        let now = s.host.al_states();
        for (i, (was, is)) in last.iter().zip(&now).enumerate() {
            if was != is {
                let mut e = esm_json(i + 1, *is);
                let from = esm_json(i + 1, *was);
                e["type"] = json!("event");
                e["event"] = json!("esm");
                e["t"] = json!(s.t());
                e["from"] = from["state"].clone();
                queue.push(&e);
            }
        }
        last = now;
    }
}

/// The answer of `GET /api/ethercat`.
fn line_json(host: &Host) -> serde_json::Value {
    let slaves: Vec<serde_json::Value> = host
        .slaves()
        .iter()
        .map(|s| {
            let bits = (s.al_status & 0x0F) as u8;
            serde_json::json!({"position": s.position, "name": s.name,
                "identity": {"vendor_id": s.identity.vendor_id, "product_code": s.identity.product_code,
                    "revision": s.identity.revision, "serial": s.identity.serial},
                "state": master::state_text(AlState::from_code(bits).ok_or(bits)),
                "error": s.al_status & 0x10 != 0, "al_status_code": s.al_status_code,
                "al_status_text": master::al_status_text(s.al_status_code), "powered": s.powered,
                "frames": s.traffic.frames, "datagrams": s.traffic.datagrams, "wkc": s.traffic.wkc})
        })
        .collect();
    let st = host.stats();
    serde_json::json!({"slaves": slaves,
        "line": {"frames": st.frames, "bad_frames": st.bad_frames, "lost": st.lost, "datagrams": st.datagrams}})
}
