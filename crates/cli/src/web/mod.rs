//! The browser page and its HTTP API (issue 19): `drivebus ui --http ADDR`
//! and `drivebus serve --http ADDR`. Everything goes through one
//! [`Master`] (SDO, NMT, PDO configuration, the CiA 402 `RemoteDrive`); the page
//! is plain HTML, JS and CSS inside the binary. The API is in
//! `docs/http-api.md`.
//!
//! A page that can move axes binds loopback by default; on any other
//! address every request needs the token printed at start (`?token=` or
//! the `X-Drivebus-Token` header), else 401.

pub(crate) mod api;
mod drive;
pub(crate) mod error;
mod frames;
mod identify;
mod jog;
mod load;
mod lss;
mod machine;
pub(crate) mod objects;
mod pdo;
mod sine;
pub(crate) mod stream;
pub(crate) mod values;

use std::collections::{HashMap, VecDeque};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use anyhow::Context;
use axum::Router;
use axum::extract::{Request, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use drivebus_master::{Master, MasterEvent};
use drivebus_personality::Profile;
use tokio::sync::broadcast;

use crate::dict::Dict;
pub use stream::Queue;

/// `--http`'s default address: loopback, port 8402 ("402").
pub const DEFAULT_HTTP: &str = "127.0.0.1:8402";

/// EMCYs kept for `GET /api/emcy`.
const EMCY_HISTORY: usize = 256;

/// What every handler shares.
pub struct Web {
    /// The bus.
    pub master: Master,
    /// Object names and types (`--eds`, then CiA 301/402).
    pub dict: Dict,
    /// The personality of each drive this process hosts (`serve --drive`,
    /// `ui --sim`): its homing methods and its manual's EMCY table.
    pub profiles: HashMap<u8, Profile>,
    /// The personality of drives this process does not host, picked from
    /// their 1018h (`identify`).
    identified: Mutex<HashMap<u8, Profile>>,
    /// The last EMCYs, oldest first.
    emcy: Mutex<VecDeque<serde_json::Value>>,
    /// Events the server itself makes (a motion's end), for the stream.
    events: broadcast::Sender<serde_json::Value>,
    /// Jogs held on pages, with their watchdog.
    jogs: jog::JogTable,
    /// CSP sines running, and their SYNC.
    sines: sine::SineTable,
    /// Time zero of `t` in the API.
    start: std::time::Instant,
    /// Required on a non-loopback address.
    token: Option<String>,
    /// The machine inputs and faults of the drives `serve` hosts.
    control: Option<Arc<crate::control::Control>>,
    /// The bus's bitrate when known: the load's denominator.
    bitrate: Option<u32>,
    /// Frames and bits per second on the bus.
    load: load::BusLoad,
}

impl Web {
    /// Milliseconds since the server started (`t` of samples and events).
    pub fn t(&self) -> f64 {
        self.start.elapsed().as_secs_f64() * 1000.0
    }

    /// The personality of `node`: hosted, or recognized by its 1018h.
    pub fn profile(&self, node: u8) -> Option<Profile> {
        self.profiles
            .get(&node)
            .copied()
            .or_else(|| self.identified.lock().unwrap_or_else(|e| e.into_inner()).get(&node).copied())
    }

    /// Sends a server event to the streams.
    pub fn event(&self, v: serde_json::Value) {
        let _ = self.events.send(v);
    }

    /// An EMCY as the API gives it: the code, the text the master decoded
    /// (the hosted personality's table, else CiA 301/402) and the
    /// manual's classification of the code (`F439 (fault)`), if any.
    pub fn emcy_json(
        &self,
        node: u8,
        code: u16,
        register: u8,
        data: &[u8],
        text: Option<String>,
    ) -> serde_json::Value {
        let detail = self
            .profile(node)
            .and_then(|p| p.info().emcy.iter().find(|e| e.code == code))
            .map(|e| e.detail)
            .filter(|d| !d.is_empty());
        serde_json::json!({"t": self.t(), "node": node, "code": format!("{code:04X}"), "register": register,
            "data": values::hex(data), "text": text, "detail": detail})
    }
}

/// A running web server.
pub struct Server {
    /// Where it listens.
    pub addr: SocketAddr,
    /// The token, when one is required.
    pub token: Option<String>,
    /// The server task (aborted on drop).
    task: tokio::task::JoinHandle<()>,
}

impl Server {
    /// `http://ADDR/`, with `?token=` when one is required.
    pub fn url(&self) -> String {
        match &self.token {
            Some(t) => format!("http://{}/?token={t}", self.addr),
            None => format!("http://{}/", self.addr),
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.task.abort();
    }
}

/// Binds `addr` and serves the page and the API for `master`; `profiles`
/// are the drives this process hosts (their EMCY texts go to the master),
/// `control` their machine inputs and faults (`serve`).
pub async fn start(
    master: Master,
    dict: Dict,
    profiles: HashMap<u8, Profile>,
    control: Option<Arc<crate::control::Control>>,
    bitrate: Option<u32>,
    addr: &str,
) -> anyhow::Result<Server> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on --http {addr}: is the port free? (port 0 picks one)"))?;
    let local = listener.local_addr()?;
    let token = (!local.ip().is_loopback()).then(new_token);
    let (events, _) = broadcast::channel(256);
    // The manual's texts, as `Master::emcy_text` gives them to every EMCY event.
    for (&node, p) in &profiles {
        master.add_emcy_texts(node, p.info().emcy.iter().map(|e| (e.code, e.text)));
        // Its EDS (names, types, limits) unless `--eds` gave one.
        if master.eds(node).is_none()
            && let Ok(od) = drivebus_eds::to_od(&p.eds().eds, node)
        {
            master.set_eds(node, od);
        }
    }
    let web = Arc::new(Web {
        master,
        dict,
        profiles,
        identified: Mutex::new(HashMap::new()),
        emcy: Mutex::new(VecDeque::new()),
        events,
        jogs: jog::JogTable::default(),
        sines: sine::SineTable::default(),
        start: std::time::Instant::now(),
        token: token.clone(),
        control,
        bitrate,
        load: load::BusLoad::default(),
    });
    tokio::spawn(load::keep_measuring(web.clone()));
    tokio::spawn(keep_emcy(web.clone()));
    tokio::spawn(identify::keep_identifying(web.clone()));
    let app = router(web);
    let task = tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, app).await {
            tracing::error!(error = %e, "web server stopped");
        }
    });
    Ok(Server { addr: local, token, task })
}

