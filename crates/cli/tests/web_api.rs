//! The HTTP API of `drivebus ui` and `serve --http` (docs/http-api.md),
//! with an HTTP and a WebSocket client against the real binary and two
//! virtual drives: every endpoint, and every bad input answered with a
//! 4xx `{"error": ...}` that changed nothing (checked by reading back).

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};

/// A running `drivebus ui`; killed when dropped.
struct Ui {
    child: Child,
    /// `http://ADDR` without the trailing slash.
    base: String,
    line: String,
    /// Its stderr (the log).
    log: tempfile::NamedTempFile,
}

impl Ui {
    fn start(args: &[&str]) -> Ui {
        let log = tempfile::NamedTempFile::new().expect("log file");
        let mut child = Command::new(common::bin())
            .args(args)
            .env_remove("RUST_LOG")
            .stdout(Stdio::piped())
            .stderr(log.reopen().expect("log file"))
            .spawn()
            .expect("spawn drivebus");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let line = rx.recv_timeout(Duration::from_secs(60)).expect("drivebus printed no ready line");
        let at = line.find("http://").unwrap_or_else(|| panic!("no http:// in `{line}`"));
        let url: String = line[at..].chars().take_while(|c| !c.is_whitespace() && *c != '?').collect();
        Ui { child, base: url.trim_end_matches('/').to_owned(), line, log }
    }

    fn sims() -> Ui {
        Ui::start(&["ui", "--sim", "akd:1", "--sim", "dds6:2", "--http", "127.0.0.1:0"])
    }

    fn log(&self) -> String {
        std::fs::read_to_string(self.log.path()).unwrap_or_default()
    }

    fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }
}

