//! `drivebus serve --bus URL`: the virtual drives as stations of another
//! bus — an slcan adapter (the pseudo-terminal emulator stands in for the
//! hardware) and a second socketcand hub — with their own timing, and the
//! socketcand listener on or off.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use common::{bin, connect, free_port, sdo_read, sdo_write, wait_frame};
use drivebus_transport::socketcand::SocketcandServer;
use drivebus_transport::{CanBus, Frame, Hub};

/// A `drivebus serve` child and its ready line; killed when dropped.
struct Served {
    child: Child,
    line: String,
}

impl Served {
    fn start(args: &[&str]) -> Served {
        let mut child = Command::new(bin())
            .arg("serve")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn drivebus serve");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let line = rx.recv_timeout(Duration::from_secs(20)).expect("the ready line");
        Served { child, line }
    }

    /// SIGTERM, then the exit status (bounded).
    fn terminate(&mut self) -> std::process::ExitStatus {
        let _ = Command::new("kill").args(["-TERM", &self.child.id().to_string()]).status();
        for _ in 0..500 {
            if let Some(st) = self.child.try_wait().expect("try_wait") {
                return st;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("serve did not exit after SIGTERM");
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The drive answers, boots on reset node and beats at 1017h on `bus`.
async fn drive_on(bus: &mut CanBus, node: u8, device_type: u32) {
    assert_eq!(sdo_read(bus, node, 0x1000, 0).await, Ok(device_type));
    let hb = 0x700 + u16::from(node);
    bus.send(Frame::new(0x000, &[0x81, node])).await.unwrap();
    let boot = wait_frame(bus, Duration::from_secs(3), |f| f.std_id() == Some(hb)).await;
    assert_eq!(boot.map(|f| f.data().to_vec()), Some(vec![0x00]), "boot-up after reset node");
    sdo_write(bus, node, 0x1017, 0, &50u16.to_le_bytes()).await.unwrap();
    // Its own timing on the bus: heartbeats every 50 ms.
    let t0 = tokio::time::Instant::now();
    for _ in 0..4 {
        let f = wait_frame(bus, Duration::from_secs(2), |f| f.std_id() == Some(hb)).await;
        assert_eq!(f.expect("heartbeat").data(), [0x7F]);
    }
    let dt = t0.elapsed();
    assert!(dt >= Duration::from_millis(140) && dt < Duration::from_secs(2), "4 heartbeats in {dt:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn drives_on_another_socketcand_hub() {
    // The "real" bus: a socketcand server in this process, and a station on it.
    let (outer, addr) = SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
    let mut station = outer.hub().attach();
    let url = format!("socketcand://{addr}/can0");
    let mut srv = Served::start(&["--bus", &url, "--drive", "akd:1"]);
    assert!(srv.line.contains(&format!("serving on {url}")), "{}", srv.line);
    assert!(!srv.line.contains("listening on"), "no listener without --listen: {}", srv.line);
    // socketcand clients see traffic only after the server's grace time.
    tokio::time::sleep(Duration::from_millis(100)).await;
    let akd = drivebus_personality::Profile::Akd.info().device_type;
    drive_on(&mut station, 1, akd).await;
    let st = srv.terminate();
    assert!(st.success(), "exit status {st:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_listener_shares_the_drives_and_the_outer_bus() {
    let (outer, addr) = SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
    let mut station = outer.hub().attach();
    let port = free_port();
    let listen = format!("127.0.0.1:{port}");
    let srv = Served::start(&[
        "--bus",
        &format!("socketcand://{addr}/can0"),
        "--listen",
        &listen,
        "--drive",
        "generic:5",
    ]);
    assert!(srv.line.contains(&format!("listening on {listen} (channel can0)")), "{}", srv.line);
    let mut client = connect(&format!("socketcand://{listen}/can0")).await;
    tokio::time::sleep(Duration::from_millis(100)).await;
    // The listener's client reaches the drive...
    assert_eq!(sdo_read(&mut client, 5, 0x1000, 0).await, Ok(0x0002_0192));
    // ...and hears the outer bus's stations.
    station.send(Frame::new(0x123, &[1, 2, 3])).await.unwrap();
    let f = wait_frame(&mut client, Duration::from_secs(3), |f| f.std_id() == Some(0x123)).await;
    assert_eq!(f, Some(Frame::new(0x123, &[1, 2, 3])));
    // The outer station hears the drive answer the listener's client.
    let seen = wait_frame(&mut station, Duration::from_secs(3), |f| f.std_id() == Some(0x585)).await;
    assert!(seen.is_some(), "the SDO answer reached the outer bus");
}

#[cfg(unix)]
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn drives_behind_an_slcan_adapter() {
    // The emulated adapter: an slcan pseudo-terminal onto this process's hub.
    let hub = Hub::default();
    let pty = drivebus_transport::slcan::SlcanPty::spawn(hub.attach()).expect("a pseudo-terminal");
    let mut station = hub.attach();
    let url = format!("slcan://{}?bitrate=500000", pty.path().display());
    let mut srv = Served::start(&["--bus", &url, "--drive", "kc1:3", "--drive", "dds6:4"]);
    assert!(srv.line.contains("serving on slcan://"), "{}", srv.line);
    let kc1 = drivebus_personality::Profile::Kc1.info().device_type;
    drive_on(&mut station, 3, kc1).await;
    // Both drives are stations: the second answers too.
    let dds6 = drivebus_personality::Profile::Dds6.info().device_type;
    assert_eq!(sdo_read(&mut station, 4, 0x1000, 0).await, Ok(dds6));
    let st = srv.terminate();
    assert!(st.success(), "exit status {st:?}");
}
