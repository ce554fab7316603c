//! `GET /api/stream` (WebSocket): samples of the objects a client
//! subscribes to (from their TPDO when mapped, else polled by SDO at the
//! period it asks), raw frames (`frames.rs`), and NMT, EMCY and motion
//! events. Everything goes through one bounded queue per client:
//! when the client reads slower than the bus gives, the oldest messages
//! are dropped and counted, and the count is in every `status` message,
//! so the bus side never waits for a browser.

use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use axum::extract::State;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::response::Response;
use drivebus_master::{Frame, MasterEvent, PdoDir, RemoteState, Value};
use serde_json::{Value as Json_, json};
use tokio::sync::{Notify, broadcast};
use tokio::task::JoinHandle;

use super::Web;
use super::api::{nmt_name, seen_node};
use super::frames::{self, FrameSelection};
use super::values;
use crate::decode;

/// Messages queued per client before the oldest is dropped.
const QUEUE: usize = 4096;
/// Shortest polling period a client may ask for.
const MIN_PERIOD_MS: u64 = 1;

/// A client's bounded queue.
pub struct Queue {
    q: Mutex<VecDeque<String>>,
    /// Messages dropped so far (sent in every `status`).
    pub dropped: AtomicU64,
    ready: Notify,
}

impl Queue {
    /// An empty queue.
    pub fn new() -> Arc<Queue> {
        Arc::new(Queue { q: Mutex::new(VecDeque::new()), dropped: AtomicU64::new(0), ready: Notify::new() })
    }

    /// Waits until a message is queued.
    pub async fn ready(&self) {
        self.ready.notified().await
    }

    /// Queues `v`, dropping the oldest message when full.
    pub fn push(&self, v: &Json_) {
        let mut q = self.q.lock().unwrap_or_else(|e| e.into_inner());
        if q.len() >= QUEUE {
            q.pop_front();
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
        q.push_back(v.to_string());
        drop(q);
        self.ready.notify_one();
    }

    /// The queued messages, oldest first; empties the queue.
    pub fn take(&self) -> Vec<String> {
        self.q.lock().unwrap_or_else(|e| e.into_inner()).drain(..).collect()
    }
}

/// Upgrades to the stream.
pub async fn upgrade(State(web): State<Arc<Web>>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |s| session(web, s))
}

/// Aborts its tasks when the client goes.
struct Tasks(Vec<JoinHandle<()>>);

impl Drop for Tasks {
    fn drop(&mut self) {
        self.0.iter().for_each(JoinHandle::abort);
    }
}

async fn session(web: Arc<Web>, mut socket: WebSocket) {
    let queue = Queue::new();
    let _events = Tasks(vec![tokio::spawn(events(web.clone(), queue.clone()))]);
    let mut polls = Tasks(Vec::new());
    let mut frames = Tasks(Vec::new());
    let mut status = tokio::time::interval(Duration::from_secs(1));
    loop {
        tokio::select! {
            m = socket.recv() => match m {
                Some(Ok(Message::Text(t))) => match request(&web, &queue, t.as_str()) {
                    // A ping alone: its pong is queued.
                    Ok((None, None)) => {}
                    Ok((channels, filter)) => {
                        let mut answer = json!({"type": "subscribed"});
                        if let Some(tasks) = channels {
                            answer["channels"] = json!(tasks.len());
                            polls = Tasks(tasks);
                        }
                        if let Some(task) = filter {
                            answer["frames"] = json!(task.is_some());
                            frames = Tasks(task.into_iter().collect());
                        }
                        queue.push(&answer);
                    }
                    Err(e) => queue.push(&json!({"type": "error", "error": e})),
                },
                Some(Ok(_)) => {}
                Some(Err(_)) | None => return,
            },
            _ = queue.ready.notified() => {
                for m in queue.take() {
                    if socket.send(Message::Text(m.into())).await.is_err() {
                        return;
                    }
                }
            }
            _ = status.tick() => {
                let s = json!({"type": "status", "t": web.t(), "dropped": queue.dropped.load(Ordering::Relaxed),
                    "channels": polls.0.len(), "frames": !frames.0.is_empty()});
                if socket.send(Message::Text(s.to_string().into())).await.is_err() {
                    return;
                }
            }
        }
    }
}