impl Drop for Ui {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn client() -> reqwest::Client {
    reqwest::Client::builder().timeout(Duration::from_secs(30)).build().expect("client")
}

async fn get(ui: &Ui, path: &str) -> (u16, Value) {
    let r = client().get(ui.url(path)).send().await.expect("GET");
    let status = r.status().as_u16();
    (status, r.json().await.expect("JSON answer"))
}

async fn send(ui: &Ui, method: reqwest::Method, path: &str, body: &str) -> (u16, Value) {
    let r = client()
        .request(method, ui.url(path))
        .header("content-type", "application/json")
        .body(body.to_owned())
        .send()
        .await
        .expect("request");
    let status = r.status().as_u16();
    (status, r.json().await.expect("JSON answer"))
}

async fn put(ui: &Ui, path: &str, body: Value) -> (u16, Value) {
    send(ui, reqwest::Method::PUT, path, &body.to_string()).await
}

async fn post(ui: &Ui, path: &str, body: Value) -> (u16, Value) {
    send(ui, reqwest::Method::POST, path, &body.to_string()).await
}

/// A 4xx with an `error` text containing `word`.
fn refused(r: &(u16, Value), status: u16, word: &str) {
    assert_eq!(r.0, status, "{r:?}");
    let e = r.1["error"].as_str().unwrap_or_else(|| panic!("no error text in {r:?}"));
    assert!(e.contains(word), "`{e}` does not say `{word}`");
}

/// Polls `f` until it gives `Some`, for at most `limit`.
async fn wait_for<T, F: std::future::Future<Output = Option<T>>>(
    limit: Duration,
    mut f: impl FnMut() -> F,
) -> T {
    let t0 = Instant::now();
    loop {
        if let Some(v) = f().await {
            return v;
        }
        assert!(t0.elapsed() < limit, "condition not met within {limit:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ui_prints_one_line_and_lists_both_drives() {
    let ui = Ui::sims();
    assert!(ui.line.starts_with("drivebus ui: open http://127.0.0.1:"), "{}", ui.line);
    let (s, v) = get(&ui, "/api/nodes").await;
    assert_eq!(s, 200, "{v}");
    let nodes = v["nodes"].as_array().expect("nodes");
    assert_eq!(nodes.iter().map(|n| n["node"].as_u64().unwrap()).collect::<Vec<_>>(), vec![1, 2]);
    for n in nodes {
        assert_eq!(n["device_type"].as_u64().map(|t| t & 0xFFFF), Some(402), "{n}");
        assert!(n["identity"]["vendor_id"].as_u64().is_some(), "{n}");
        assert_eq!(n["drive"]["state"], "switch on disabled", "{n}");
        assert!(n["nmt"].is_string(), "{n}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sdo_reads_by_hex_or_name_and_writes_read_back() {
    let ui = Ui::sims();
    let (s, a) = get(&ui, "/api/nodes/1/sdo/6041/0").await;
    assert_eq!(s, 200, "{a}");
    assert_eq!(a["type"], "UNSIGNED16");
    assert_eq!(a["name"], "Statusword");
    assert_eq!(a["unit"], Value::Null, "a word has no unit");
    let (_, v) = get(&ui, "/api/nodes/1/sdo/606C/0").await;
    assert_eq!(v["unit"], "velocity units", "{v}");
    let (_, v) = get(&ui, "/api/nodes/2/sdo/1017/0").await;
    assert_eq!(v["unit"], "ms", "{v}");
    let (_, b) = get(&ui, "/api/nodes/1/sdo/statusword").await;
    let (_, c) = get(&ui, "/api/nodes/1/sdo/0x6041/00").await;
    assert_eq!(a["value"], b["value"]);
    assert_eq!(a["value"], c["value"]);
    let (s, v) = get(&ui, "/api/nodes/2/sdo/identity/1").await;
    assert_eq!((s, v["index"].as_str()), (200, Some("1018")), "{v}");
    let (s, w) = put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": 12345})).await;
    assert_eq!(s, 200, "{w}");
    assert_eq!(w["type"], "UNSIGNED32");
    assert_eq!(get(&ui, "/api/nodes/1/sdo/6081/0").await.1["value"], 12345);
    let (s, w) = put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": "0x100", "type": "u32"})).await;
    assert_eq!(s, 200, "{w}");
    assert_eq!(get(&ui, "/api/nodes/1/sdo/6081/0?type=u32").await.1["value"], 256);
    // Every write is logged, by default.
    wait_for(Duration::from_secs(10), || async { ui.log().contains("web: SDO write").then_some(()) }).await;
    assert!(ui.log().contains("6081"), "{}", ui.log());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_inputs_are_4xx_json_and_change_nothing() {
    let ui = Ui::sims();
    assert_eq!(put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": 777})).await.0, 200);
    refused(&get(&ui, "/api/nodes/9/sdo/6041/0").await, 404, "node 9 has not been seen");
    refused(&put(&ui, "/api/nodes/9/sdo/6081/0", json!({"value": 1})).await, 404, "not been seen");
    refused(&get(&ui, "/api/nodes/0/sdo/6041/0").await, 400, "not a node-ID");
    refused(&get(&ui, "/api/nodes/abc/pdo").await, 400, "not a node-ID");
    refused(&get(&ui, "/api/nodes/1/sdo/zz99/0").await, 400, "is not an object");
    refused(&get(&ui, "/api/nodes/1/sdo/6041/100").await, 400, "above FFh");
    refused(&get(&ui, "/api/nodes/1/sdo/5FFE/0").await, 404, "Object does not exist");
    refused(
        &put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": 5_000_000_000u64})).await,
        400,
        "UNSIGNED32",
    );
    refused(&put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": -1})).await, 400, "out of range");
    refused(&put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": 1.5})).await, 400, "not an integer");
    refused(&put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": "fast"})).await, 400, "not a valid");
    refused(
        &put(&ui, "/api/nodes/1/sdo/6081/0", json!({"value": 1, "type": "u17"})).await,
        400,
        "not a data type",
    );
    refused(&put(&ui, "/api/nodes/1/sdo/6081/0", json!({"val": 1})).await, 400, "malformed JSON");
    refused(
        &send(&ui, reqwest::Method::PUT, "/api/nodes/1/sdo/6081/0", "{\"value\": ").await,
        400,
        "malformed JSON",
    );
    refused(&put(&ui, "/api/nodes/1/sdo/5FFE/0", json!({"value": 1})).await, 400, "data type");
    refused(&put(&ui, "/api/nodes/1/sdo/6041/0", json!({"value": 1})).await, 422, "read only");
    refused(&post(&ui, "/api/nodes/1/nmt", json!({"command": "jump"})).await, 400, "not an NMT command");
    refused(&send(&ui, reqwest::Method::POST, "/api/nodes/1/nmt", "nmt start").await, 400, "malformed JSON");
    refused(&post(&ui, "/api/nodes/1/drive", json!({"action": "dance"})).await, 400, "not a drive action");
    refused(&post(&ui, "/api/nodes/1/drive", json!({"action": "move"})).await, 400, "needs \"target\"");
    refused(&post(&ui, "/api/nodes/1/drive", json!({"action": "move", "target": 5})).await, 409, "enable");
    refused(&get(&ui, "/api/nowhere").await, 404, "http-api.md");
    // Nothing changed: the value, the NMT state, the drive state.
    assert_eq!(get(&ui, "/api/nodes/1/sdo/6081/0").await.1["value"], 777);
    let (_, n) = get(&ui, "/api/nodes").await;
    assert_eq!(n["nodes"][0]["drive"]["state"], "switch on disabled", "{n}");
    assert_eq!(
        get(&ui, "/api/nodes/1/sdo/6060/0").await.1["value"],
        get(&ui, "/api/nodes/1/sdo/6061/0").await.1["value"]
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nmt_pdo_emcy_and_the_page() {
    let ui = Ui::sims();
    // Heartbeats every 50 ms, so the master sees the NMT state change.
    assert_eq!(put(&ui, "/api/nodes/2/sdo/1017/0", json!({"value": 50})).await.0, 200);
    let state = |want: &'static str| {
        let ui = &ui;
        move || async move {
            let (_, v) = get(ui, "/api/nodes").await;
            (v["nodes"][1]["nmt"] == want).then_some(v)
        }
    };
    assert_eq!(post(&ui, "/api/nodes/2/nmt", json!({"command": "start"})).await.0, 200);
    let v = wait_for(Duration::from_secs(30), state("operational")).await;
    assert!(v["nodes"][1]["heartbeat_age_ms"].as_u64().is_some(), "{v}");
    assert_eq!(post(&ui, "/api/nodes/2/nmt", json!({"command": "stop"})).await.0, 200);
    let v = wait_for(Duration::from_secs(30), state("stopped")).await;
    // A stopped node answers no SDO: listed without identity.
    assert_eq!(v["nodes"][1]["identity"], json!({}), "{v}");
    assert_eq!(post(&ui, "/api/nodes/2/nmt", json!({"command": "preop"})).await.0, 200);
    wait_for(Duration::from_secs(30), state("pre-operational")).await;
    let (s, p) = get(&ui, "/api/nodes/1/pdo").await;
    assert_eq!(s, 200, "{p}");
    let tpdo1 = &p["tpdo"][0];
    assert_eq!(tpdo1["cob_id"], "181", "{p}");
    assert!(tpdo1["mapping"].as_array().unwrap().iter().any(|m| m["index"] == "6041"), "{p}");
    let (s, e) = get(&ui, "/api/emcy").await;
    assert_eq!(s, 200);
    assert!(e["emcy"].is_array(), "{e}");
    let page = client().get(ui.url("/")).send().await.unwrap().text().await.unwrap();
    assert!(page.contains("<canvas id=\"scope\""), "{page}");
    let js = client().get(ui.url("/app.js")).send().await.unwrap();
    assert!(js.headers()["content-type"].to_str().unwrap().starts_with("text/javascript"));
    assert!(js.text().await.unwrap().contains("/api/stream"));
}

/// Enable and move node 1 through the API; the WebSocket stream shows
/// the position reach the target, and the motion's end as an event.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn enable_and_move_seen_in_the_stream() {
    let ui = Ui::sims();
    let ws_url = ui.url("/api/stream").replacen("http://", "ws://", 1);
    let (mut ws, _) = tokio_tungstenite::connect_async(ws_url).await.expect("WebSocket");
    let sub = json!({"subscribe": [{"node": 1, "index": "6064", "sub": 0, "period_ms": 20}]});
    ws.send(tokio_tungstenite::tungstenite::Message::Text(sub.to_string().into())).await.unwrap();
    let (s, v) = post(&ui, "/api/nodes/1/drive", json!({"action": "enable"})).await;
    assert_eq!((s, v["state"].as_str()), (200, Some("operation enabled")), "{v}");
    let (s, v) = post(
        &ui,
        "/api/nodes/1/drive",
        json!({"action": "move", "target": 4000, "velocity": 4000, "acceleration": 20000}),
    )
    .await;
    assert_eq!(s, 202, "{v}");
    let (mut subscribed, mut reached, mut ended, mut status) = (false, false, false, false);
    let t0 = Instant::now();
    while !(reached && ended && status) {
        assert!(
            t0.elapsed() < Duration::from_secs(90),
            "subscribed {subscribed} reached {reached} ended {ended}"
        );
        let m = tokio::time::timeout(Duration::from_secs(30), ws.next())
            .await
            .expect("stream silent")
            .unwrap()
            .unwrap();
        let Ok(text) = m.to_text() else { continue };
        let msg: Value = serde_json::from_str(text).unwrap();
        match msg["type"].as_str() {
            Some("subscribed") => subscribed = msg["channels"] == 1,
            Some("sample") if msg["node"] == 1 && msg["index"] == "6064" => {
                assert!(msg["t"].is_number() && msg["sub"] == 0, "{msg}");
                // The model settles within a few increments of the target.
                reached |= msg["value"].as_i64().is_some_and(|p| (p - 4000).abs() <= 20);
            }
            Some("event") if msg["event"] == "motion" => {
                assert_eq!(msg["result"]["end"], "target_reached", "{msg}");
                ended = true;
            }
            Some("status") => status = msg["dropped"].is_u64(),
            _ => {}
        }
    }
    assert!(subscribed);
    let (_, d) = get(&ui, "/api/nodes/1/drive").await;
    assert_eq!(d["state"], "operation enabled", "{d}");
    assert!(d["position"].as_i64().is_some_and(|p| (p - 4000).abs() <= 20), "{d}");
    let (s, d) = post(&ui, "/api/nodes/1/drive", json!({"action": "disable"})).await;
    assert_eq!((s, d["state"].as_str()), (200, Some("ready to switch on")), "{d}");
}

/// Beyond loopback every request needs the token printed at start.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_non_loopback_address_needs_the_token() {
    let ui = Ui::start(&["ui", "--sim", "akd:1", "--http", "0.0.0.0:0"]);
    let token =
        ui.line.split("?token=").nth(1).expect("token in the line").split_whitespace().next().unwrap();
    let port = ui.base.rsplit(':').next().unwrap();
    let base = format!("http://127.0.0.1:{port}");
    let r = client().get(format!("{base}/api/nodes")).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 401);
    assert!(r.json::<Value>().await.unwrap()["error"].as_str().unwrap().contains("token"));
    let r = client().get(format!("{base}/api/nodes?token={token}")).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 200);
    let r = client().get(format!("{base}/api/nodes")).header("X-Drivebus-Token", token).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 200);
    let r = client().get(format!("{base}/?token=wrong")).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 401);
}

/// `serve --http`: the page for the drives it serves.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn serve_hosts_the_page_for_its_drives() {
    let port = common::free_port().to_string();
    let listen = format!("127.0.0.1:{port}");
    let ui = Ui::start(&["serve", "--listen", &listen, "--drive", "akd:1", "--http", "127.0.0.1:0"]);
    assert!(
        ui.line.contains("listening on") && ui.line.contains("; page on http://127.0.0.1:"),
        "{}",
        ui.line
    );
    let (s, v) = get(&ui, "/api/nodes").await;
    assert_eq!(s, 200);
    assert_eq!(v["nodes"][0]["node"], 1, "{v}");
    let (s, v) = get(&ui, "/api/nodes/1/sdo/6041/0").await;
    assert_eq!((s, v["type"].as_str()), (200, Some("UNSIGNED16")), "{v}");
}

/// The README's "In the browser" command prints the line the README shows
/// (run on a free port instead of 8402).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn readme_in_the_browser_prints_its_line() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let from = readme.find("## In the browser").expect("README section");
    let block = &readme[from..];
    let block = &block[block.find("```sh\n").unwrap() + 6..];
    let mut lines = block.lines();
    let cmd = lines.next().unwrap();
    let printed = lines.next().unwrap().strip_prefix("# prints: ").unwrap();
    let port = common::free_port().to_string();
    let mut args: Vec<&str> = cmd.split_whitespace().skip(1).collect();
    let http = format!("127.0.0.1:{port}");
    args.extend(["--http", &http]);
    let ui = Ui::start(&args);
    assert_eq!(ui.line.replace(&port, "8402"), printed);
}

/// A following error trips node 1: the EMCY is in the history and on the
/// stream with its text, and a fault reset through the API clears it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn following_error_emcy_is_decoded_and_fault_reset() {
    let ui = Ui::sims();
    let ws_url = ui.url("/api/stream").replacen("http://", "ws://", 1);
    let (mut ws, _) = tokio_tungstenite::connect_async(ws_url).await.expect("WebSocket");
    assert_eq!(get(&ui, "/api/emcy").await.1["emcy"], json!([]));
    assert_eq!(put(&ui, "/api/nodes/1/sdo/6065/0", json!({"value": 1})).await.0, 200);
    assert_eq!(post(&ui, "/api/nodes/1/drive", json!({"action": "enable"})).await.0, 200);
    let fast = json!({"action": "move", "target": 40000, "velocity": 40000, "acceleration": 200000});
    assert_eq!(post(&ui, "/api/nodes/1/drive", fast).await.0, 202);
    let e = wait_for(Duration::from_secs(60), || async {
        let (_, v) = get(&ui, "/api/emcy").await;
        v["emcy"].as_array().and_then(|l| l.iter().find(|e| e["code"] == "8611").cloned())
    })
    .await;
    // The AKD manual's text and fault number (its EMCY table), not CiA 402's.
    assert_eq!(
        (e["node"].as_u64(), e["text"].as_str(), e["detail"].as_str()),
        (Some(1), Some("Following error (user)"), Some("F439 (fault)")),
        "{e}"
    );
    let t0 = Instant::now();
    loop {
        assert!(t0.elapsed() < Duration::from_secs(60), "no emcy event on the stream");
        let m = tokio::time::timeout(Duration::from_secs(30), ws.next())
            .await
            .expect("stream silent")
            .unwrap()
            .unwrap();
        let msg: Value = serde_json::from_str(m.to_text().unwrap_or("{}")).unwrap_or_default();
        if msg["event"] == "emcy" && msg["code"] == "8611" {
            assert_eq!(
                (msg["text"].as_str(), msg["detail"].as_str()),
                (Some("Following error (user)"), Some("F439 (fault)")),
                "{msg}"
            );
            break;
        }
    }
    assert_eq!(get(&ui, "/api/nodes/1/drive").await.1["state"], "fault");
    let (s, d) = post(&ui, "/api/nodes/1/drive", json!({"action": "fault-reset"})).await;
    assert_eq!((s, d["state"].as_str()), (200, Some("switch on disabled")), "{d}");
}

/// The object dictionary of a hosted drive from its EDS, searchable; a
/// write outside the EDS limits is a 400 and nothing is sent.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn objects_from_the_eds_and_their_limits() {
    let ui = Ui::sims();
    let (s, v) = get(&ui, "/api/nodes/1/objects?q=latch%20control").await;
    assert_eq!(s, 200, "{v}");
    let list = v["objects"].as_array().expect("objects");
    let e = list.iter().find(|o| o["index"] == "20A4").unwrap_or_else(|| panic!("no 20A4h in {v}"));
    assert_eq!(
        (e["type"].as_str(), e["access"].as_str(), e["low"].as_u64(), e["high"].as_u64()),
        (Some("UNSIGNED16"), Some("rw"), Some(0), Some(15)),
        "{e}"
    );
    let named = |o: &Value, k: &str| o[k].as_str().unwrap().to_lowercase().contains("latch control");
    assert!(list.iter().all(|o| named(o, "name") || named(o, "object")), "{v}");
    // By index prefix: every sub of 1018h.
    let (_, v) = get(&ui, "/api/nodes/1/objects?q=1018").await;
    assert_eq!(v["objects"].as_array().unwrap().len(), 5, "{v}");
    assert!(get(&ui, "/api/nodes/1/objects").await.1["objects"].as_array().unwrap().len() > 100);
    assert_eq!(put(&ui, "/api/nodes/1/sdo/20A4/0", json!({"value": 5})).await.0, 200);
    refused(&put(&ui, "/api/nodes/1/sdo/20A4/0", json!({"value": 16})).await, 400, "the EDS allows 0 to 15");
    assert_eq!(get(&ui, "/api/nodes/1/sdo/20A4/0").await.1["value"], 5);
    refused(&get(&ui, "/api/nodes/9/objects").await, 404, "not been seen");
}

/// A device that is not a hosted drive: its dictionary comes from
/// `--eds`; without one the answer says how to give it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn objects_of_a_device_come_from_eds() {
    let eds = concat!(env!("CARGO_MANIFEST_DIR"), "/../personality/eds/generic.eds");
    let sim = format!("{eds}:3");
    let ui = Ui::start(&["ui", "--sim", &sim, "--http", "127.0.0.1:0"]);
    refused(&get(&ui, "/api/nodes/3/objects").await, 404, "--eds FILE");
    drop(ui);
    let ui = Ui::start(&["ui", "--sim", &sim, "--eds", eds, "--http", "127.0.0.1:0"]);
    let (s, v) = get(&ui, "/api/nodes/3/objects?q=60E3").await;
    assert_eq!(s, 200, "{v}");
    assert!(v["objects"].as_array().unwrap().iter().all(|o| o["index"] == "60E3"), "{v}");
    assert!(v["objects"].as_array().unwrap().len() > 1, "{v}");
}

