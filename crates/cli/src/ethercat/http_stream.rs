//! `ethercat serve --http`'s `/api/stream`: object subscriptions as on
//! the CAN side (`{"subscribe": [{"node": 1, "index": "6064", ...}]}`,
//! the node being the slave's line position). An object mapped in the
//! slave's process data is sampled after every frame that carried it
//! (a host frame observer with [`objects::Watch`]: raw bytes only in the
//! frame path, decoded here); every object is also read at the period
//! asked while no process-data sample came within it (a line not in OP).

use std::collections::VecDeque;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use drivebus_ethercat::objects::{self, Watch};
use drivebus_ethercat::{Host, ObserverId};
use drivebus_master::{DataType, Value};
use serde_json::{Value as Json_, json};
use tokio::sync::Notify;
use tokio::task::JoinHandle;

use super::http::Served;
use super::http_objects::{position, slot};
use crate::web::Queue;
use crate::web::stream::Channel;
use crate::web::values;

/// Raw samples the frame path leaves before the stream decodes them.
const RAW: usize = 4096;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    subscribe: Option<Vec<Channel>>,
    ping: Option<Json_>,
}

const SHAPE: &str = r#"{"subscribe": [{"node": 1, "index": "6064", "sub": 0, "period_ms": 10}]}"#;

/// One subscribed object.
struct Plan {
    position: usize,
    index: u16,
    sub: u8,
    dt: DataType,
    period: Duration,
    mapped: bool,
}

/// A sample as the frame path leaves it: channel, `t`, the value's
/// bytes (a PDO entry has at most 64 bits) and how many.
type RawSample = (usize, f64, [u8; 8], u8);

/// What the frame observer leaves, and per channel when its last
/// process-data sample came.
#[derive(Default)]
struct Raw {
    samples: Mutex<VecDeque<RawSample>>,
    last_pdo: Mutex<Vec<Option<Instant>>>,
    ready: Notify,
}

/// A running subscription: its observer and tasks end with it.
pub struct Subscription {
    host: Host,
    observer: Option<ObserverId>,
    tasks: Vec<JoinHandle<()>>,
    /// Channels subscribed.
    pub channels: usize,
}

impl Drop for Subscription {
    fn drop(&mut self) {
        if let Some(id) = self.observer {
            self.host.stop_observing(id);
        }
        self.tasks.iter().for_each(JoinHandle::abort);
    }
}

/// Handles a client's text message: a new subscription (replacing the
/// old one when `Some`), or an error message to queue. A ping's pong is
/// queued at once.
pub fn message(s: &Served, queue: &Arc<Queue>, text: &str) -> Result<Option<Subscription>, String> {
    let r: Request =
        serde_json::from_str(text).map_err(|e| format!("malformed subscription: {e}; send {SHAPE}"))?;
    if let Some(p) = &r.ping {
        queue.push(&json!({"type": "pong", "ping": p, "t": s.t()}));
    }
    match r.subscribe {
        Some(c) => subscribe(s, queue, &c).map(Some),
        None if r.ping.is_some() => Ok(None),
        None => Err(format!("nothing asked: send {SHAPE}")),
    }
}

fn plan(s: &Served, c: &Channel) -> Result<Plan, String> {
    let p = position(&c.node_text()).map_err(|e| e.message)?;
    let slot = slot(&s.host, &s.slots, p).map_err(|e| e.message)?;
    let (index, sub) =
        values::object(&slot.dict, &c.index_text(), Some(&format!("{:X}", c.sub))).map_err(|e| e.message)?;
    let dt = slot.data_type(index, sub, c.ty.as_deref()).map_err(|e| e.message)?.ok_or_else(|| {
        format!(
            "slave {p} has no object {index:04X}h:{sub:02X}h: GET /api/nodes/{p}/objects lists its objects"
        )
    })?;
    // The assignment as it is now (a master may change it in PRE-OP).
    let mapped = objects::with_objects(&s.host, p, |a| objects::in_process_data(a.dictionary(), index, sub))
        .map_err(|e| e.to_string())?;
    Ok(Plan { position: p, index, sub, dt, period: c.period(), mapped })
}

