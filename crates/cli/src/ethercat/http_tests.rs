//! `ethercat serve --http` in process: the server of `http.rs` on a line
//! hosted on real time, our own master (`LineMaster` over the in-process
//! link) cycling it where a test needs process data.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use drivebus_can::Duration;
use drivebus_ethercat::drive::DriveLine;
use drivebus_ethercat::master::drive::CyclicDrive;
use drivebus_ethercat::master::{LineMaster, PduFrames, block_on};
use drivebus_ethercat::{BoxDevice, Clock, Host, dio};
use drivebus_personality::Profile;
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};

/// An iPOS, a generic servo and a digital I/O slave (no CoE).
fn line() -> Host {
    let mut devices = DriveLine::new().drive(Profile::Ipos).drive(Profile::Generic).devices().unwrap();
    devices.push(Box::new(dio::slave(&dio::DioConfig::default())) as BoxDevice);
    Host::line(devices, Clock::real())
}

async fn get(base: &str, path: &str) -> (u16, Value) {
    let r = reqwest::get(format!("{base}{path}")).await.unwrap();
    (r.status().as_u16(), r.json().await.unwrap())
}

async fn put(base: &str, path: &str, body: Value) -> (u16, Value) {
    let r = reqwest::Client::new().put(format!("{base}{path}")).json(&body).send().await.unwrap();
    (r.status().as_u16(), r.json().await.unwrap())
}

/// Objects by position: 6041h of slave 1 read (by index and by name),
/// 6060h of slave 2 written and read back; a write to the read-only
/// 6041h is 422 with the abort's CiA 301 text and changes nothing; an
/// unknown position and the I/O slave without a dictionary are 404, a bad
/// index 400; the dictionary browser lists 6064h with its type.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn objects_by_position() {
    let host = line();
    let super::http::Started { task, addr, .. } =
        super::http::start(host.clone(), "127.0.0.1:0").await.unwrap();
    let base = format!("http://{addr}");
    let (st, v) = get(&base, "/api/nodes/1/sdo/6041/0").await;
    assert_eq!(st, 200, "{v}");
    assert_eq!(
        (v["node"].as_u64(), v["index"].as_str(), v["type"].as_str()),
        (Some(1), Some("6041"), Some("UNSIGNED16"))
    );
    let sw = v["value"].as_u64().expect("a number");
    let (st, by_name) = get(&base, "/api/nodes/1/sdo/statusword").await;
    assert_eq!(
        (st, by_name["index"].as_str(), by_name["value"].as_u64()),
        (200, Some("6041"), Some(sw)),
        "{by_name}"
    );

    let (st, v) = put(&base, "/api/nodes/2/sdo/6060/0", json!({"value": 3})).await;
    assert_eq!((st, v["written"].as_bool(), v["value"].as_i64()), (200, Some(true), Some(3)), "{v}");
    let (st, v) = get(&base, "/api/nodes/2/sdo/6060/0").await;
    assert_eq!((st, v["value"].as_i64(), v["type"].as_str()), (200, Some(3), Some("INTEGER8")), "{v}");

    let (st, v) = put(&base, "/api/nodes/1/sdo/6041/0", json!({"value": 0x27})).await;
    assert_eq!(st, 422, "{v}");
    let e = v["error"].as_str().unwrap();
    assert!(e.contains("06010002h") && e.contains("read only object"), "{e}");
    let (_, v) = get(&base, "/api/nodes/1/sdo/6041/0").await;
    assert_eq!(v["value"].as_u64(), Some(sw), "the refused write changed nothing");

    let (st, v) = get(&base, "/api/nodes/4/sdo/6041/0").await;
    assert_eq!(st, 404, "{v}");
    assert!(v["error"].as_str().unwrap().contains("no slave at position 4"), "{v}");
    let (st, v) = get(&base, "/api/nodes/3/sdo/1000/0").await;
    assert_eq!(st, 404, "{v}");
    assert!(v["error"].as_str().unwrap().contains("no CoE object dictionary"), "{v}");
    let (st, v) = get(&base, "/api/nodes/1/sdo/zz/0").await;
    assert_eq!(st, 400, "{v}");
    let (st, v) = get(&base, "/api/nodes/1/sdo/5FFF/0").await;
    assert_eq!(st, 404, "{v}");
    let (st, v) = get(&base, "/api/nodes/x/sdo/6041/0").await;
    assert_eq!(st, 400, "{v}");

    let (st, v) = get(&base, "/api/nodes/1/objects?q=6064").await;
    assert_eq!(st, 200, "{v}");
    let o = &v["objects"][0];
    assert_eq!(
        (o["index"].as_str(), o["type"].as_str(), o["access"].as_str(), o["unit"].as_str()),
        (Some("6064"), Some("INTEGER32"), Some("ro"), Some("position units")),
        "{v}"
    );
    let (_, v) = get(&base, "/api/nodes/1/sdo/6064/0").await;
    assert_eq!(v["unit"], "position units", "{v}");
    task.abort();
}