type Ws = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn ws_connect(ui: &Ui, first: Value) -> Ws {
    let ws_url = ui.url("/api/stream").replacen("http://", "ws://", 1);
    let (mut ws, _) = tokio_tungstenite::connect_async(ws_url).await.expect("WebSocket");
    ws.send(tokio_tungstenite::tungstenite::Message::Text(first.to_string().into())).await.unwrap();
    ws
}

/// The next JSON message of the stream.
async fn next_msg(ws: &mut Ws) -> Value {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(30), ws.next())
            .await
            .expect("stream silent")
            .expect("stream closed")
            .expect("stream error");
        if let Ok(text) = m.to_text() {
            return serde_json::from_str(text).expect("JSON message");
        }
    }
}

/// `serve --drive akd:1 --http` with TPDO1 (6041h) and TPDO3 (6041h,
/// 6064h) of node 1 sent at every SYNC
/// and heartbeats every 50 ms, operational; and a second process that
/// produces SYNC every `sync_ms` on its socketcand bus (killed on drop).
struct SyncedDrive {
    ui: Ui,
    sync: Child,
}

impl Drop for SyncedDrive {
    fn drop(&mut self) {
        let _ = self.sync.kill();
        let _ = self.sync.wait();
    }
}

async fn synced_drive(sync_ms: &str) -> SyncedDrive {
    let listen = format!("127.0.0.1:{}", common::free_port());
    let ui = Ui::start(&["serve", "--listen", &listen, "--drive", "akd:1", "--http", "127.0.0.1:0"]);
    assert_eq!(put(&ui, "/api/nodes/1/sdo/1800/2", json!({"value": 1})).await.0, 200);
    assert_eq!(put(&ui, "/api/nodes/1/sdo/1802/2", json!({"value": 1})).await.0, 200);
    assert_eq!(put(&ui, "/api/nodes/1/sdo/1017/0", json!({"value": 50})).await.0, 200);
    assert_eq!(post(&ui, "/api/nodes/1/nmt", json!({"command": "start"})).await.0, 200);
    let sync = Command::new(common::bin())
        .args(["--bus", &format!("socketcand://{listen}/can0"), "produce", "--sync", sync_ms])
        .env_remove("RUST_LOG")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn drivebus produce");
    SyncedDrive { ui, sync }
}