/// The bus a page is served for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServedBus {
    /// CANopen nodes (`serve`, `ui`): the node overview, objects, drives, scope.
    Can,
    /// An EtherCAT line (`ethercat serve`): the line view (`line.js`).
    Ethercat,
}

/// The page's files: `index.html` (for an EtherCAT line with `<body
/// data-bus="ethercat">`, which the scripts read), the scripts and the style.
pub fn page_routes<S: Clone + Send + Sync + 'static>(bus: ServedBus) -> Router<S> {
    let index: &'static str = match bus {
        ServedBus::Ethercat => {
            static INDEX: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
                include_str!("assets/index.html").replacen("<body>", "<body data-bus=\"ethercat\">", 1)
            });
            INDEX.as_str()
        }
        ServedBus::Can => include_str!("assets/index.html"),
    };
    Router::new()
        .route("/", get(move || async move { page("text/html; charset=utf-8", index) }))
        .route(
            "/app.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/app.js")) }),
        )
        .route(
            "/scope.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/scope.js")) }),
        )
        .route(
            "/motion.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/motion.js")) }),
        )
        .route(
            "/pdo.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/pdo.js")) }),
        )
        .route(
            "/lss.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/lss.js")) }),
        )
        .route(
            "/machine.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/machine.js")) }),
        )
        .route(
            "/line.js",
            get(|| async { page("text/javascript; charset=utf-8", include_str!("assets/line.js")) }),
        )
        .route(
            "/style.css",
            get(|| async { page("text/css; charset=utf-8", include_str!("assets/style.css")) }),
        )
}

fn router(web: Arc<Web>) -> Router {
    page_routes(ServedBus::Can)
        .route("/api/nodes", get(api::nodes))
        .route("/api/nodes/{n}/sdo/{index}", get(api::sdo_get_object).put(api::sdo_put_object))
        .route("/api/nodes/{n}/sdo/{index}/{sub}", get(api::sdo_get).put(api::sdo_put))
        .route("/api/nodes/{n}/objects", get(objects::list))
        .route("/api/nodes/{n}/nmt", post(api::nmt))
        .route("/api/nodes/{n}/pdo", get(pdo::list))
        .route("/api/nodes/{n}/pdo/{dir}/{k}", axum::routing::put(pdo::write))
        .route("/api/nodes/{n}/drive", get(drive::status).post(drive::action))
        .route("/api/nodes/{n}/drive/homing", get(drive::homing))
        .route("/api/nodes/{n}/drive/jog", post(jog::jog))
        .route("/api/nodes/{n}/drive/sine", post(sine::sine))
        .route("/api/nodes/{n}/machine/input", post(machine::input))
        .route("/api/nodes/{n}/machine", get(machine::state))
        .route("/api/nodes/{n}/machine/fault", post(machine::fault))
        .route("/api/emcy", get(api::emcy))
        .route("/api/bus", get(load::bus))
        .route("/api/lss/scan", post(lss::scan))
        .route("/api/lss/inquire", post(lss::inquire))
        .route("/api/lss/configure", post(lss::configure))
        .route("/api/stream", get(stream::upgrade))
        .fallback(|| async { error::ApiError::not_found("no such page or endpoint: see docs/http-api.md") })
        .layer(axum::middleware::from_fn_with_state(web.clone(), auth))
        .with_state(web)
}