/// A client message: object channels, raw frames, or both.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    subscribe: Option<Vec<Channel>>,
    /// Absent: unchanged; `null`: no frames; an object: the filter.
    #[serde(default, deserialize_with = "present")]
    frames: Option<Json_>,
    /// Echoed at once through the client's queue as a `pong` with the
    /// server's `t` (the stream's own latency and clock offset).
    ping: Option<Json_>,
}

/// `Some` for any value given, `null` included.
fn present<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Json_>, D::Error> {
    <Json_ as serde::Deserialize>::deserialize(d).map(Some)
}

const SHAPE: &str = r#"{"subscribe": [{"node": 1, "index": "6064", "sub": 0, "period_ms": 10}]} or {"frames": {"ids": ["0x180-0x1FF"]}}"#;

/// What a message asks for: the new polling tasks (if it has
/// `subscribe`) and the new frame task (if it has `frames`; `None` inside
/// for `null`). An error names the first fault and starts nothing.
#[allow(clippy::type_complexity)]
fn request(
    web: &Arc<Web>,
    queue: &Arc<Queue>,
    text: &str,
) -> Result<(Option<Vec<JoinHandle<()>>>, Option<Option<JoinHandle<()>>>), String> {
    let r: Request =
        serde_json::from_str(text).map_err(|e| format!("malformed subscription: {e}; send {SHAPE}"))?;
    if let Some(p) = &r.ping {
        queue.push(&json!({"type": "pong", "ping": p, "t": web.t()}));
        if r.subscribe.is_none() && r.frames.is_none() {
            return Ok((None, None));
        }
    }
    if r.subscribe.is_none() && r.frames.is_none() {
        return Err(format!("nothing asked: send {SHAPE}"));
    }
    let filter = match &r.frames {
        Some(Json_::Null) => Some(None),
        Some(v) => Some(Some(FrameSelection::parse(v)?)),
        None => None,
    };
    let channels = r.subscribe.as_deref().map(|c| subscribe(web, queue, c)).transpose()?;
    let frames = filter.map(|f| f.map(|f| tokio::spawn(frames::forward(web.clone(), queue.clone(), f))));
    Ok((channels, frames))
}

/// One channel of a `{"subscribe": [...]}` message, on both servers'
/// streams (`ethercat serve --http`'s node is the slave's position).
#[derive(serde::Deserialize)]
pub(crate) struct Channel {
    node: Json_,
    index: Json_,
    /// The sub-index.
    #[serde(default)]
    pub(crate) sub: u8,
    period_ms: Option<u64>,
    /// The type to decode as, for objects the dictionary does not know.
    #[serde(rename = "type")]
    pub(crate) ty: Option<String>,
}

/// A number or a string as the text the API's parsers take.
fn text_of(v: &Json_) -> String {
    match v {
        Json_::String(s) => s.clone(),
        other => other.to_string(),
    }
}

impl Channel {
    /// The node as written (`1`, `"1"`).
    pub(crate) fn node_text(&self) -> String {
        text_of(&self.node)
    }

    /// The object as written (`"6064"`, `"position actual value"`, `24676`).
    pub(crate) fn index_text(&self) -> String {
        text_of(&self.index)
    }

    /// How often to poll: `period_ms` (100 ms when not given), at least
    /// [`MIN_PERIOD_MS`].
    pub(crate) fn period(&self) -> Duration {
        Duration::from_millis(self.period_ms.unwrap_or(100).max(MIN_PERIOD_MS))
    }
}