/// Raw frames with a filter: only SYNC and TPDO1 identifiers arrive
/// (heartbeats and SDO answers are on the bus too), each with its time
/// and data, and the drive's TPDO1 follows a SYNC.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn raw_frames_pass_the_filter_and_a_tpdo_follows_sync() {
    let d = synced_drive("20").await;
    let mut ws = ws_connect(&d.ui, json!({"frames": {"ids": ["0x180-0x1FF", "080"]}})).await;
    let (mut subscribed, mut after_sync, mut status) = (false, false, false);
    let mut last_sync = false;
    let mut seen = Vec::new();
    let t0 = Instant::now();
    while !(subscribed && after_sync && status && seen.len() > 20) {
        assert!(t0.elapsed() < Duration::from_secs(60), "frames {seen:?}");
        // SDO answers (581h) on the bus meanwhile must not pass.
        if seen.len() == 5 {
            assert_eq!(get(&d.ui, "/api/nodes/1/sdo/6041/0").await.0, 200);
        }
        let msg = next_msg(&mut ws).await;
        match msg["type"].as_str() {
            Some("subscribed") => subscribed = msg["frames"] == true,
            Some("frame") => {
                let id = u32::from_str_radix(msg["id"].as_str().unwrap(), 16).unwrap();
                assert!(id == 0x080 || (0x180..=0x1FF).contains(&id), "{msg}");
                assert!(msg["t"].is_number() && msg["data"].is_string(), "{msg}");
                after_sync |= last_sync && id == 0x181;
                last_sync = id == 0x080;
                seen.push(id);
            }
            Some("status") => status = msg["frames"] == true && msg["dropped"].is_u64(),
            _ => {}
        }
    }
    // Both kinds came: SYNCs and TPDOs; and the filter can be changed.
    assert!(seen.contains(&0x080) && seen.contains(&0x181), "{seen:?}");
    ws.send(tokio_tungstenite::tungstenite::Message::Text(
        json!({"frames": {"functions": ["heartbeat"]}}).to_string().into(),
    ))
    .await
    .unwrap();
    let t0 = Instant::now();
    loop {
        assert!(t0.elapsed() < Duration::from_secs(30), "no heartbeat frame");
        let msg = next_msg(&mut ws).await;
        if msg["type"] == "frame" && msg["id"] == "701" {
            assert_eq!(msg["data"], "05", "{msg}");
            break;
        }
    }
    // A bad filter is an error message and changes nothing.
    ws.send(tokio_tungstenite::tungstenite::Message::Text(
        json!({"frames": {"ids": ["0x200-0x100"]}}).to_string().into(),
    ))
    .await
    .unwrap();
    loop {
        let msg = next_msg(&mut ws).await;
        if msg["type"] == "error" {
            assert!(msg["error"].as_str().unwrap().contains("200 is above 100"), "{msg}");
            break;
        }
        assert!(msg["type"] != "frame" || msg["id"] == "701", "{msg}");
    }
}

/// 6064h, mapped in TPDO3 of the AKD (transmission type 1), arrives at
/// every SYNC with `source: "pdo"`, not at the 1 s polling period; 607Ah,
/// in no TPDO, is polled by SDO.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pdo_mapped_objects_arrive_at_every_sync() {
    let d = synced_drive("20").await;
    let sub = json!({"subscribe": [{"node": 1, "index": "6064", "period_ms": 1000}, {"node": 1, "index": "607A", "period_ms": 200}]});
    let mut ws = ws_connect(&d.ui, sub).await;
    let (mut pdo, mut sdo) = (Vec::new(), 0);
    let t0 = Instant::now();
    while pdo.len() < 50 || sdo < 2 {
        assert!(t0.elapsed() < Duration::from_secs(60), "pdo samples {} sdo samples {sdo}", pdo.len());
        let msg = next_msg(&mut ws).await;
        if msg["type"] != "sample" {
            continue;
        }
        match (msg["index"].as_str(), msg["source"].as_str()) {
            (Some("6064"), Some("pdo")) => pdo.push(msg["t"].as_f64().unwrap()),
            (Some("607A"), Some("sdo")) => sdo += 1,
            // Until the master saw the node operational (its heartbeat).
            (Some("6064"), Some("sdo")) if pdo.is_empty() => {}
            _ => panic!("{msg}"),
        }
    }
    // About one sample per 20 ms SYNC (the 1 s poll would give one per second).
    let span = pdo.last().unwrap() - pdo[10];
    let per = span / (pdo.len() - 11) as f64;
    assert!((10.0..=40.0).contains(&per), "one 6064h sample every {per:.1} ms");
}

/// The drive's position 6064h and velocity 606Ch as `GET .../drive` gives them.
async fn drive_pv(ui: &Ui, node: u8) -> (i64, i64) {
    let (s, d) = get(ui, &format!("/api/nodes/{node}/drive")).await;
    assert_eq!(s, 200, "{d}");
    (d["position"].as_i64().expect("position"), d["velocity"].as_i64().expect("velocity"))
}

/// The next stream event named `name`.
async fn next_event(ws: &mut Ws, name: &str) -> Value {
    loop {
        let msg = next_msg(ws).await;
        if msg["type"] == "event" && msg["event"] == name {
            return msg;
        }
    }
}

