//! socketcand-compatible TCP hub.

use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream, ToSocketAddrs};
use tokio::sync::{broadcast, mpsc};
use tokio::task::{JoinHandle, JoinSet};

use super::proto::{self, Message, Splitter};
use crate::handle::CanBus;
use crate::hub::{Hub, HubFrame, ParticipantId};

/// Settings of a [`SocketcandServer`].
#[derive(Clone, Debug)]
pub struct SocketcandConfig {
    /// The only bus name `< open NAME >` accepts.
    pub channel: String,
    /// Quiet time after `< ok >` for rawmode before frames flow; frames of
    /// that window are not sent to the client. python-can reads the `< ok >`
    /// with one `recv` and fails if a frame arrives in the same read.
    pub grace: Duration,
    /// Most simultaneous clients; further connections are closed at once.
    pub max_clients: usize,
    /// A client whose socket accepts nothing for this long is disconnected
    /// (it stopped reading; without traffic the hub cannot notice a lag).
    pub write_timeout: Duration,
}

impl SocketcandConfig {
    /// Defaults for bus `channel`: 20 ms grace, 256 clients, 10 s write timeout.
    pub fn new(channel: &str) -> Self {
        SocketcandConfig {
            channel: channel.to_owned(),
            grace: Duration::from_millis(20),
            max_clients: 256,
            write_timeout: Duration::from_secs(10),
        }
    }
}

/// A socketcand-compatible server: a bus hub that TCP clients (python-can's
/// `socketcand` interface, our [`connect`](super::connect)) join in raw
/// mode, and that in-process participants join with
/// [`attach`](SocketcandServer::attach).
///
/// Dropping the server closes the listener and every client connection.
pub struct SocketcandServer {
    hub: Hub,
    local_addr: SocketAddr,
    clients: Arc<AtomicUsize>,
    task: JoinHandle<()>,
}

impl SocketcandServer {
    /// Listens on `addr` serving bus `channel` on a new default [`Hub`].
    /// Returns the server and the address it listens on (useful with port 0).
    pub async fn bind(addr: impl ToSocketAddrs, channel: &str) -> io::Result<(SocketcandServer, SocketAddr)> {
        SocketcandServer::bind_with(addr, SocketcandConfig::new(channel), Hub::default()).await
    }

    /// Listens on `addr` with `cfg`, relaying through `hub` (which may be
    /// shared with an [`SlcanPty`](crate::slcan::SlcanPty), a paced or
    /// faulty [`HubConfig`](crate::HubConfig), …).
    pub async fn bind_with(
        addr: impl ToSocketAddrs,
        cfg: SocketcandConfig,
        hub: Hub,
    ) -> io::Result<(SocketcandServer, SocketAddr)> {
        let listener = TcpListener::bind(addr).await?;
        let local_addr = listener.local_addr()?;
        let clients = Arc::new(AtomicUsize::new(0));
        let task = tokio::spawn(accept_loop(listener, Arc::new(cfg), hub.clone(), clients.clone()));
        tracing::info!(%local_addr, "socketcand server listening");
        Ok((SocketcandServer { hub, local_addr, clients, task }, local_addr))
    }

    /// The hub behind the server.
    pub fn hub(&self) -> &Hub {
        &self.hub
    }
    /// A new in-process participant on this bus (a virtual drive, a master).
    pub fn attach(&self) -> CanBus {
        self.hub.attach()
    }
    /// The listening address.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }
    /// TCP clients connected now.
    pub fn client_count(&self) -> usize {
        self.clients.load(Ordering::Relaxed)
    }

    /// Stops the server and returns once the listener is closed (a
    /// connection attempt afterwards is refused); dropping the server
    /// closes it a moment later instead.
    pub async fn close(mut self) {
        self.task.abort();
        // Cancelled (or finished): the accept loop and its listener are gone.
        let _ = (&mut self.task).await;
    }
}

