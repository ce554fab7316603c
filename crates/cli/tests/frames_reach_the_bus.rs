//! A command has put its frames on the bus before it reports success and
//! exits: 1 000 `drivebus nmt stop` invocations over socketcand and over
//! the slcan pseudo-terminal, every frame seen by a sniffer on the bus.
//! (Before issue 10 about half were lost: the process exited before the
//! transport had written the frame.)

mod common;

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use drivebus_transport::{CanBus, Hub};

const RUNS: usize = 1000;

/// Counts NMT stop frames to node `node` on `spy` until dropped.
fn sniff(rt: &tokio::runtime::Runtime, mut spy: CanBus, node: u8) -> Arc<AtomicU64> {
    let n = Arc::new(AtomicU64::new(0));
    let n2 = n.clone();
    rt.spawn(async move {
        while let Ok(f) = spy.recv().await {
            if f.std_id() == Some(0x000) && f.data() == [0x02, node] {
                n2.fetch_add(1, Ordering::Relaxed);
            }
        }
    });
    n
}

fn nmt_stop(url: &str, node: u8) {
    let out = std::process::Command::new(common::bin())
        .args(["--bus", url, "--node", &node.to_string(), "nmt", "stop"])
        .env_remove("DRIVEBUS_BUS")
        .output()
        .expect("run drivebus");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("NMT stop sent to node"));
}

/// Every run has reported success; the sniffer must have every frame.
/// (A short settle for the sniffer's own task, not a measurement.)
fn settle(n: &AtomicU64) -> u64 {
    for _ in 0..50 {
        if n.load(Ordering::Relaxed) as usize >= RUNS {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    n.load(Ordering::Relaxed)
}

#[test]
fn nmt_stop_1000_times_over_socketcand_every_frame_on_the_bus() {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let (server, addr) =
        rt.block_on(drivebus_transport::socketcand::SocketcandServer::bind("127.0.0.1:0", "can0")).unwrap();
    let seen = sniff(&rt, server.attach(), 5);
    let url = format!("socketcand://{addr}/can0");
    // Four clients at a time: the server takes several connections.
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                for _ in 0..RUNS / 4 {
                    nmt_stop(&url, 5);
                }
            });
        }
    });
    assert_eq!(settle(&seen) as usize, RUNS, "NMT stop frames on the bus");
    drop(server);
}

#[cfg(unix)]
#[test]
fn nmt_stop_1000_times_over_the_slcan_pty_every_frame_on_the_bus() {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let hub = Hub::default();
    let pty = rt.block_on(async { drivebus_transport::slcan::SlcanPty::spawn(hub.attach()) }).unwrap();
    let seen = sniff(&rt, hub.attach(), 6);
    let url = format!("slcan://{}?bitrate=1000000", pty.path().display());
    // One host at a time: a serial port is opened exclusively.
    for _ in 0..RUNS {
        nmt_stop(&url, 6);
    }
    assert_eq!(settle(&seen) as usize, RUNS, "NMT stop frames on the bus");
    drop(pty);
}