/// Jog: the drive runs while the page repeats the request; when the
/// repeats stop (the page vanished), the server's watchdog stops the
/// drive within its 500 ms and says so in a `jog` event. Released by
/// the page (velocity 0), it stops at once. Not enabled or malformed:
/// refused, nothing moves.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn jog_runs_while_refreshed_and_the_watchdog_stops_it() {
    let ui = Ui::sims();
    let mut ws = ws_connect(&ui, json!({"subscribe": []})).await;
    let jog = |v: i64| json!({"velocity": v, "acceleration": 200000});
    refused(&post(&ui, "/api/nodes/1/drive/jog", jog(20000)).await, 409, "not operation enabled");
    refused(&post(&ui, "/api/nodes/1/drive/jog", json!({"speed": 1})).await, 400, "velocity");
    refused(&post(&ui, "/api/nodes/9/drive/jog", jog(20000)).await, 404, "9");
    assert_eq!(post(&ui, "/api/nodes/1/drive", json!({"action": "enable"})).await.0, 200);
    let (p0, _) = drive_pv(&ui, 1).await;
    // Held for 1 s: refreshed every 100 ms.
    for _ in 0..10 {
        let (s, v) = post(&ui, "/api/nodes/1/drive/jog", jog(20000)).await;
        assert_eq!((s, v["jogging"].as_bool()), (200, Some(true)), "{v}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let (p1, v1) = drive_pv(&ui, 1).await;
    assert!(p1 > p0 + 5000 && v1 > 10000, "jogging at 20000/s for 1 s: {p0} -> {p1}, velocity {v1}");
    // The page vanishes: no more refreshes. The watchdog stops the jog.
    let last = Instant::now();
    let ev =
        tokio::time::timeout(Duration::from_secs(5), next_event(&mut ws, "jog")).await.expect("no jog event");
    let after = last.elapsed();
    assert_eq!(ev["node"], 1, "{ev}");
    assert_eq!(ev["result"]["end"], "watchdog", "{ev}");
    assert!(
        after >= Duration::from_millis(400) && after < Duration::from_millis(1500),
        "stopped after {after:?}"
    );
    // Decelerating at 200000/s²: at rest within 0.1 s; give it 0.5 s.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (p2, v2) = drive_pv(&ui, 1).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (p3, _) = drive_pv(&ui, 1).await;
    assert_eq!((v2, p3), (0, p2), "still moving after the watchdog");
    // Released by the page: stopped at once, a `released` event.
    assert_eq!(post(&ui, "/api/nodes/1/drive/jog", jog(-20000)).await.0, 200);
    tokio::time::sleep(Duration::from_millis(200)).await;
    let (s, v) = post(&ui, "/api/nodes/1/drive/jog", jog(0)).await;
    assert_eq!((s, v["jogging"].as_bool()), (200, Some(false)), "{v}");
    let ev = next_event(&mut ws, "jog").await;
    assert_eq!(ev["result"]["end"], "released", "{ev}");
    let (p4, _) = drive_pv(&ui, 1).await;
    assert!(p4 < p3, "jogged backwards: {p3} -> {p4}");
}

/// The CSP sine generator: streamed one target per SYNC, the position
/// swings from where it was to 2·amplitude above and back (the scope's
/// samples show both), the end is a `sine` event with the cycles; a
/// stop ends a long one early (`stopped`, fewer cycles); bad requests
/// are refused.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn csp_sine_streams_and_reports_its_end() {
    let ui = Ui::sims();
    let path = "/api/nodes/1/drive/sine";
    let sine = json!({"amplitude": 5000, "period_ms": 600, "duration_ms": 1200});
    refused(&post(&ui, path, sine.clone()).await, 409, "not operation enabled");
    refused(&post(&ui, path, json!({"amplitude": 5000})).await, 400, "period_ms");
    refused(
        &post(&ui, path, json!({"amplitude": 5000, "period_ms": 5, "duration_ms": 100})).await,
        400,
        "period_ms",
    );
    refused(&post(&ui, path, json!({"stop": true})).await, 409, "no sine");
    assert_eq!(put(&ui, "/api/nodes/1/sdo/1017/0", json!({"value": 50})).await.0, 200);
    assert_eq!(post(&ui, "/api/nodes/1/nmt", json!({"command": "start"})).await.0, 200);
    assert_eq!(post(&ui, "/api/nodes/1/drive", json!({"action": "enable"})).await.0, 200);
    let (p0, _) = drive_pv(&ui, 1).await;
    let mut ws = ws_connect(&ui, json!({"subscribe": [{"node": 1, "index": "6064", "period_ms": 5}]})).await;
    let (s, v) = post(&ui, path, sine).await;
    assert_eq!((s, v["cycles"].as_u64()), (202, Some(600)), "{v}");
    refused(
        &post(&ui, path, json!({"amplitude": 1, "period_ms": 600, "duration_ms": 100})).await,
        409,
        "already",
    );
    let (mut lo, mut hi, mut back) = (i64::MAX, i64::MIN, false);
    let end = loop {
        let msg = next_msg(&mut ws).await;
        match msg["type"].as_str() {
            Some("sample") => {
                let p = msg["value"].as_i64().unwrap();
                (lo, hi) = (lo.min(p), hi.max(p));
                // Back near the start after the top.
                back |= hi > p0 + 9000 && p < p0 + 1000;
            }
            Some("event") if msg["event"] == "sine" => break msg,
            _ => {}
        }
    };
    assert_eq!(end["node"], 1, "{end}");
    assert_eq!(
        (end["result"]["end"].as_str(), end["result"]["cycles"].as_u64()),
        (Some("completed"), Some(600)),
        "{end}"
    );
    assert!(lo >= p0 - 500 && (hi - (p0 + 10000)).abs() < 1000 && back, "from {p0}: {lo}..{hi}, back {back}");
    // A long one, stopped early.
    let (s, v) = post(&ui, path, json!({"amplitude": 2000, "period_ms": 1000, "duration_ms": 60000})).await;
    assert_eq!(s, 202, "{v}");
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert_eq!(post(&ui, path, json!({"stop": true})).await.0, 200);
    let end =
        tokio::time::timeout(Duration::from_secs(5), next_event(&mut ws, "sine")).await.expect("no end");
    assert_eq!(end["result"]["end"], "stopped", "{end}");
    let n = end["result"]["cycles"].as_u64().unwrap();
    assert!(n > 0 && n < 30000, "{end}");
    let (_, d) = get(&ui, "/api/nodes/1/drive").await;
    assert_eq!(d["state"], "operation enabled", "{d}");
}

/// A `ping` comes back as a `pong` through the client's queue with the
/// server's time, and changes no subscription (no `subscribed`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_stream_answers_a_ping_with_a_pong() {
    let ui = Ui::sims();
    let mut ws = ws_connect(&ui, json!({"ping": 12.5})).await;
    // The first `status` may come before.
    let msg = loop {
        let msg = next_msg(&mut ws).await;
        assert_ne!(msg["type"], "subscribed", "{msg}");
        if msg["type"] != "status" {
            break msg;
        }
    };
    assert_eq!((msg["type"].as_str(), msg["ping"].as_f64()), (Some("pong"), Some(12.5)), "{msg}");
    assert!(msg["t"].as_f64().is_some_and(|t| t > 0.0), "{msg}");
    ws.send(tokio_tungstenite::tungstenite::Message::Text(json!({"ping": "x"}).to_string().into()))
        .await
        .unwrap();
    loop {
        let msg = next_msg(&mut ws).await;
        assert_ne!(msg["type"], "subscribed", "{msg}");
        if msg["type"] == "pong" {
            assert_eq!(msg["ping"], "x", "{msg}");
            break;
        }
    }
}

