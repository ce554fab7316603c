//! `drivebus ethercat serve`: the contract other tools rely on. On one end
//! of a veth pair the command prints a line containing `ready on IFACE`,
//! the line of drives answers frames from the other end (a broadcast read
//! counts the slaves), `--state-dir` gets one directory per slave,
//! `--pcap` records the exchange, and SIGTERM ends it with status 0.
//!
//! Needs root (veth, AF_PACKET); prints why it was skipped otherwise.

use drivebus_ethercat::server::RawSocket;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod netns;
use netns::{Veth, count_frame};

#[test]
fn serves_a_line_of_drives_on_an_interface_and_stops_on_sigterm() {
    let veth = match Veth::create("dbcli") {
        Ok(v) => v,
        Err(why) => {
            println!("SKIPPED serves_a_line_of_drives_on_an_interface_and_stops_on_sigterm: {why}");
            return;
        }
    };
    let (tag, a, b) = (veth.tag, veth.a.clone(), veth.b.clone());
    let dir = std::env::temp_dir().join(format!("drivebus-ecat-serve-{tag}"));
    let _ = std::fs::remove_dir_all(&dir);
    let pcap = dir.join("line.pcapng");
    std::fs::create_dir_all(&dir).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args([
            "ethercat", "serve", "--iface", &a, "--drive", "ipos", "--drive", "generic", "--drive", "ipos",
        ])
        .arg("--state-dir")
        .arg(dir.join("state"))
        .arg("--pcap")
        .arg(&pcap)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn drivebus");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    assert!(line.contains(&format!("ready on {a}")), "{line}");
    // The segment answers: three slaves add to the working counter.
    let sock = RawSocket::open(&b).expect("socket on the other end");
    let mut buf = vec![0u8; 1514];
    let start = Instant::now();
    let mut wkc = None;
    while wkc.is_none() && start.elapsed() < Duration::from_secs(10) {
        sock.send(&count_frame()).unwrap();
        let until = Instant::now() + Duration::from_millis(500);
        while Instant::now() < until {
            if let Ok(Some(n)) = sock.recv(&mut buf, drivebus_can::Duration::from_millis(100))
                && n >= 30
                && buf[12..14] == [0x88, 0xA4]
                && buf[6] & 0x02 != 0
            {
                wkc = Some(u16::from_le_bytes([buf[28], buf[29]]));
                break;
            }
        }
    }
    assert_eq!(wkc, Some(3), "three drives answer the broadcast read");
    for d in ["ecat-1-ipos", "ecat-2-generic", "ecat-3-ipos"] {
        assert!(dir.join("state").join(d).is_dir(), "{d}");
    }
    // SIGTERM: exit 0.
    let st = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(st.success());
    let status = child.wait().unwrap();
    assert!(status.success(), "exit status {status:?}");
    assert!(std::fs::metadata(&pcap).unwrap().len() > 100, "the capture has the frames");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn refuses_a_drive_that_is_not_an_ethercat_drive() {
    let out = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args(["ethercat", "serve", "--iface", "lo", "--drive", "akd"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("akd: not an EtherCAT drive"), "{err}");
}

/// `--http`: `GET /api/ethercat` gives every slave's name, identity, ESM
/// state and AL status code, and the line's frame counters, which count
/// what the master sends.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn http_gives_the_line_state() {
    let veth = match Veth::create("dbhttp") {
        Ok(v) => v,
        Err(why) => {
            println!("SKIPPED http_gives_the_line_state: {why}");
            return;
        }
    };
    let (a, b) = (veth.a.clone(), veth.b.clone());
    let mut child = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args([
            "ethercat",
            "serve",
            "--iface",
            &a,
            "--drive",
            "ipos",
            "--drive",
            "generic",
            "--http",
            "127.0.0.1:0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn drivebus");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let at = line.find("; state on http://").unwrap_or_else(|| panic!("no state URL in `{line}`"));
    let url = line[at + 11..].trim().to_owned();
    let get =
        || async { reqwest::get(&url).await.expect("GET").json::<serde_json::Value>().await.expect("JSON") };
    let v = get().await;
    let slaves = v["slaves"].as_array().unwrap_or_else(|| panic!("{v}"));
    assert_eq!(slaves.len(), 2, "{v}");
    for (i, s) in slaves.iter().enumerate() {
        assert_eq!(s["position"], i + 1, "{s}");
        assert_eq!((s["state"].as_str(), s["al_status_code"].as_u64()), (Some("INIT"), Some(0)), "{s}");
        assert!(s["identity"]["product_code"].as_u64().is_some_and(|x| x != 0), "{s}");
        assert!(s["name"].as_str().is_some_and(|n| !n.is_empty()), "{s}");
    }
    assert_ne!(slaves[0]["identity"], slaves[1]["identity"], "{v}");
    let before = v["line"]["frames"].as_u64().expect("frames");
    let sock = RawSocket::open(&b).expect("socket on the other end");
    sock.send(&count_frame()).unwrap();
    let t0 = Instant::now();
    while get().await["line"]["frames"].as_u64() <= Some(before) {
        assert!(t0.elapsed() < Duration::from_secs(10), "the frame was not counted");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let _ = child.kill();
    let _ = child.wait();
}

/// `--http` counts what each slave did: a broadcast read is one frame,
/// one datagram and one working counter increment at every slave; the
/// page for the line is served too (the line view: `data-bus="ethercat"`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn http_counts_datagrams_and_working_counters_and_serves_the_line_page() {
    let veth = match Veth::create("dbwkc") {
        Ok(v) => v,
        Err(why) => {
            println!("SKIPPED http_counts_datagrams_and_working_counters_and_serves_the_line_page: {why}");
            return;
        }
    };
    let (a, b) = (veth.a.clone(), veth.b.clone());
    let mut child = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args([
            "ethercat",
            "serve",
            "--iface",
            &a,
            "--drive",
            "generic",
            "--drive",
            "generic",
            "--http",
            "127.0.0.1:0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn drivebus");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let at = line.find("; page on http://").unwrap_or_else(|| panic!("no page URL in `{line}`"));
    let base: String = line[at + 10..].chars().take_while(|c| *c != ';' && !c.is_whitespace()).collect();
    let base = base.trim_end_matches('/').to_owned();
    let get = |path: &'static str| {
        let url = format!("{base}{path}");
        async move { reqwest::get(&url).await.expect("GET").json::<serde_json::Value>().await.expect("JSON") }
    };
    let counters = |v: &serde_json::Value| -> Vec<(u64, u64, u64)> {
        v["slaves"]
            .as_array()
            .unwrap_or_else(|| panic!("{v}"))
            .iter()
            .map(|s| {
                (s["frames"].as_u64().unwrap(), s["datagrams"].as_u64().unwrap(), s["wkc"].as_u64().unwrap())
            })
            .collect()
    };
    let v0 = get("/api/ethercat").await;
    let before = counters(&v0);
    let sock = RawSocket::open(&b).expect("socket on the other end");
    sock.send(&count_frame()).unwrap();
    let t0 = Instant::now();
    let v1 = loop {
        let v = get("/api/ethercat").await;
        // The slaves' counters, not the line's frames: an IPv6 packet on
        // the veth counts there too.
        if counters(&v) != before {
            break v;
        }
        assert!(t0.elapsed() < Duration::from_secs(10), "the frame was not counted");
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    let delta: Vec<(u64, u64, u64)> =
        counters(&v1).iter().zip(&before).map(|(a, b)| (a.0 - b.0, a.1 - b.1, a.2 - b.2)).collect();
    // Only our frame: a master-less line has no other traffic.
    assert_eq!(delta, [(1, 1, 1), (1, 1, 1)], "{v1}");
    assert_eq!(
        v1["line"]["datagrams"].as_u64().unwrap() - v0["line"]["datagrams"].as_u64().unwrap(),
        1,
        "{v1}"
    );
    let page = reqwest::get(format!("{base}/")).await.unwrap().text().await.unwrap();
    assert!(page.contains("<body data-bus=\"ethercat\">") && page.contains("id=\"line\""), "{page}");
    let js = reqwest::get(format!("{base}/line.js")).await.unwrap();
    assert!(js.headers()["content-type"].to_str().unwrap().starts_with("text/javascript"));
    let _ = child.kill();
    let _ = child.wait();
}

/// `--http`'s WebSocket `/api/stream`: the line's ESM first, then an
/// `esm` event whenever a slave's AL state changes; a master (`drivebus
/// ethercat state` in a network namespace) takes the line to PRE-OP, OP
/// and back to INIT and every slave's events come in that order, each
/// `from` the previous `to`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn http_stream_sends_esm_events_in_order() {
    use futures_util::StreamExt;
    let mut l = match netns::VethPair::create("dbesm") {
        Ok(v) => v,
        Err(why) => {
            println!("SKIPPED http_stream_sends_esm_events_in_order: {why}");
            return;
        }
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_drivebus"))
        .args(["ethercat", "serve", "--iface", &l.outer, "--drive", "generic", "--drive", "ipos"])
        .args(["--http", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn drivebus");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    l.serve = Some(child);
    let at = line.find("; page on http://").unwrap_or_else(|| panic!("no page URL in `{line}`"));
    let base: String = line[at + 17..].chars().take_while(|c| *c != ';' && !c.is_whitespace()).collect();
    let (mut ws, _) =
        tokio_tungstenite::connect_async(format!("ws://{}api/stream", base)).await.expect("WebSocket");
    // The next message that is not a `status`.
    let mut next = async move || loop {
        let m = tokio::time::timeout(Duration::from_secs(30), ws.next())
            .await
            .expect("a message within 30 s")
            .expect("stream open")
            .expect("message");
        let v: serde_json::Value = serde_json::from_str(m.to_text().unwrap()).unwrap();
        if v["type"] != "status" {
            return v;
        }
    };
    let first = next().await;
    assert_eq!(first["type"], "line", "{first}");
    let states: Vec<&str> =
        first["slaves"].as_array().unwrap().iter().map(|s| s["state"].as_str().unwrap()).collect();
    assert_eq!(states, ["INIT", "INIT"], "{first}");
    let (ns, inner) = (l.ns.clone(), l.inner.clone());
    let master = move |state: &'static str| {
        let (ns, inner) = (ns.clone(), inner.clone());
        tokio::task::spawn_blocking(move || {
            let out = Command::new("ip")
                .args(["netns", "exec", &ns, env!("CARGO_BIN_EXE_drivebus"), "ethercat", "state", state])
                .args(["--iface", &inner])
                .stdin(Stdio::null())
                .output()
                .expect("run drivebus ethercat state");
            assert!(out.status.success(), "state {state}: {}", String::from_utf8_lossy(&out.stderr));
        })
    };
    // Every slave's states as the events give them, from INIT.
    let mut seen: Vec<Vec<String>> = vec![vec!["INIT".into()]; 2];
    let mut last_t = 0.0;
    for want in ["PRE-OP", "OP", "INIT"] {
        let cmd = master(match want {
            "PRE-OP" => "preop",
            "OP" => "op",
            _ => "init",
        });
        // Until each slave's events have reached `want` since the command.
        let mut reached = [false; 2];
        while reached != [true, true] {
            let e = next().await;
            assert_eq!((e["type"].as_str(), e["event"].as_str()), (Some("event"), Some("esm")), "{e}");
            let i = e["position"].as_u64().unwrap() as usize - 1;
            assert_eq!(e["from"].as_str(), seen[i].last().map(String::as_str), "{e}: after {:?}", seen[i]);
            let t = e["t"].as_f64().unwrap();
            assert!(t >= last_t, "{e}: t before {last_t}");
            last_t = t;
            seen[i].push(e["state"].as_str().unwrap().to_owned());
            reached[i] |= e["state"] == want;
        }
        cmd.await.unwrap();
    }
    println!("states seen per slave: {seen:?}");
    // In order: PRE-OP, then OP, then INIT last.
    for s in &seen {
        let at = |st: &str| s.iter().position(|x| x == st).unwrap_or_else(|| panic!("no {st} in {s:?}"));
        assert!(at("PRE-OP") < at("OP"), "{s:?}");
        assert_eq!(s.last().map(String::as_str), Some("INIT"), "{s:?}");
    }
}
