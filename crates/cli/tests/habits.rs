//! The habits of candump/cangen/cansend users and of bus analysers (issue
//! 15 §2): candump filters and timestamp modes, RTR where the transport
//! carries it, cyclic transmit, SYNC/heartbeat/TIME producers, a load
//! generator, bus statistics, CSV from `monitor` and `dump --pdo`.

mod common;

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::time::Duration;

use assert_cmd::Command;
use common::{Serve, connect, wait_frame};
use predicates::str::contains;

fn db(url: &str, args: &[&str]) -> assert_cmd::assert::Assert {
    Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .timeout(Duration::from_secs(60))
        .assert()
}

fn stdout(a: assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.success().get_output().stdout).into_owned()
}

/// Lines of a background command until it exits (bounded by its own --seconds).
fn lines_of(url: &str, args: &[&str], during: impl FnOnce()) -> Vec<String> {
    let mut child = std::process::Command::new(common::bin())
        .arg("--bus")
        .arg(url)
        .args(args)
        .env_remove("DRIVEBUS_BUS")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = child.stdout.take().unwrap();
    let reader =
        std::thread::spawn(move || BufReader::new(out).lines().map_while(Result::ok).collect::<Vec<_>>());
    during();
    let _ = child.wait();
    reader.join().unwrap()
}

/// The leading number of a trace line.
fn time_of(line: &str) -> f64 {
    line.split_whitespace().next().and_then(|t| t.parse().ok()).unwrap_or_else(|| panic!("`{line}`"))
}

#[test]
fn dump_takes_candump_filters_and_timestamp_modes() {
    let srv = Serve::start(&["--drive", "generic:5", "--drive", "generic:6"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "write", "1017", "0", "50"]).success();
    db(&u, &["--node", "6", "sdo", "write", "1017", "0", "50"]).success();
    // ID:MASK: node 5's heartbeat only; every line 50 ms after the last.
    let got = lines_of(
        &u,
        &["dump", "--filter", "705:7FF", "--count", "4", "-t", "delta", "--seconds", "10"],
        || {},
    );
    assert_eq!(got.len(), 4, "{got:?}");
    assert!(got.iter().all(|l| l.contains("heartbeat node 5")), "{got:?}");
    assert_eq!(time_of(&got[0]), 0.0, "{got:?}");
    for l in &got[1..] {
        assert!((0.02..0.2).contains(&time_of(l)), "delta of 50 ms heartbeats: {got:?}");
    }
    // Zero: from the first frame shown, rising.
    let got = lines_of(
        &u,
        &["dump", "--filter", "706:7FF", "--count", "3", "-t", "zero", "--seconds", "10"],
        || {},
    );
    let t: Vec<f64> = got.iter().map(|l| time_of(l)).collect();
    assert!(t.len() == 3 && t[0] == 0.0 && t[1] > 0.02 && t[2] > t[1], "{got:?}");
    // Absolute: Unix time.
    let got = lines_of(
        &u,
        &["dump", "--filter", "706:7FF", "--count", "1", "-t", "absolute", "--seconds", "10"],
        || {},
    );
    assert!(time_of(&got[0]) > 1.7e9, "{got:?}");
    // ~: inverted (all but node 5's heartbeat); several filters; j joins.
    let got = lines_of(&u, &["dump", "--filter", "705~7FF", "--count", "4", "--seconds", "10"], || {});
    assert!(got.len() == 4 && got.iter().all(|l| l.contains("heartbeat node 6")), "{got:?}");
    let got =
        lines_of(&u, &["dump", "--filter", "705:7FF,706:7FF", "--count", "8", "--seconds", "10"], || {});
    assert!(got.iter().any(|l| l.contains("node 5")) && got.iter().any(|l| l.contains("node 6")), "{got:?}");
    let got = lines_of(
        &u,
        &["dump", "--filter", "700:780", "--filter", "706~7FF,j", "--count", "3", "--seconds", "10"],
        || {},
    );
    assert!(got.len() == 3 && got.iter().all(|l| l.contains("heartbeat node 5")), "{got:?}");
    db(&u, &["dump", "--filter", "705", "--count", "1"]).failure().stderr(contains("bad --filter `705`"));
    db(&u, &["dump", "--candump", "-t", "delta", "--count", "1"])
        .failure()
        .stderr(contains("absolute times"));
}

