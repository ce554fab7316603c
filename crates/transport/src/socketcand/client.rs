//! socketcand client.

use std::io;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpStream, ToSocketAddrs};

use super::proto::{self, Message, Splitter};
use crate::handle::{CanBus, LinkEnd, Out, link};

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

/// Longest wait for the server's close after ours (`CanBus::close`).
const CLOSE_WAIT: Duration = Duration::from_secs(2);

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
                split.feed(&buf[..n], |m| deliver(&end, m));
                if end.user_gone() {
                    return;
                }
            }
            _ = end.up.to_user.closed(), if !user_sends => return,
            m = end.from_user.recv(), if user_sends => {
                let Some(mut m) = m else {
                    // Every sender is gone; keep receiving while the user reads.
                    user_sends = false;
                    if end.user_gone() { return; }
                    continue;
                };
                // Batch the frames already queued into one write; a flush
                // or close is answered once everything before it is written.
                out.clear();
                let control = loop {
                    match m {
                        Out::Frame(f) if f.is_rtr() => {
                            tracing::warn!(frame = %f, "socketcand cannot carry RTR frames: not sent");
                        }
                        Out::Frame(f) => proto::write_send(&mut out, &f),
                        other => break Some(other),
                    }
                    if out.len() >= 4096 {
                        break None;
                    }
                    match end.from_user.try_recv() {
                        Ok(next) => m = next,
                        Err(_) => break None,
                    }
                };
                if !out.is_empty()
                    && let Err(e) = stream.write_all(out.as_bytes()).await
                {
                    return end.fail(format!("socketcand write: {e}"));
                }
                match control {
                    None => {}
                    Some(Out::Flush(done)) => {
                        let _ = stream.flush().await;
                        let _ = done.send(());
                    }
                    Some(Out::Close(done)) => {
                        // Boxed: keeps the per-frame future small (the hub bench lost ~12 % without).
                        Box::pin(close(&mut stream, &mut split, &end, &mut buf)).await;
                        let _ = done.send(());
                        return end.fail("closed by the user");
                    }
                    Some(Out::Frame(_)) => {}
                }
            }
        }
    }
}

fn deliver(end: &LinkEnd, m: &[u8]) {
    match proto::parse(m) {
        Message::Frame(f, _) => end.deliver(f),
        Message::Echo | Message::Ok => {}
        other => tracing::debug!(?other, "ignored socketcand message"),
    }
}

/// Half-closes (FIN after the data written so far) and reads until the
/// server closes too: once it has, it has read and relayed every frame.
/// Closing with unread input would make the kernel send RST, which may
/// discard data still in flight.
async fn close(stream: &mut TcpStream, split: &mut Splitter, end: &LinkEnd, buf: &mut [u8]) {
    if stream.shutdown().await.is_err() {
        return;
    }
    let drain = async {
        loop {
            match stream.read(buf).await {
                Ok(0) | Err(_) => return,
                Ok(n) => split.feed(&buf[..n], |m| deliver(end, m)),
            }
        }
    };
    let _ = tokio::time::timeout(CLOSE_WAIT, drain).await;
}