/// Starts one polling task per channel of a `{"subscribe": [...]}`
/// message (replacing the previous subscription); an error names the
/// first bad channel and starts nothing.
fn subscribe(
    web: &Arc<Web>,
    queue: &Arc<Queue>,
    channels: &[Channel],
) -> Result<Vec<JoinHandle<()>>, String> {
    let mut plan = Vec::new();
    for c in channels {
        let node = seen_node(web, &c.node_text()).map_err(|e| e.message)?;
        let (index, sub) = values::object(&web.dict, &c.index_text(), Some(&format!("{:X}", c.sub)))
            .map_err(|e| e.message)?;
        let dt = match &c.ty {
            Some(t) => values::data_type(t).map_err(|e| e.message)?,
            None => web.dict.data_type(index, sub).or_else(|| web.master.sdo(node).data_type(index, sub)).ok_or_else(
                || format!("the data type of {index:04X}h:{sub:02X}h is unknown: add \"type\": \"i32\" to the channel"),
            )?,
        };
        plan.push((node, index, sub, dt, c.period()));
    }
    Ok(plan.into_iter().map(|p| tokio::spawn(poll(web.clone(), queue.clone(), p))).collect())
}

async fn poll(web: Arc<Web>, queue: Arc<Queue>, p: (u8, u16, u8, drivebus_master::DataType, Duration)) {
    let (node, index, sub, dt, period) = p;
    // Mapped in a TPDO: a sample per frame of it; by SDO only while the
    // node does not send its TPDOs (not operational).
    let (mut pdo, at, bits) = match tpdo_of(&web, node, index, sub).await {
        Some((rx, at, bits)) => (Some(rx), at, bits),
        None => (None, 0, 0),
    };
    let sdo = web.master.sdo(node);
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut failing = false;
    // When the last TPDO sample was taken: while TPDOs come, SDO is not
    // needed, and an SDO answer older than a TPDO sample is stale.
    let mut last_pdo: Option<tokio::time::Instant> = None;
    loop {
        tokio::select! {
            f = next_pdo(&mut pdo) => {
                match f {
                    Ok(f) => {
                        if let Some(v) = decode::entry_bytes(f.data(), at, bits).and_then(|b| Value::decode(dt, &b).ok()) {
                            queue.push(&sample(&web, node, index, sub, &v, "pdo"));
                            last_pdo = Some(tokio::time::Instant::now());
                        }
                    }
                    Err(broadcast::error::RecvError::Lagged(n)) => {
                        queue.dropped.fetch_add(n, Ordering::Relaxed);
                    }
                    Err(broadcast::error::RecvError::Closed) => pdo = None,
                }
                continue;
            }
            _ = tick.tick() => {}
        }
        let pdo_recent = last_pdo.is_some_and(|t| t.elapsed() < period);
        if pdo.is_some() && (pdo_recent || web.master.node_state(node) == Some(RemoteState::Operational)) {
            continue;
        }
        let asked = tokio::time::Instant::now();
        match sdo.upload(index, sub).await.map(|raw| Value::decode(dt, &raw)) {
            // A TPDO sample came while the upload was under way: it is newer.
            Ok(Ok(_)) if last_pdo.is_some_and(|t| t >= asked) => failing = false,
            Ok(Ok(v)) => {
                failing = false;
                queue.push(&sample(&web, node, index, sub, &v, "sdo"));
            }
            // Said once per run of failures, not at every period.
            r if !failing => {
                failing = true;
                let why = match r {
                    Err(e) => e.to_string(),
                    Ok(Err(a)) => format!("not a {}: {a}", dt.name()),
                    Ok(Ok(_)) => String::new(),
                };
                queue.push(
                    &json!({"type": "error", "t": web.t(), "node": node, "index": format!("{index:04X}"),
                    "sub": sub, "error": why}),
                );
            }
            _ => {}
        }
    }
}