/// A subscription to 6064h of slave 1 (mapped in its TxPDO) gets a
/// `pdo` sample per process-data cycle while our master cycles the line
/// in OP, with the stream's message format.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stream_samples_6064_at_every_cycle() {
    static S: PduFrames = PduFrames::new();
    let host = line();
    let super::http::Started { task, addr, .. } =
        super::http::start(host.clone(), "127.0.0.1:0").await.unwrap();
    let (mut ws, _) =
        tokio_tungstenite::connect_async(format!("ws://{addr}/api/stream")).await.expect("WebSocket");
    let sub = json!({"subscribe": [{"node": 1, "index": "6064", "period_ms": 5000}]});
    ws.send(tokio_tungstenite::tungstenite::Message::Text(sub.to_string().into())).await.unwrap();

    let stop = Arc::new(AtomicBool::new(false));
    let cycles = {
        let (stop, host) = (stop.clone(), host.clone());
        std::thread::spawn(move || -> u64 {
            let m = LineMaster::on_host(&S, host).unwrap();
            block_on(async {
                let g = m.init().await.unwrap();
                let mut d =
                    CyclicDrive::start(&m, g, 1, Duration::from_millis(2), false, None).await.unwrap();
                while !stop.load(Ordering::Relaxed) {
                    d.cycle().await.unwrap();
                }
                d.cycles
            })
        })
    };
    let mut pdo = Vec::new();
    let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(20);
    while pdo.len() < 50 {
        let m =
            tokio::time::timeout_at(deadline, ws.next()).await.expect("50 samples in 20 s").unwrap().unwrap();
        let v: Value = serde_json::from_str(m.to_text().unwrap()).unwrap();
        if v["type"] == "error" {
            panic!("{v}");
        }
        if v["type"] == "sample" && v["source"] == "pdo" {
            assert_eq!(
                (v["node"].as_u64(), v["index"].as_str(), v["sub"].as_u64()),
                (Some(1), Some("6064"), Some(0)),
                "{v}"
            );
            assert!(v["value"].is_i64() && v["t"].is_f64(), "{v}");
            pdo.push(v);
        }
    }
    stop.store(true, Ordering::Relaxed);
    let cycles = cycles.join().unwrap();
    // The samples of the last cycles, still on their way.
    while let Ok(Some(Ok(m))) = tokio::time::timeout(std::time::Duration::from_millis(500), ws.next()).await {
        let v: Value = serde_json::from_str(m.to_text().unwrap()).unwrap();
        if v["type"] == "sample" && v["source"] == "pdo" {
            pdo.push(v);
        }
    }
    // One per cycle in OP, and the few frames with process data that
    // brought the line there (SAFE-OP, the first exchange).
    let n = pdo.len() as u64;
    assert!(cycles <= n && n <= cycles + 5, "{n} samples for {cycles} cycles");
    let t: Vec<f64> = pdo.iter().map(|v| v["t"].as_f64().unwrap()).collect();
    assert!(t.windows(2).all(|w| w[0] <= w[1]), "in order: {t:?}");
    task.abort();
}

/// Beyond loopback the API writes only with the token: without it 401 and
/// nothing written, with it (`?token=` or the header) as on loopback.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn beyond_loopback_the_token_is_required() {
    let host = line();
    let s = super::http::start(host.clone(), "0.0.0.0:0").await.unwrap();
    let token = s.token.clone().expect("a token beyond loopback");
    let base = format!("http://127.0.0.1:{}", s.addr.port());
    let (st, v) = put(&base, "/api/nodes/2/sdo/6060/0", json!({"value": 3})).await;
    assert_eq!(st, 401, "{v}");
    let (st, _) = get(&base, "/api/ethercat").await;
    assert_eq!(st, 401);
    let mode = drivebus_ethercat::objects::read(&host, 2, 0x6060, 0).unwrap();
    assert_ne!(mode, [3]);
    let (st, v) = put(&base, &format!("/api/nodes/2/sdo/6060/0?token={token}"), json!({"value": 3})).await;
    assert_eq!(st, 200, "{v}");
    assert_eq!(drivebus_ethercat::objects::read(&host, 2, 0x6060, 0).unwrap(), [3]);
    let r = reqwest::Client::new()
        .get(format!("{base}/api/ethercat"))
        .header("X-Drivebus-Token", &*token)
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);
    s.task.abort();
}