/// `PUT /api/nodes/{n}/pdo/{rx|tx}/{k}`: a TPDO mapped through the API
/// reads back; refusals (the device's aborts and bad requests) are 4xx
/// with the reason and leave the PDO as it was.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pdo_write_reads_back_and_refusals_change_nothing() {
    let ui = Ui::sims();
    let body = json!({"transmission_type": 1, "event_timer": 0,
        "mapping": [{"index": "6064", "sub": 0, "bits": 32}, {"index": "statusword"}]});
    let (s, v) = put(&ui, "/api/nodes/1/pdo/tx/2", body).await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(v["pdo"]["transmission_type"], 1, "{v}");
    let (_, p) = get(&ui, "/api/nodes/1/pdo").await;
    let tpdo2 = p["tpdo"][1].clone();
    assert_eq!(tpdo2["num"], 2, "{p}");
    assert_eq!(tpdo2["valid"], true, "{p}");
    let mapped: Vec<(String, u64)> = tpdo2["mapping"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["index"].as_str().unwrap().to_owned(), m["bits"].as_u64().unwrap()))
        .collect();
    assert_eq!(mapped, vec![("6064".to_owned(), 32), ("6041".to_owned(), 16)], "{p}");
    // Refused by the device: not mappable (1018h:1), too long (3 × 32 bits).
    let not_mappable = json!({"mapping": [{"index": "1018", "sub": 1, "bits": 32}]});
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", not_mappable).await, 422, "cannot be mapped");
    let long = json!({"mapping": [{"index": "6064", "sub": 0, "bits": 32}, {"index": "606C", "sub": 0, "bits": 32},
        {"index": "6041", "sub": 0, "bits": 16}]});
    let r = put(&ui, "/api/nodes/1/pdo/tx/2", long).await;
    refused(&r, 422, "exceed PDO length");
    refused(&r, 422, "in force again");
    // Refused before anything is sent.
    let ok = json!({"mapping": [{"index": "6041", "sub": 0, "bits": 16}]});
    refused(&put(&ui, "/api/nodes/9/pdo/tx/2", ok.clone()).await, 404, "not been seen");
    refused(&put(&ui, "/api/nodes/0/pdo/tx/2", ok.clone()).await, 400, "1..127");
    refused(&put(&ui, "/api/nodes/1/pdo/up/2", ok.clone()).await, 400, "direction");
    refused(&put(&ui, "/api/nodes/1/pdo/tx/0", ok.clone()).await, 400, "PDO number");
    refused(&put(&ui, "/api/nodes/1/pdo/tx/513", ok.clone()).await, 400, "PDO number");
    refused(&put(&ui, "/api/nodes/1/pdo/tx/300", ok.clone()).await, 404, "192Bh");
    refused(
        &send(&ui, reqwest::Method::PUT, "/api/nodes/1/pdo/tx/2", "{\"mapping\": [").await,
        400,
        "malformed JSON",
    );
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", json!({"maping": []})).await, 400, "malformed JSON");
    let bits = json!({"mapping": [{"index": "6041", "sub": 0, "bits": 65}]});
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", bits).await, 400, "1..64 bits");
    let name = json!({"mapping": [{"index": "no such object"}]});
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", name).await, 400, "mapping index");
    let cob = json!({"cob_id": "0x900", "mapping": []});
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", cob).await, 400, "11-bit");
    let tt = json!({"transmission_type": 300, "mapping": []});
    refused(&put(&ui, "/api/nodes/1/pdo/tx/2", tt).await, 400, "malformed JSON");
    let (_, after) = get(&ui, "/api/nodes/1/pdo").await;
    assert_eq!(after["tpdo"][1], tpdo2, "a refused write changed TPDO2");
    assert_eq!(after["tpdo"][0], p["tpdo"][0], "a refused write changed TPDO1");
}

/// LSS for a configured node (the generic drive has LSS): inquire by
/// node (its 1018h) or address, configure a node-ID that takes effect at
/// NMT reset communication; a refused bit timing and bad requests change
/// nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lss_inquire_and_configure_a_node_and_refusals() {
    let ui = Ui::start(&["ui", "--sim", "generic:5", "--http", "127.0.0.1:0"]);
    let (s, v) = post(&ui, "/api/lss/inquire", json!({"node": 5})).await;
    assert_eq!(s, 200, "{v}");
    assert_eq!((v["node_id"].as_u64(), v["configured"].as_bool()), (Some(5), Some(true)), "{v}");
    let serial = get(&ui, "/api/nodes/5/sdo/1018/4").await.1["value"].clone();
    assert_eq!(v["address"]["serial"], serial, "{v}");
    let address = v["address"].clone();
    let (s, by_address) = post(&ui, "/api/lss/inquire", json!({"address": address})).await;
    assert_eq!((s, &by_address["node_id"]), (200, &json!(5)), "{by_address}");
    // No unconfigured slave on this bus.
    let (s, v) = post(&ui, "/api/lss/scan", json!({})).await;
    assert_eq!((s, &v["found"]), (200, &json!(false)), "{v}");
    // Refused: bad requests, nobody at an address, a bit timing the slave lacks.
    refused(&post(&ui, "/api/lss/configure", json!({"node": 9, "node_id": 7})).await, 404, "not been seen");
    refused(&post(&ui, "/api/lss/configure", json!({"node": 5, "node_id": 0})).await, 400, "1..127");
    refused(&post(&ui, "/api/lss/configure", json!({"node": 5, "node_id": 128})).await, 400, "1..127");
    refused(
        &post(&ui, "/api/lss/configure", json!({"node": 5, "node_id": 300})).await,
        400,
        "malformed JSON",
    );
    refused(&post(&ui, "/api/lss/configure", json!({"node": 5, "nodeid": 7})).await, 400, "malformed JSON");
    refused(
        &send(&ui, reqwest::Method::POST, "/api/lss/configure", "{\"node\": ").await,
        400,
        "malformed JSON",
    );
    let both = json!({"node": 5, "address": address, "node_id": 7});
    refused(&post(&ui, "/api/lss/configure", both).await, 400, "not both");
    refused(&post(&ui, "/api/lss/inquire", json!({})).await, 400, "give the slave");
    let nobody =
        json!({"address": {"vendor_id": 1, "product_code": 2, "revision": 3, "serial": 4}, "node_id": 7});
    refused(&post(&ui, "/api/lss/configure", nobody).await, 504, "no LSS answer");
    let rate = json!({"node": 5, "node_id": 7, "bit_timing": 5});
    refused(&post(&ui, "/api/lss/configure", rate).await, 422, "not supported");
    // Node-ID 6, active at reset communication.
    let (s, v) = post(&ui, "/api/lss/configure", json!({"node": 5, "node_id": 6, "bit_timing": 4})).await;
    assert_eq!(s, 200, "{v}");
    // The node boots as 6: the wait for node 5's boot-up ends in 504.
    let _ = post(&ui, "/api/nodes/5/nmt", json!({"command": "reset-comm"})).await;
    let v = wait_for(Duration::from_secs(30), || async {
        let (s, v) = get(&ui, "/api/nodes/6/sdo/1018/4").await;
        (s == 200).then_some(v)
    })
    .await;
    assert_eq!(v["value"], serial, "{v}");
    // Not 7: the refused configuration did not stay pending.
    assert_eq!(get(&ui, "/api/nodes/7/sdo/1018/4").await.0, 404);
}