/// The next frame of the TPDO, never without one.
async fn next_pdo(rx: &mut Option<broadcast::Receiver<Frame>>) -> Result<Frame, broadcast::error::RecvError> {
    match rx {
        Some(rx) => rx.recv().await,
        None => std::future::pending().await,
    }
}

fn sample(web: &Web, node: u8, index: u16, sub: u8, v: &Value, source: &str) -> Json_ {
    json!({"type": "sample", "t": web.t(), "node": node, "index": format!("{index:04X}"), "sub": sub,
        "value": values::to_json(v), "source": source})
}

/// When `index:sub` is mapped in a valid TPDO of `node` (as the master
/// reads the mapping now): the frames of that TPDO from now on, and the
/// entry's bit offset and length in them. Decoded in the client's task,
/// not in the master's frame path.
async fn tpdo_of(
    web: &Web,
    node: u8,
    index: u16,
    sub: u8,
) -> Option<(broadcast::Receiver<Frame>, usize, usize)> {
    for num in 1..=512u16 {
        let Ok(rec) = web.master.read_pdo(node, PdoDir::Tx, num).await else { break };
        if let Some((at, bits)) = decode::mapped_at(&rec.mapping, index, sub).filter(|_| rec.valid()) {
            return Some((web.master.subscribe_pdo(rec.can_id()), at, bits));
        }
    }
    None
}

/// NMT state changes, EMCYs and the server's motion events.
async fn events(web: Arc<Web>, queue: Arc<Queue>) {
    let mut bus = web.master.subscribe_events();
    let mut own = web.events.subscribe();
    let mut last: HashMap<u8, RemoteState> = HashMap::new();
    loop {
        let ev = tokio::select! {
            e = bus.recv() => match e {
                Ok(e) => bus_event(&web, &mut last, e),
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    queue.dropped.fetch_add(n, Ordering::Relaxed);
                    None
                }
                Err(broadcast::error::RecvError::Closed) => return,
            },
            e = own.recv() => e.ok(),
        };
        if let Some(ev) = ev {
            queue.push(&ev);
        }
    }
}

fn bus_event(web: &Web, last: &mut HashMap<u8, RemoteState>, e: MasterEvent) -> Option<Json_> {
    let t = web.t();
    Some(match e {
        MasterEvent::Bootup { node } => {
            last.insert(node, RemoteState::BootUp);
            json!({"type": "event", "event": "bootup", "t": t, "node": node})
        }
        MasterEvent::Heartbeat { node, state } => {
            if last.insert(node, state) == Some(state) {
                return None;
            }
            json!({"type": "event", "event": "nmt", "t": t, "node": node, "state": nmt_name(state)})
        }
        MasterEvent::HeartbeatLost { node } => {
            json!({"type": "event", "event": "heartbeat-lost", "t": t, "node": node})
        }
        MasterEvent::HeartbeatRecovered { node } => {
            json!({"type": "event", "event": "heartbeat-recovered", "t": t, "node": node})
        }
        MasterEvent::Emcy { node, code, register, data, text } => {
            let mut v = web.emcy_json(node, code, register, &data, text);
            v["type"] = json!("event");
            v["event"] = json!("emcy");
            v
        }
        MasterEvent::BusError { reason } => {
            json!({"type": "event", "event": "bus-error", "t": t, "reason": reason})
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A client that reads slower than samples come loses the oldest,
    /// counted; the queue never grows past its bound.
    #[test]
    fn the_queue_drops_the_oldest_and_counts() {
        let q = Queue { q: Mutex::new(VecDeque::new()), dropped: AtomicU64::new(0), ready: Notify::new() };
        for i in 0..QUEUE + 10 {
            q.push(&json!(i));
        }
        assert_eq!(q.dropped.load(Ordering::Relaxed), 10);
        let all = q.take();
        assert_eq!(all.len(), QUEUE);
        assert_eq!(all[0], "10");
        assert_eq!(all.last().map(String::as_str), Some(&*(QUEUE + 9).to_string()));
        assert!(q.take().is_empty());
    }
}
