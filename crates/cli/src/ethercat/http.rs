//! `ethercat serve --http ADDR`: the line's state as its slaves hold it,
//! `GET /api/ethercat` (docs/http-api.md), and the page (`crate::web`'s
//! files) showing it as the line view. Read only: nothing here changes
//! the line.

use std::net::SocketAddr;

use anyhow::Context;
use axum::extract::State;
use axum::routing::get;
use drivebus_ethercat::Host;
use drivebus_ethercat::master::{self, AlState};

/// Binds `addr` and serves the state of `host`'s line until the task is
/// aborted.
pub async fn start(host: Host, addr: &str) -> anyhow::Result<(tokio::task::JoinHandle<()>, SocketAddr)> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on --http {addr}: is the port free? (port 0 picks one)"))?;
    let local = listener.local_addr()?;
    let app = crate::web::page_routes(crate::web::ServedBus::Ethercat)
        .route("/api/ethercat", get(line))
        .with_state(host);
    let task = tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, app).await {
            tracing::error!(error = %e, "web server stopped");
        }
    });
    Ok((task, local))
}

async fn line(State(host): State<Host>) -> axum::Json<serde_json::Value> {
    axum::Json(line_json(&host))
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