/// Two unconfigured LSS slaves: scan finds the lowest address and says
/// there are more; "the only one" is refused (nothing changes); by
/// address one gets node-ID 9, starts under it, and the scan finds the other.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lss_scan_and_configure_unconfigured_slaves() {
    let (server, addr) =
        drivebus_transport::socketcand::SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
    let unconfigured = |serial| {
        let mut cfg = drivebus_node::NodeConfig::new(0xFF);
        cfg.lss = true;
        cfg.identity = drivebus_node::Identity { vendor_id: 0xABC, product_code: 0x77, revision: 3, serial };
        drivebus_node::NodeDevice::new(drivebus_node::Node::new(cfg), drivebus_od::NoHooks)
    };
    let _hosts =
        drivebus_transport::host::spawn_on_hub([unconfigured(0x20), unconfigured(0x10)], server.hub());
    let bus = format!("socketcand://{addr}/can0");
    let ui = Ui::start(&["ui", "--bus", &bus, "--http", "127.0.0.1:0"]);
    let (s, v) = post(&ui, "/api/lss/scan", json!({})).await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(
        (&v["found"], &v["first"]["serial"], &v["more"]),
        (&json!(true), &json!(0x10), &json!(true)),
        "{v}"
    );
    refused(&post(&ui, "/api/lss/configure", json!({"node_id": 9})).await, 409, "nothing was changed");
    let (_, again) = post(&ui, "/api/lss/scan", json!({})).await;
    assert_eq!(again, v, "the refused configuration changed the slaves");
    let (s, v) = post(&ui, "/api/lss/configure", json!({"node_id": 9, "address": v["first"]})).await;
    assert_eq!(s, 200, "{v}");
    let v = wait_for(Duration::from_secs(30), || async {
        let (s, v) = get(&ui, "/api/nodes/9/sdo/1018/4?type=u32").await;
        (s == 200).then_some(v)
    })
    .await;
    assert_eq!(v["value"], 0x10, "{v}");
    let (_, v) = post(&ui, "/api/lss/scan", json!({})).await;
    assert_eq!((&v["first"]["serial"], &v["more"]), (&json!(0x20), &json!(false)), "{v}");
    drop(server);
}

/// Machine inputs and faults of `serve`'s drives, through the control
/// interface: a digital input and a tripped limit switch are seen in
/// 60FDh read by SDO through the API; an encoder fault's EMCY is in the
/// history and clears; bad requests change nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn machine_inputs_and_faults_of_hosted_drives() {
    let listen = format!("127.0.0.1:{}", common::free_port());
    let ui = Ui::start(&["serve", "--listen", &listen, "--drive", "generic:5", "--http", "127.0.0.1:0"]);
    let inputs = || async { get(&ui, "/api/nodes/5/sdo/60FD/0").await.1["value"].as_u64().expect("60FDh") };
    let before = inputs().await;
    assert_eq!(before & (1 << 18 | 1 << 1), 0, "{before:#x}");
    // Refused, nothing changed.
    let line3 = json!({"input": "digital", "line": 3, "value": 1});
    refused(
        &post(&ui, "/api/nodes/9/machine/input", line3.clone()).await,
        404,
        "not a drive this process hosts",
    );
    refused(&post(&ui, "/api/nodes/0/machine/input", line3.clone()).await, 400, "1..127");
    refused(
        &post(&ui, "/api/nodes/5/machine/input", json!({"input": "digitl", "line": 3, "value": 1})).await,
        400,
        "unknown variant",
    );
    refused(
        &post(&ui, "/api/nodes/5/machine/input", json!({"input": "digital", "line": 17, "value": 1})).await,
        400,
        "1..=16",
    );
    refused(
        &post(
            &ui,
            "/api/nodes/5/machine/input",
            json!({"input": "digital", "line": 3, "value": 1, "duration": -1}),
        )
        .await,
        400,
        "duration",
    );
    refused(
        &send(&ui, reqwest::Method::POST, "/api/nodes/5/machine/input", "{\"input\"").await,
        400,
        "malformed JSON",
    );
    refused(
        &post(&ui, "/api/nodes/5/machine/fault", json!({"kind": "encodr"})).await,
        400,
        "unknown variant",
    );
    refused(&post(&ui, "/api/nodes/5/machine/fault", json!({"kind": "trip"})).await, 400, "fault");
    assert_eq!(inputs().await, before);
    // Nothing in force yet; the state of a node not hosted is refused.
    let state = || async { get(&ui, "/api/nodes/5/machine").await };
    let (s, v) = state().await;
    assert_eq!((s, &v["faults"], &v["inputs"]), (200, &json!([]), &json!([])), "{v}");
    refused(&get(&ui, "/api/nodes/9/machine").await, 404, "not a drive this process hosts");
    // An input: generic shows line 3 in 60FDh bit 18.
    let (s, v) = post(&ui, "/api/nodes/5/machine/input", line3).await;
    assert_eq!(s, 200, "{v}");
    wait_for(Duration::from_secs(10), || async { (inputs().await & 1 << 18 != 0).then_some(()) }).await;
    let v = state().await.1;
    let held = &v["inputs"][0];
    assert_eq!(
        (&held["input"], &held["line"], &held["value"]),
        (&json!("digital"), &json!(3), &json!(1.0)),
        "{v}"
    );
    assert_eq!(held["remaining_s"], Value::Null, "{v}");
    // A limit switch trips: 60FDh bit 1 (positive limit switch).
    let trip = json!({"kind": "trip", "switch": "positive_limit", "duration": 600});
    assert_eq!(post(&ui, "/api/nodes/5/machine/fault", trip).await.0, 200);
    wait_for(Duration::from_secs(10), || async { (inputs().await & 1 << 1 != 0).then_some(()) }).await;
    let v = state().await.1;
    let fault = &v["faults"][0];
    assert_eq!((&fault["kind"], &fault["switch"]), (&json!("trip"), &json!("positive_limit")), "{v}");
    let left = fault["remaining_s"].as_f64().expect("remaining_s");
    assert!(left > 500.0 && left <= 600.0, "{v}");
    assert_eq!(post(&ui, "/api/nodes/5/machine/fault", json!({"kind": "clear"})).await.0, 200);
    wait_for(Duration::from_secs(10), || async { (inputs().await & 1 << 1 == 0).then_some(()) }).await;
    // Clear ends the faults; the input stays.
    let v = state().await.1;
    assert_eq!((v["faults"].as_array().unwrap().len(), v["inputs"].as_array().unwrap().len()), (0, 1), "{v}");
    // A drive fault: the encoder's EMCY 7305h reaches the history.
    assert_eq!(post(&ui, "/api/nodes/5/machine/fault", json!({"kind": "encoder"})).await.0, 200);
    wait_for(Duration::from_secs(10), || async {
        let (_, e) = get(&ui, "/api/emcy").await;
        e["emcy"].as_array().unwrap().iter().any(|e| e["node"] == 5 && e["code"] == "7305").then_some(())
    })
    .await;
}

/// `ui` hosts no machine: inputs are refused with the reason.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn machine_inputs_need_a_hosting_serve() {
    let ui = Ui::start(&["ui", "--sim", "generic:5", "--http", "127.0.0.1:0"]);
    let r = post(&ui, "/api/nodes/5/machine/input", json!({"input": "digital", "line": 3, "value": 1})).await;
    refused(&r, 404, "drivebus serve --drive");
}

/// `ui --bus URL` on a bus whose drive it does not host (a `serve`
/// process stands in for a real DDS6): the drive's 1018h picks its
/// personality, so its EMCY comes with the manual's text and class.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_real_drive_identified_by_1018h_gets_the_manuals_emcy_texts() {
    let listen = format!("127.0.0.1:{}", common::free_port());
    let real = Ui::start(&["serve", "--listen", &listen, "--drive", "dds6:3", "--http", "127.0.0.1:0"]);
    // Heartbeats, so the ui's master hears node 3.
    assert_eq!(put(&real, "/api/nodes/3/sdo/1017/0", json!({"value": 100})).await.0, 200);
    let bus = format!("socketcand://{listen}/can0");
    let ui = Ui::start(&["ui", "--bus", &bus, "--http", "127.0.0.1:0"]);
    wait_for(Duration::from_secs(30), || async {
        let (_, v) = get(&ui, "/api/nodes").await;
        v["nodes"].as_array()?.iter().any(|n| n["node"] == 3 && n["personality"] == "dds6").then_some(())
    })
    .await;
    let (s, v) = post(&real, "/api/nodes/3/machine/fault", json!({"kind": "over_current"})).await;
    assert_eq!(s, 200, "{v}");
    let e = wait_for(Duration::from_secs(30), || async {
        let (_, e) = get(&ui, "/api/emcy").await;
        e["emcy"].as_array()?.iter().find(|e| e["node"] == 3 && e["code"] == "2310").cloned()
    })
    .await;
    assert_eq!(e["text"], "Over-current detected, motor output side", "{e}");
    assert_eq!(e["detail"], "class 6", "{e}");
}