fn page(content_type: &'static str, body: &'static str) -> Response {
    ([(header::CONTENT_TYPE, HeaderValue::from_static(content_type))], body).into_response()
}

/// 401 without the token, when one is required.
async fn auth(State(web): State<Arc<Web>>, req: Request, next: Next) -> Response {
    check_token(web.token.as_deref(), req, next).await
}

/// Runs `req` when no token is required or it carries `want` (`?token=`
/// or the `X-Drivebus-Token` header); else 401. The one check of both
/// servers (`ui`/`serve --http`, `ethercat serve --http`).
pub async fn check_token(want: Option<&str>, req: Request, next: Next) -> Response {
    let Some(want) = want else { return next.run(req).await };
    let header = req.headers().get("x-drivebus-token").and_then(|v| v.to_str().ok());
    let query = req.uri().query().unwrap_or("").split('&').find_map(|kv| kv.strip_prefix("token="));
    if header == Some(want) || query == Some(want) {
        return next.run(req).await;
    }
    error::ApiError {
        status: StatusCode::UNAUTHORIZED,
        message: "missing or wrong token: this server listens beyond loopback; add ?token=TOKEN (printed at start) or the X-Drivebus-Token header".into(),
    }
    .into_response()
}

/// 128 random bits in hex (from the OS, else from the hasher's seed).
pub fn new_token() -> String {
    use std::io::Read;
    let mut b = [0u8; 16];
    let from_os = std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut b)).is_ok();
    if !from_os {
        use std::hash::{BuildHasher, Hasher};
        for c in b.chunks_mut(8) {
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_u128(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap_or_default()
                    .as_nanos(),
            );
            c.copy_from_slice(&h.finish().to_le_bytes());
        }
    }
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// Keeps the last EMCYs with their decoded text.
async fn keep_emcy(web: Arc<Web>) {
    let mut rx = web.master.subscribe_events();
    loop {
        match rx.recv().await {
            Ok(MasterEvent::Emcy { node, code, register, data, text }) => {
                let v = web.emcy_json(node, code, register, &data, text);
                let mut h = web.emcy.lock().unwrap_or_else(|e| e.into_inner());
                if h.len() == EMCY_HISTORY {
                    h.pop_front();
                }
                h.push_back(v);
            }
            Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
            Err(broadcast::error::RecvError::Closed) => return,
        }
    }
}

/// The personalities of `--sim PROFILE:NODE` (device files left out).
fn hosted_profiles(sim: &[String]) -> anyhow::Result<HashMap<u8, Profile>> {
    let drives: Vec<String> =
        sim.iter().filter(|s| !crate::vdevice::DeviceSpec::is_file_spec(s)).cloned().collect();
    Ok(crate::vdrive::DriveSpec::parse_all(&drives)?.into_iter().map(|s| (s.node, s.profile)).collect())
}

/// `drivebus ui`: the page for the bus of `--bus` (and its `--sim` drives)
/// until SIGINT/SIGTERM or the bus is lost.
pub async fn run_ui(g: &crate::args::Global, a: &crate::args::UiArgs) -> anyhow::Result<()> {
    let stop = crate::serve::Signals::install()?;
    let conn = crate::conn::Conn::open(g).await?;
    let dict = Dict { eds: crate::eds_cmd::load_global_eds(g)? };
    let bitrate = match drivebus_transport::BusUrl::parse(&g.bus) {
        Ok(drivebus_transport::BusUrl::Slcan { bitrate, .. }) => bitrate,
        _ => None,
    };
    let server = start(conn.master.clone(), dict, hosted_profiles(&g.sim)?, None, bitrate, &a.http).await?;
    let nodes: Vec<String> = conn.master.seen_nodes().iter().map(u8::to_string).collect();
    let seen =
        if nodes.is_empty() { "none seen yet".to_owned() } else { format!("nodes {}", nodes.join(", ")) };
    crate::output::outln!("drivebus ui: open {} in a browser ({seen} on {})", server.url(), g.bus);
    tokio::select! {
        r = stop.wait() => r?,
        why = conn.master.lost() => return Err(conn.lost(&why)),
    }
    drop(server);
    conn.close().await
}
