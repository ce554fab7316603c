//! slcan adapters emulated over TCP: every connection is one adapter on
//! the hub, reachable by pyserial's `socket://HOST:PORT` URL (python-can
//! `can.Bus(interface='slcan', channel='socket://127.0.0.1:PORT')`) or by
//! our `slcan://tcp:HOST:PORT`.

use std::io;
use std::net::SocketAddr;
use std::time::{SystemTime, UNIX_EPOCH};

use tokio::net::{TcpListener, TcpStream, ToSocketAddrs};
use tokio::task::{JoinHandle, JoinSet};

use super::codec::{LineSplitter, Token};
use super::device::{Action, SlcanDevice};
use crate::hub::Hub;

/// Bytes queued towards a connection before bus frames wait in the hub
/// receiver (which then counts overruns for a host that stops reading).
const OUT_MAX: usize = 16 * 1024;
/// Most simultaneous connections.
const MAX_CLIENTS: usize = 64;

/// A TCP listener whose connections are emulated slcan adapters on a hub;
/// dropping it closes the listener and every connection.
pub struct SlcanTcpServer {
    local_addr: SocketAddr,
    task: JoinHandle<()>,
}

impl SlcanTcpServer {
    /// Listens on `addr`; each connection joins `hub` as an adapter.
    pub async fn bind(addr: impl ToSocketAddrs, hub: Hub) -> io::Result<(SlcanTcpServer, SocketAddr)> {
        let listener = TcpListener::bind(addr).await?;
        let local_addr = listener.local_addr()?;
        let task = tokio::spawn(async move {
            let mut tasks = JoinSet::new();
            loop {
                tokio::select! {
                    acc = listener.accept() => match acc {
                        Ok((stream, peer)) if tasks.len() < MAX_CLIENTS => {
                            let hub = hub.clone();
                            tasks.spawn(async move {
                                if let Err(e) = serve(stream, hub).await {
                                    tracing::debug!(%peer, error = %e, "slcan TCP client gone");
                                }
                            });
                        }
                        Ok((_, peer)) => tracing::warn!(%peer, "too many slcan TCP clients, refusing"),
                        Err(e) => {
                            tracing::warn!(error = %e, "accept failed");
                            tokio::time::sleep(std::time::Duration::from_millis(50)).await;
                        }
                    },
                    Some(_) = tasks.join_next(), if !tasks.is_empty() => {}
                }
            }
        });
        Ok((SlcanTcpServer { local_addr, task }, local_addr))
    }

    /// The listening address.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }
}

impl Drop for SlcanTcpServer {
    fn drop(&mut self) {
        self.task.abort();
    }
}

async fn serve(stream: TcpStream, hub: Hub) -> io::Result<()> {
    stream.set_nodelay(true)?;
    let (tx, mut rx) = hub.attach().split();
    let mut dev = SlcanDevice::new();
    let mut split = LineSplitter::new();
    let mut buf = [0u8; 2048];
    let mut out: Vec<u8> = Vec::with_capacity(4096);
    let mut to_bus = Vec::new();
    loop {
        tokio::select! {
            r = stream.readable() => {
                r?;
                let n = match stream.try_read(&mut buf) {
                    Ok(0) => return Ok(()),
                    Ok(n) => n,
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
                    Err(e) => return Err(e),
                };
                split.feed(&buf[..n], |t| {
                    if let Token::Line(l) = t {
                        let mut reply = Vec::new();
                        match dev.handle_line(l, &mut reply) {
                            Action::Send(f) => to_bus.push(f),
                            Action::Closed => out.clear(),
                            Action::None => {}
                        }
                        if out.len() < 2 * OUT_MAX {
                            out.extend_from_slice(&reply);
                        }
                    }
                });
                for f in to_bus.drain(..) {
                    tx.send(f).await?;
                }
            }
            f = rx.recv(), if out.len() < OUT_MAX => {
                let now_ms = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64);
                dev.bus_frame(&f?, now_ms, &mut out);
            }
            w = stream.writable(), if !out.is_empty() => {
                w?;
                match stream.try_write(&out) {
                    Ok(n) => { out.drain(..n); }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                    Err(e) => return Err(e),
                }
            }
        }
    }
}