#[test]
fn rtr_frames_where_the_transport_carries_them_and_a_clear_refusal_where_not() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    // socketcand has no remote frames: dump says so, gen -R refuses.
    db(&u, &["dump", "--seconds", "0.3"]).success().stderr(contains("carries no remote (RTR) frames"));
    db(&u, &["gen", "-R", "--count", "1"]).failure().stderr(contains("cannot carry RTR frames (socketcand)"));
    // The in-process bus carries them.
    let out = stdout(db("virtual", &["gen", "-R", "-I", "705", "-L", "1", "--count", "2", "-v", "-g", "1"]));
    assert!(out.contains("705#R1") && out.contains("gen: sent 2 frame(s)"), "{out}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn send_repeats_with_a_period() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let mut spy = connect(&u).await;
    let u2 = u.clone();
    // Read while it sends: the frames' arrival times.
    let run = tokio::task::spawn_blocking(move || {
        stdout(db(&u2, &["send", "321#01", "322#", "--period", "20", "--count", "5"]))
    });
    let mut at = Vec::new();
    while at.len() < 5 {
        wait_frame(&mut spy, Duration::from_secs(10), |f| f.std_id() == Some(0x321))
            .await
            .expect("cyclic frame");
        at.push(tokio::time::Instant::now());
    }
    assert!(wait_frame(&mut spy, Duration::from_millis(300), |f| f.std_id() == Some(0x321)).await.is_none());
    let out = run.await.unwrap();
    assert!(out.contains("sent 2 frame(s) 5 time(s) every 20 ms"), "{out}");
    // Four periods of 20 ms between the first and the last (sent, then relayed).
    let span = at[4] - at[0];
    assert!(span >= Duration::from_millis(50), "5 rounds 20 ms apart arrived within {span:?}");
    db(&u, &["send", "321#01", "--count", "5"]).failure().stderr(contains("--period"));
    db(&u, &["send", "321#01", "--period", "0"]).failure().stderr(contains("milliseconds"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn produce_sync_heartbeat_and_time() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let mut spy = connect(&u).await;
    let u2 = u.clone();
    let run = tokio::task::spawn_blocking(move || {
        stdout(db(
            &u2,
            &[
                "produce",
                "--sync",
                "10",
                "--sync-counter",
                "4",
                "--heartbeat",
                "100",
                "--heartbeat-id",
                "100",
                "--time",
                "200",
                "--seconds",
                "1.5",
            ],
        ))
    });
    let (mut sync, mut hb, mut time) = (Vec::new(), 0, Vec::new());
    let end = tokio::time::Instant::now() + Duration::from_secs(4);
    while let Ok(Ok(f)) = tokio::time::timeout_at(end, spy.recv()).await {
        match f.std_id() {
            Some(0x080) => sync.push(f.data()[0]),
            Some(0x764) if f.data() == [0x05] => hb += 1,
            Some(0x100) => time.push(f),
            _ => {}
        }
    }
    let out = run.await.unwrap();
    assert!(out.contains("produced") && out.contains("SYNC every 10 ms"), "{out}");
    assert!(sync.len() >= 50, "{} SYNCs", sync.len());
    for w in sync.windows(2) {
        assert_eq!(w[1], if w[0] == 4 { 1 } else { w[0] + 1 }, "SYNC counter 1..4: {sync:?}");
    }
    assert!((5..=20).contains(&hb), "{hb} heartbeats of node 100 in 1.5 s at 100 ms");
    assert!(time.len() >= 4, "{} TIME stamps", time.len());
    // TIME_OF_DAY: ms after midnight (28 bits), days since 1984 — today.
    let d = time[0].data();
    let days = u16::from_le_bytes([d[4], d[5]]);
    let now_days =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs() / 86_400;
    assert!((u64::from(days) + 5113).abs_diff(now_days) <= 1, "TIME says day {days} since 1984");
    db(&u, &["produce", "--seconds", "0.1"]).failure().stderr(contains("nothing to produce"));
    db(&u, &["produce", "--heartbeat", "100"]).failure().stderr(contains("--heartbeat-id"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn gen_makes_cangen_traffic() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    let mut spy = connect(&u).await;
    let u2 = u.clone();
    let out = tokio::task::spawn_blocking(move || {
        stdout(db(&u2, &["gen", "-g", "1", "--count", "50", "-I", "42A", "-L", "8", "-D", "i"]))
    })
    .await
    .unwrap();
    assert!(out.contains("gen: sent 50 frame(s)"), "{out}");
    for k in 0u64..50 {
        let f =
            wait_frame(&mut spy, Duration::from_secs(3), |f| f.std_id() == Some(0x42A)).await.expect("frame");
        assert_eq!(f.data(), k.to_le_bytes(), "frame {k} counts");
    }
}

#[test]
fn stats_reports_load_and_rates_per_cob_id() {
    let srv = Serve::start(&["--drive", "generic:5"], None);
    let u = srv.url();
    db(&u, &["--node", "5", "sdo", "write", "1017", "0", "10"]).success();
    let out = stdout(db(&u, &["stats", "--bitrate", "125000", "--seconds", "2.1", "--interval", "1"]));
    let first = out.lines().next().unwrap_or_default();
    assert!(first.contains("load ") && first.contains("% of 125 kbit/s"), "{out}");
    assert!(first.contains("error frames: not reported by this transport"), "{out}");
    assert!(out.contains("705 ") && out.contains("heartbeat node 5"), "{out}");
    let out = stdout(db(&u, &["--json", "stats", "--bitrate", "125000", "--seconds", "1.05"]));
    let j: serde_json::Value = serde_json::from_str(out.lines().next().unwrap()).unwrap();
    let hb = j["per_id"].as_array().unwrap().iter().find(|e| e["id"] == 0x705).expect("705h counted").clone();
    let rate = hb["per_second"].as_f64().unwrap();
    assert!((40.0..130.0).contains(&rate), "heartbeat every 10 ms: {rate}/s");
    // Each heartbeat (705#7F, pre-operational) counted with its exact
    // length on the wire: stuff bits and intermission included.
    let wire = drivebus_bus::timing::frame_bits(&drivebus_transport::Frame::new(0x705, &[0x7F])).total();
    assert_eq!(hb["bits"].as_u64().unwrap(), hb["frames"].as_u64().unwrap() * u64::from(wire), "{hb}");
    // The load is the bits on the wire per second over the bit rate.
    let load = j["load"].as_f64().unwrap();
    let expected = j["bits_per_second"].as_f64().unwrap() / 125_000.0;
    assert!(load > 0.01 && (load - expected).abs() < 1e-9, "{load} vs {expected}");
}

#[test]
fn csv_from_monitor_and_dump_pdo() {
    let srv = Serve::start(&["--drive", "generic:1"], None);
    let u = srv.url();
    db(&u, &["--node", "1", "sdo", "write", "1017", "0", "50"]).success();
    let got = lines_of(
        &u,
        &["monitor", "--csv", "--seconds", "2", "--watch", "statusword", "--watch", "6064"],
        || {},
    );
    assert_eq!(got[0], "time_s,node,state,emcy,Statusword,Position actual value", "{got:?}");
    // A row per change: the state first, the values once read.
    let row = got
        .iter()
        .find(|l| l.contains(",1,pre-operational,") && !l.ends_with(','))
        .unwrap_or_else(|| panic!("{got:?}"));
    let cells: Vec<&str> = row.split(',').collect();
    assert_eq!(cells.len(), 6, "{row}");
    assert!(cells[0].parse::<f64>().is_ok() && cells[4].parse::<u16>().is_ok() && cells[5] == "0", "{row}");
    // dump --pdo --csv: a column per mapped object, a row per PDO.
    let u2 = u.clone();
    let got = lines_of(
        &u,
        &["--node", "1", "dump", "--pdo", "--csv", "--count", "2", "--seconds", "10"],
        move || {
            std::thread::sleep(Duration::from_millis(700));
            Command::new(common::bin())
                .args(["--bus", &u2, "--node", "1", "nmt", "start"])
                .assert()
                .success();
            Command::new(common::bin())
                .args(["--bus", &u2, "--node", "1", "drive", "enable"])
                .assert()
                .success();
        },
    );
    let header: Vec<&str> = got[0].split(',').collect();
    assert_eq!(&header[..3], ["time_s", "cob_id", "pdo"], "{got:?}");
    let sw = header
        .iter()
        .position(|h| *h == "TPDO1 node 1 6041h:00 Statusword")
        .unwrap_or_else(|| panic!("{got:?}"));
    let row: Vec<&str> = got[1].split(',').collect();
    assert_eq!(row.len(), header.len(), "{got:?}");
    assert_eq!((row[1], row[2]), ("181", "TPDO1 node 1"), "{got:?}");
    assert!(row[sw].parse::<u16>().is_ok(), "statusword as a number: {got:?}");
    db(&u, &["dump", "--csv"]).failure().stderr(contains("--pdo"));
}

/// The commands of `--help`'s examples, as written (the part before two
/// spaces or a parenthesis; hardware URLs left out).
fn help_examples(cmd: &str) -> Vec<String> {
    let out =
        Command::new(common::bin()).args([cmd, "--help"]).assert().success().get_output().stdout.clone();
    let text = String::from_utf8_lossy(&out).into_owned();
    let from = text.find("Examples:\n").expect("Examples") + 10;
    text[from..]
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.trim_start().strip_prefix("drivebus "))
        .map(|l| {
            let l = l.split("  ").next().unwrap_or(l);
            l.split(" (").next().unwrap_or(l).trim().to_owned()
        })
        .filter(|l| !l.contains("/dev/") && !l.contains("socketcan://"))
        .collect()
}

/// Every example of the new options runs as written against a served
/// drive: it succeeds, or runs until Ctrl-C and then exits 0.
#[test]
fn help_examples_of_the_bus_commands_run_as_written() {
    let srv = Serve::start(&["--drive", "generic:1", "--drive", "generic:5"], None);
    let dir = tempfile::tempdir().unwrap();
    let mut ran = 0;
    for cmd in ["dump", "monitor", "send", "produce", "gen", "stats"] {
        for ex in help_examples(cmd) {
            let ex = ex.replace("29536", &srv.port.to_string());
            let (ex, to_file) = match ex.split_once(" > ") {
                Some((c, f)) => (c.to_owned(), Some(f.trim().to_owned())),
                None => (ex, None),
            };
            let mut child = std::process::Command::new(common::bin())
                .args(ex.split_whitespace())
                // Examples without --bus run on the in-process bus.
                .env_remove("DRIVEBUS_BUS")
                .current_dir(dir.path())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            let end = std::time::Instant::now() + Duration::from_millis(2500);
            let status = loop {
                if let Some(s) = child.try_wait().unwrap() {
                    break s;
                }
                if std::time::Instant::now() > end {
                    let _ =
                        std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
                    break child.wait().unwrap();
                }
                std::thread::sleep(Duration::from_millis(20));
            };
            let mut err = String::new();
            let _ = std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err);
            assert!(
                status.success(),
                "`drivebus {ex}`{}: {err}",
                to_file.map(|f| format!(" > {f}")).unwrap_or_default()
            );
            ran += 1;
        }
    }
    assert!(ran >= 20, "{ran} examples ran");
}