impl Drop for SocketcandServer {
    fn drop(&mut self) {
        // The accept task owns the client tasks (JoinSet): aborting it ends all.
        self.task.abort();
    }
}

async fn accept_loop(listener: TcpListener, cfg: Arc<SocketcandConfig>, hub: Hub, clients: Arc<AtomicUsize>) {
    let mut tasks = JoinSet::new();
    loop {
        tokio::select! {
            acc = listener.accept() => match acc {
                Ok((stream, peer)) => {
                    if tasks.len() >= cfg.max_clients {
                        tracing::warn!(%peer, "too many socketcand clients, refusing");
                        continue;
                    }
                    let (cfg, hub, clients) = (cfg.clone(), hub.clone(), clients.clone());
                    tasks.spawn(async move {
                        clients.fetch_add(1, Ordering::Relaxed);
                        let why = serve(stream, &cfg, &hub).await;
                        clients.fetch_sub(1, Ordering::Relaxed);
                        tracing::debug!(%peer, %why, "socketcand client gone");
                    });
                }
                Err(e) => {
                    // Typically EMFILE: back off instead of spinning.
                    tracing::warn!(error = %e, "accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                }
            },
            Some(_) = tasks.join_next(), if !tasks.is_empty() => {}
        }
    }
}

/// What the reader asks the writer to do (the writer owns the socket's
/// write half, so replies and relayed frames never interleave mid-message).
enum Ctl {
    Reply(&'static str),
    /// `< ok >` for rawmode, a grace with frames held back, then relaying.
    EnterRaw,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    NoBus,
    Bcm,
    Raw,
}

/// Serves one client until it leaves or fails; returns why.
async fn serve(stream: TcpStream, cfg: &SocketcandConfig, hub: &Hub) -> String {
    if let Err(e) = stream.set_nodelay(true) {
        return format!("set TCP_NODELAY: {e}");
    }
    let id = hub.new_participant();
    let (rd, wr) = stream.into_split();
    let (ctl_tx, ctl_rx) = mpsc::channel(16);
    // Whichever side ends first ends the session; the other is dropped.
    tokio::select! {
        why = reader(rd, cfg, hub, id, ctl_tx) => why,
        why = writer(wr, cfg, hub, id, ctl_rx) => why,
    }
}

/// Re-arms TCP_QUICKACK. Linux clears it after some ACKs, so socketcand sets
/// it after every read: without it the last segment of each burst a Nagle
/// client sends waits ~40 ms for our delayed ACK (SDO block transfer stall).
fn quickack(rd: &OwnedReadHalf) {
    #[cfg(any(target_os = "linux", target_os = "android"))]
    {
        let _ = socket2::SockRef::from(rd.as_ref()).set_tcp_quickack(true);
    }
    #[cfg(not(any(target_os = "linux", target_os = "android")))]
    let _ = rd;
}

async fn reader(
    mut rd: OwnedReadHalf,
    cfg: &SocketcandConfig,
    hub: &Hub,
    id: ParticipantId,
    ctl: mpsc::Sender<Ctl>,
) -> String {
    let mut split = Splitter::new();
    let mut buf = vec![0u8; 4096];
    let mut mode = Mode::NoBus;
    let mut frames = Vec::with_capacity(64);
    let mut replies = Vec::with_capacity(4);
    loop {
        let n = match rd.read(&mut buf).await {
            Ok(0) => return "closed by client".into(),
            Ok(n) => n,
            Err(e) => return format!("read: {e}"),
        };
        quickack(&rd);
        split.feed(&buf[..n], |m| match proto::parse(m) {
            Message::Send(f) if mode != Mode::NoBus => frames.push(f),
            Message::Echo => replies.push(Ctl::Reply("< echo >")),
            Message::Open(name) if mode == Mode::NoBus => {
                if name == cfg.channel {
                    mode = Mode::Bcm;
                    replies.push(Ctl::Reply("< ok >"));
                } else {
                    tracing::info!(name, "client asked for an unknown bus");
                    replies.push(Ctl::Reply("< error could not open bus >"));
                }
            }
            Message::RawMode if mode == Mode::Bcm => {
                mode = Mode::Raw;
                replies.push(Ctl::EnterRaw);
            }
            other => {
                let text = String::from_utf8_lossy(m);
                tracing::debug!(msg = %text.trim(), ?other, "ignored socketcand message");
            }
        });
        for r in replies.drain(..) {
            if ctl.send(r).await.is_err() {
                return "writer stopped".into();
            }
        }
        for f in frames.drain(..) {
            hub.publish(id, f).await;
        }
    }
}

async fn writer(
    mut wr: OwnedWriteHalf,
    cfg: &SocketcandConfig,
    hub: &Hub,
    id: ParticipantId,
    mut ctl: mpsc::Receiver<Ctl>,
) -> String {
    // `< hi >` alone: python-can compares one whole recv() with it.
    if let Err(why) = write(&mut wr, b"< hi >", cfg).await {
        return why;
    }
    let mut sub: Option<broadcast::Receiver<HubFrame>> = None;
    let mut out = String::with_capacity(4096);
    loop {
        tokio::select! {
            c = ctl.recv() => {
                let Some(c) = c else { return "reader stopped".into() };
                let msg = match c { Ctl::Reply(s) => s, Ctl::EnterRaw => "< ok >" };
                if let Err(why) = write(&mut wr, msg.as_bytes(), cfg).await {
                    return why;
                }
                if matches!(c, Ctl::EnterRaw) {
                    // Subscribe first, write later: frames of the grace
                    // window (e.g. the answer to a request a client sends
                    // right after `< ok >`) wait in the queue instead of
                    // being lost; the pause keeps `< ok >` alone in the
                    // client's first read (transport-feasibility §4.2).
                    sub = Some(hub.subscribe());
                    tokio::time::sleep(cfg.grace).await;
                }
            }
            m = recv_some(&mut sub) => {
                let Some(rx) = sub.as_mut() else { continue };
                out.clear();
                let mut next = m;
                // Batch what is already queued (up to 256 frames) into one write.
                for batched in 1.. {
                    match next {
                        Ok(f) => {
                            if f.from != id && !f.frame.is_rtr() {
                                proto::write_frame(&mut out, &f.frame, f.timestamp_us);
                            }
                        }
                        Err(broadcast::error::TryRecvError::Lagged(n)) => {
                            tracing::warn!(lost = n, "socketcand client too slow, disconnecting");
                            return format!("too slow: fell {n} frames behind");
                        }
                        Err(broadcast::error::TryRecvError::Closed) => return "hub closed".into(),
                        Err(broadcast::error::TryRecvError::Empty) => break,
                    }
                    if batched == 256 {
                        break;
                    }
                    next = rx.try_recv();
                }
                if !out.is_empty()
                    && let Err(why) = write(&mut wr, out.as_bytes(), cfg).await
                {
                    return why;
                }
            }
        }
    }
}

/// Writes all of `data` within the configured timeout.
async fn write(wr: &mut OwnedWriteHalf, data: &[u8], cfg: &SocketcandConfig) -> Result<(), String> {
    match tokio::time::timeout(cfg.write_timeout, wr.write_all(data)).await {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(format!("write: {e}")),
        Err(_) => Err(format!("client accepted nothing for {:?}", cfg.write_timeout)),
    }
}

/// The next hub frame, as a `try_recv`-style result; pending forever
/// before rawmode.
async fn recv_some(
    sub: &mut Option<broadcast::Receiver<HubFrame>>,
) -> Result<HubFrame, broadcast::error::TryRecvError> {
    use broadcast::error::{RecvError, TryRecvError};
    match sub {
        None => std::future::pending().await,
        Some(rx) => rx.recv().await.map_err(|e| match e {
            RecvError::Lagged(n) => TryRecvError::Lagged(n),
            RecvError::Closed => TryRecvError::Closed,
        }),
    }
}
