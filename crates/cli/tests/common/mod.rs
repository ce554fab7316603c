//! Shared helpers: a `drivebus serve` child process that is always killed,
//! free ports, and a tiny SDO client over our socketcand transport.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use drivebus_transport::{CanBus, Frame};

/// Path of the binary under test; `DRIVEBUS_TEST_BIN` runs the tests on
/// another build (e.g. an older one, to see a test fail before a fix).
pub fn bin() -> &'static str {
    match std::env::var("DRIVEBUS_TEST_BIN") {
        Ok(b) => Box::leak(b.into_boxed_str()),
        Err(_) => env!("CARGO_BIN_EXE_drivebus"),
    }
}

/// A free TCP port on 127.0.0.1 (bound once, then released).
pub fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind ephemeral port");
    l.local_addr().expect("local addr").port()
}

/// A running `drivebus serve`; killed when dropped.
pub struct Serve {
    pub child: Child,
    pub port: u16,
    pub line: String,
}

impl Serve {
    /// Starts serve with `args` (besides --listen) and waits for `listening on`.
    pub fn start(args: &[&str], state_dir: Option<&Path>) -> Serve {
        for _ in 0..3 {
            let port = free_port();
            let mut cmd = Command::new(bin());
            cmd.arg("serve").arg("--listen").arg(format!("127.0.0.1:{port}")).args(args);
            if let Some(d) = state_dir {
                cmd.arg("--state-dir").arg(d);
            }
            let mut child =
                cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn drivebus serve");
            let stdout = child.stdout.take().expect("stdout");
            let (tx, rx) = mpsc::channel();
            std::thread::spawn(move || {
                for line in BufReader::new(stdout).lines() {
                    let Ok(line) = line else { break };
                    if tx.send(line).is_err() {
                        break;
                    }
                }
            });
            let mut serve = Serve { child, port, line: String::new() };
            match rx.recv_timeout(Duration::from_secs(20)) {
                Ok(line) if line.contains("listening on") => {
                    serve.line = line;
                    return serve;
                }
                _ => {
                    // Port taken between probe and bind, or a failure: retry.
                    drop(serve);
                }
            }
        }
        panic!("drivebus serve did not print `listening on`");
    }

    /// The socketcand URL of this server.
    pub fn url(&self) -> String {
        format!("socketcand://127.0.0.1:{}/can0", self.port)
    }

    /// Sends SIGTERM and waits (bounded) for the exit status.
    pub fn terminate(&mut self) -> std::process::ExitStatus {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-TERM", &pid]).status();
        let t0 = std::time::Instant::now();
        loop {
            if let Some(st) = self.child.try_wait().expect("try_wait") {
                return st;
            }
            assert!(t0.elapsed() < Duration::from_secs(10), "serve did not exit after SIGTERM");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Serve {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Our socketcand client, past the server's post-rawmode grace time.
pub async fn connect(url: &str) -> CanBus {
    let bus = tokio::time::timeout(Duration::from_secs(5), drivebus_transport::open(url))
        .await
        .expect("connect timed out")
        .expect("connect");
    tokio::time::sleep(Duration::from_millis(60)).await;
    bus
}

/// The next frame matching `pred` within `t`.
pub async fn wait_frame(
    bus: &mut CanBus,
    t: Duration,
    mut pred: impl FnMut(&Frame) -> bool,
) -> Option<Frame> {
    let deadline = tokio::time::Instant::now() + t;
    loop {
        match tokio::time::timeout_at(deadline, bus.recv()).await {
            Ok(Ok(f)) if pred(&f) => return Some(f),
            Ok(Ok(_)) => {}
            _ => return None,
        }
    }
}

/// Expedited SDO upload; `Err(abort code)` or panics on timeout.
pub async fn sdo_read(bus: &mut CanBus, node: u8, index: u16, sub: u8) -> Result<u32, u32> {
    let i = index.to_le_bytes();
    bus.send(Frame::new(0x600 + u16::from(node), &[0x40, i[0], i[1], sub, 0, 0, 0, 0])).await.unwrap();
    let id = 0x580 + u16::from(node);
    let f = wait_frame(bus, Duration::from_secs(3), |f| f.std_id() == Some(id))
        .await
        .unwrap_or_else(|| panic!("no SDO response from node {node} for {index:04X}h"));
    let d = f.data();
    let v = u32::from_le_bytes([d[4], d[5], d[6], d[7]]);
    if d[0] == 0x80 { Err(v) } else { Ok(v) }
}

/// Expedited SDO download of 1..=4 bytes.
pub async fn sdo_write(bus: &mut CanBus, node: u8, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
    let i = index.to_le_bytes();
    let n = data.len();
    assert!((1..=4).contains(&n));
    let mut b = [0x23 | (((4 - n) as u8) << 2), i[0], i[1], sub, 0, 0, 0, 0];
    b[4..4 + n].copy_from_slice(data);
    bus.send(Frame::new(0x600 + u16::from(node), &b)).await.unwrap();
    let id = 0x580 + u16::from(node);
    let f = wait_frame(bus, Duration::from_secs(3), |f| f.std_id() == Some(id))
        .await
        .unwrap_or_else(|| panic!("no SDO response from node {node} for {index:04X}h"));
    let d = f.data();
    if d[0] == 0x80 { Err(u32::from_le_bytes([d[4], d[5], d[6], d[7]])) } else { Ok(()) }
}

/// A socketcand server on 127.0.0.1 whose bus holds unconfigured CiA 301
/// slaves with LSS (node-ID FFh, vendor ABCh, product 77h, revision 3),
/// one per serial. The bus lives as long as this value.
pub struct LssBus {
    /// `socketcand://127.0.0.1:PORT/can0`.
    pub url: String,
    // Dropped in this order: the slaves, the server, then their runtime.
    _hosts: Vec<drivebus_transport::host::DeviceHost<drivebus_node::NodeDevice<drivebus_od::NoHooks>>>,
    _server: drivebus_transport::socketcand::SocketcandServer,
    _rt: tokio::runtime::Runtime,
}

impl LssBus {
    /// The bus with one unconfigured slave per serial.
    pub fn start(serials: &[u32]) -> LssBus {
        let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
        let (server, addr) = rt
            .block_on(drivebus_transport::socketcand::SocketcandServer::bind("127.0.0.1:0", "can0"))
            .unwrap();
        let unconfigured = |&serial: &u32| {
            let mut cfg = drivebus_node::NodeConfig::new(0xFF);
            cfg.lss = true;
            cfg.identity =
                drivebus_node::Identity { vendor_id: 0xABC, product_code: 0x77, revision: 3, serial };
            drivebus_node::NodeDevice::new(drivebus_node::Node::new(cfg), drivebus_od::NoHooks)
        };
        let hosts = rt.block_on(async {
            drivebus_transport::host::spawn_on_hub(serials.iter().map(unconfigured), server.hub())
        });
        LssBus { url: format!("socketcand://{addr}/can0"), _hosts: hosts, _server: server, _rt: rt }
    }
}