fn subscribe(s: &Served, queue: &Arc<Queue>, channels: &[Channel]) -> Result<Subscription, String> {
    let plans: Vec<Plan> = channels.iter().map(|c| plan(s, c)).collect::<Result<_, _>>()?;
    let plans = Arc::new(plans);
    let raw = Arc::new(Raw { last_pdo: Mutex::new(vec![None; plans.len()]), ..Raw::default() });
    let mut sub =
        Subscription { host: s.host.clone(), observer: None, tasks: Vec::new(), channels: plans.len() };
    let mapped: Vec<usize> = (0..plans.len()).filter(|&i| plans[i].mapped).collect();
    if !mapped.is_empty() {
        let mut watch =
            Watch::new(mapped.iter().map(|&i| (plans[i].position, plans[i].index, plans[i].sub)).collect());
        let (frame_raw, start, frame_queue) = (raw.clone(), s.start, queue.clone());
        sub.observer = Some(s.host.observe_frames(move |seg| {
            let t = start.elapsed().as_secs_f64() * 1000.0;
            let mut got = false;
            watch.after_frame(seg, |k, bytes| {
                let mut b = [0u8; 8];
                let n = bytes.len().min(8);
                b[..n].copy_from_slice(&bytes[..n]);
                let mut q = frame_raw.samples.lock().unwrap_or_else(|e| e.into_inner());
                if q.len() >= RAW {
                    q.pop_front();
                    frame_queue.dropped.fetch_add(1, Ordering::Relaxed);
                }
                q.push_back((mapped[k], t, b, n as u8));
                got = true;
            });
            if got {
                frame_raw.ready.notify_one();
            }
        }));
        sub.tasks.push(tokio::spawn(decode(queue.clone(), plans.clone(), raw.clone())));
    }
    for i in 0..plans.len() {
        sub.tasks.push(tokio::spawn(poll(s.clone(), queue.clone(), plans.clone(), raw.clone(), i)));
    }
    Ok(sub)
}

fn sample(t: f64, p: &Plan, v: &Value, source: &str) -> Json_ {
    json!({"type": "sample", "t": t, "node": p.position, "index": format!("{:04X}", p.index), "sub": p.sub,
        "value": values::to_json(v), "source": source})
}

/// Decodes the frame path's raw samples into the client's queue.
async fn decode(queue: Arc<Queue>, plans: Arc<Vec<Plan>>, raw: Arc<Raw>) {
    loop {
        raw.ready.notified().await;
        let taken: Vec<_> = raw.samples.lock().unwrap_or_else(|e| e.into_inner()).drain(..).collect();
        let now = Instant::now();
        for (i, t, b, n) in taken {
            let p = &plans[i];
            if let Ok(v) = Value::decode(p.dt, &b[..usize::from(n)]) {
                queue.push(&sample(t, p, &v, "pdo"));
                raw.last_pdo.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(now);
            }
        }
    }
}

/// Reads channel `i` at its period while no process-data sample came
/// within it; a run of failures is said once.
async fn poll(s: Served, queue: Arc<Queue>, plans: Arc<Vec<Plan>>, raw: Arc<Raw>, i: usize) {
    let p = &plans[i];
    let mut tick = tokio::time::interval(p.period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut failing = false;
    loop {
        tick.tick().await;
        let recent = raw.last_pdo.lock().unwrap_or_else(|e| e.into_inner())[i]
            .is_some_and(|t| t.elapsed() < p.period * 2);
        if recent {
            continue;
        }
        match objects::read(&s.host, p.position, p.index, p.sub).map(|b| Value::decode(p.dt, &b)) {
            Ok(Ok(v)) => {
                failing = false;
                queue.push(&sample(s.t(), p, &v, "sdo"));
            }
            r if !failing => {
                failing = true;
                let why = match r {
                    Err(e) => e.to_string(),
                    Ok(Err(a)) => format!("not a {}: {a}", p.dt.name()),
                    Ok(Ok(_)) => String::new(),
                };
                queue.push(&json!({"type": "error", "t": s.t(), "node": p.position,
                    "index": format!("{:04X}", p.index), "sub": p.sub, "error": why}));
            }
            _ => {}
        }
    }
}