/// The drive panel's switch inputs (60FDh) and limits (607Dh, 607Fh): a
/// tripped limit switch lights its bit; an object the drive lacks (the
/// AKD's 607Fh, the DDS6's 60FDh) is null, not an error.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn drive_status_reports_switch_inputs_and_limits() {
    let listen = format!("127.0.0.1:{}", common::free_port());
    let ui = Ui::start(&[
        "serve",
        "--listen",
        &listen,
        "--drive",
        "generic:5",
        "--drive",
        "akd:6",
        "--drive",
        "dds6:7",
        "--http",
        "127.0.0.1:0",
    ]);
    let drive = || async {
        let (s, d) = get(&ui, "/api/nodes/5/drive").await;
        assert_eq!(s, 200, "{d}");
        d
    };
    let d = drive().await;
    let sdo = |path: &'static str| {
        let ui = &ui;
        async move { get(ui, path).await.1["value"].clone() }
    };
    assert_eq!(d["switches"]["positive_limit"], false, "{d}");
    assert_eq!(d["switches"]["inputs"], sdo("/api/nodes/5/sdo/60FD/0").await, "{d}");
    assert_eq!(d["limits"]["software_position_min"], sdo("/api/nodes/5/sdo/607D/1").await, "{d}");
    assert_eq!(d["limits"]["software_position_max"], sdo("/api/nodes/5/sdo/607D/2").await, "{d}");
    assert_eq!(d["limits"]["max_profile_velocity"], sdo("/api/nodes/5/sdo/607F/0").await, "{d}");
    assert!(d["limits"]["max_profile_velocity"].is_u64(), "{d}");
    // A digital input line shows in the manufacturer bits (60FDh bit 18 = 16 + 2).
    let line3 = json!({"input": "digital", "line": 3, "value": 1});
    assert_eq!(post(&ui, "/api/nodes/5/machine/input", line3).await.0, 200);
    wait_for(Duration::from_secs(10), || async {
        (drive().await["switches"]["manufacturer"].as_u64().unwrap() & 1 << 2 != 0).then_some(())
    })
    .await;
    // The positive limit switch trips, then clears.
    let trip = json!({"kind": "trip", "switch": "positive_limit"});
    assert_eq!(post(&ui, "/api/nodes/5/machine/fault", trip).await.0, 200);
    let d = wait_for(Duration::from_secs(10), || async {
        let d = drive().await;
        (d["switches"]["positive_limit"] == true).then_some(d)
    })
    .await;
    assert_eq!(d["switches"]["negative_limit"], false, "{d}");
    assert_eq!(d["switches"]["inputs"].as_u64().unwrap() & 0b10, 0b10, "{d}");
    assert_eq!(post(&ui, "/api/nodes/5/machine/fault", json!({"kind": "clear"})).await.0, 200);
    wait_for(Duration::from_secs(10), || async {
        (drive().await["switches"]["positive_limit"] == false).then_some(())
    })
    .await;
    // Objects a drive lacks: null.
    let (s, akd) = get(&ui, "/api/nodes/6/drive").await;
    assert_eq!(s, 200, "{akd}");
    assert!(akd["limits"]["max_profile_velocity"].is_null(), "{akd}");
    assert!(akd["limits"]["software_position_max"].is_i64(), "{akd}");
    let (s, dds6) = get(&ui, "/api/nodes/7/drive").await;
    assert_eq!(s, 200, "{dds6}");
    assert!(dds6["switches"].is_null(), "{dds6}");
}

/// `GET /drive/homing`: the methods of the drive's manual (neither the
/// AKD nor the DDS6 lists 60E3h) and 6098h as set now; bad and unknown
/// nodes refused.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn homing_methods_come_from_the_manual_with_the_current_method() {
    let ui = Ui::sims();
    for (node, name) in [(1, "akd"), (2, "dds6")] {
        let (s, v) = get(&ui, &format!("/api/nodes/{node}/drive/homing")).await;
        assert_eq!(s, 200, "{v}");
        let manual = drivebus_personality::Profile::from_name(name).unwrap().info().homing_methods;
        let methods: Vec<i64> =
            v["methods"].as_array().unwrap().iter().map(|m| m.as_i64().unwrap()).collect();
        assert_eq!(methods, manual.iter().map(|&m| i64::from(m)).collect::<Vec<_>>(), "{v}");
        assert_eq!(v["source"], format!("the {name} manual"), "{v}");
        let (_, m) = get(&ui, &format!("/api/nodes/{node}/sdo/6098/0")).await;
        assert_eq!(v["current"], m["value"], "{v} {m}");
    }
    // A method set by SDO is what `current` gives next.
    let (_, v) = get(&ui, "/api/nodes/1/drive/homing").await;
    let other = v["methods"].as_array().unwrap().iter().find(|m| **m != v["current"]).cloned().unwrap();
    assert_eq!(put(&ui, "/api/nodes/1/sdo/6098/0", json!({ "value": other })).await.0, 200);
    assert_eq!(get(&ui, "/api/nodes/1/drive/homing").await.1["current"], other);
    refused(&get(&ui, "/api/nodes/9/drive/homing").await, 404, "not been seen");
    refused(&get(&ui, "/api/nodes/200/drive/homing").await, 400, "node");
}

/// `GET /api/bus`: the frames and bits of the last full second and, with
/// the bitrate known (`serve --bitrate`), their share of it; without one
/// (`ui --sim`) no load.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bus_load_of_the_last_second() {
    let listen = format!("127.0.0.1:{}", common::free_port());
    let ui = Ui::start(&[
        "serve",
        "--listen",
        &listen,
        "--bitrate",
        "500000",
        "--drive",
        "generic:5",
        "--http",
        "127.0.0.1:0",
    ]);
    // Heartbeats every 10 ms: 100 frames of 1 byte per second.
    assert_eq!(put(&ui, "/api/nodes/5/sdo/1017/0", json!({"value": 10})).await.0, 200);
    let b = wait_for(Duration::from_secs(15), || async {
        let (_, b) = get(&ui, "/api/bus").await;
        b["frames_per_s"].as_f64().is_some_and(|f| f > 80.0).then_some(b)
    })
    .await;
    let (fps, bps, load) =
        (b["frames_per_s"].as_f64().unwrap(), b["bits_per_s"].as_f64().unwrap(), b["load"].as_f64().unwrap());
    assert_eq!(b["bitrate"], 500_000, "{b}");
    assert!(fps < 150.0, "{b}");
    // A heartbeat is 55 to 65 bits on the wire with stuffing and intermission.
    assert!(bps > 50.0 * fps && bps < 70.0 * fps, "{b}");
    assert!((load - bps / 500_000.0).abs() < 1e-9, "{b}");
    let sims = Ui::sims();
    let b = wait_for(Duration::from_secs(15), || async {
        let (_, b) = get(&sims, "/api/bus").await;
        b["frames_per_s"].as_f64().map(|_| b)
    })
    .await;
    assert_eq!((&b["load"], &b["bitrate"]), (&Value::Null, &Value::Null), "{b}");
}
