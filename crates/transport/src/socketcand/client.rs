//! socketcand client.

use std::io;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpStream, ToSocketAddrs};

use super::proto::{self, Message, Splitter};
use crate::handle::{CanBus, LinkEnd, link};

/// Longest wait for each handshake answer.
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);

fn proto_err(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg)
}

/// An owned copy of a message, for the handshake.
#[derive(Debug, PartialEq, Eq)]
enum Owned {
    Hi,
    Ok,
    Error(String),
    Other(String),
}

/// Reads until one message arrives; later messages stay in `split`'s
/// output queue `rest` (frames may follow the last `< ok >`).
async fn next_message(
    stream: &mut TcpStream,
    split: &mut Splitter,
    rest: &mut Vec<Vec<u8>>,
) -> io::Result<Owned> {
    let mut buf = [0u8; 1024];
    let fut = async {
        while rest.is_empty() {
            let n = stream.read(&mut buf).await?;
            if n == 0 {
                return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "server closed the connection"));
            }
            split.feed(&buf[..n], |m| rest.push(m.to_vec()));
        }
        let m = rest.remove(0);
        Ok(match proto::parse(&m) {
            Message::Hi => Owned::Hi,
            Message::Ok => Owned::Ok,
            Message::Error(e) => Owned::Error(e.to_owned()),
            _ => Owned::Other(String::from_utf8_lossy(&m).trim().to_owned()),
        })
    };
    tokio::time::timeout(HANDSHAKE_TIMEOUT, fut)
        .await
        .map_err(|_| io::Error::new(io::ErrorKind::TimedOut, "socketcand handshake timed out"))?
}

async fn expect_ok(
    stream: &mut TcpStream,
    split: &mut Splitter,
    rest: &mut Vec<Vec<u8>>,
    after: &str,
) -> io::Result<()> {
    match next_message(stream, split, rest).await? {
        Owned::Ok => Ok(()),
        Owned::Error(e) => Err(proto_err(format!("server refused {after}: {e}"))),
        other => Err(proto_err(format!("expected < ok > after {after}, got {other:?}"))),
    }
}

/// Connects to a socketcand server, opens bus `channel` in raw mode and
/// returns the handle. The connection runs on a background task that ends
/// when the handle is dropped.
pub async fn connect(addr: impl ToSocketAddrs, channel: &str) -> io::Result<CanBus> {
    if channel.is_empty() || channel.contains(|c: char| c.is_whitespace() || c == '<' || c == '>') {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, format!("bad channel name `{channel}`")));
    }
    let mut stream = TcpStream::connect(addr).await?;
    stream.set_nodelay(true)?;
    let mut split = Splitter::new();
    let mut rest = Vec::new();
    match next_message(&mut stream, &mut split, &mut rest).await? {
        Owned::Hi => {}
        other => return Err(proto_err(format!("expected < hi >, got {other:?}"))),
    }
    stream.write_all(format!("< open {channel} >").as_bytes()).await?;
    expect_ok(&mut stream, &mut split, &mut rest, &format!("< open {channel} >")).await?;
    stream.write_all(b"< rawmode >").await?;
    expect_ok(&mut stream, &mut split, &mut rest, "< rawmode >").await?;
    let (bus, end) = link(false);
    for m in &rest {
        if let Message::Frame(f, _) = proto::parse(m) {
            end.deliver(f);
        }
    }
    tokio::spawn(run(stream, split, end));
    Ok(bus)
}

/// Relays between the socket and the handle until either side is gone.
async fn run(mut stream: TcpStream, mut split: Splitter, mut end: LinkEnd) {
    let mut buf = vec![0u8; 4096];
    let mut out = String::with_capacity(256);
    let mut user_sends = true;
    loop {
        tokio::select! {
            r = stream.read(&mut buf) => {
                let n = match r {
                    Ok(0) => return end.fail("socketcand server closed the connection"),
                    Ok(n) => n,
                    Err(e) => return end.fail(format!("socketcand read: {e}")),
                };
                #[cfg(any(target_os = "linux", target_os = "android"))]
                let _ = socket2::SockRef::from(&stream).set_tcp_quickack(true);
                split.feed(&buf[..n], |m| match proto::parse(m) {
                    Message::Frame(f, _) => end.deliver(f),
                    Message::Echo | Message::Ok => {}
                    other => tracing::debug!(?other, "ignored socketcand message"),
                });
                if end.user_gone() {
                    return;
                }
            }
            _ = end.up.to_user.closed(), if !user_sends => return,
            f = end.from_user.recv(), if user_sends => {
                let Some(f) = f else {
                    // Every sender is gone; keep receiving while the user reads.
                    user_sends = false;
                    if end.user_gone() { return; }
                    continue;
                };
                if f.is_rtr() {
                    tracing::warn!(frame = %f, "socketcand cannot carry RTR frames: not sent");
                    continue;
                }
                out.clear();
                proto::write_send(&mut out, &f);
                // Batch whatever else is queued.
                while out.len() < 4096 {
                    match end.from_user.try_recv() {
                        Ok(f) if !f.is_rtr() => proto::write_send(&mut out, &f),
                        Ok(_) => {}
                        Err(_) => break,
                    }
                }
                if let Err(e) = stream.write_all(out.as_bytes()).await {
                    return end.fail(format!("socketcand write: {e}"));
                }
            }
        }
    }
}
