//! slcan host side: talks to an adapter over a serial device or TCP.
//!
//! Serial I/O uses the `serialport` crate (portable: Linux, macOS, Windows)
//! on two dedicated threads, since it is blocking: a reader that polls with
//! a short timeout (so it notices a dropped handle) and a writer fed by the
//! handle's channel. serialport opens ptys fine (it skips DTR on them), so
//! the pty emulator tests exactly this code.

use std::io::{self, Read, Write};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpStream, ToSocketAddrs};

use super::codec::{self, LineSplitter, Token};
use crate::handle::{CanBus, Out, Uplink, link};

/// Reader poll period: how soon a dropped handle releases the device.
const POLL: Duration = Duration::from_millis(50);

/// The host's open sequence: close, bit rate, open.
fn open_sequence(bitrate: Option<u32>) -> io::Result<Vec<u8>> {
    let mut v = b"C\r".to_vec();
    if let Some(b) = bitrate {
        let cmd = codec::bitrate_command(b).ok_or_else(|| {
            io::Error::new(io::ErrorKind::InvalidInput, format!("no slcan command for bitrate {b}"))
        })?;
        v.extend_from_slice(cmd.as_bytes());
        v.push(b'\r');
    }
    v.extend_from_slice(b"O\r");
    Ok(v)
}

/// Handles one token from the adapter: frames go up, answers are ignored.
fn on_token(tok: Token<'_>, up: &Uplink) {
    match tok {
        Token::Line(l @ [b't' | b'T' | b'r' | b'R', ..]) => match codec::parse_frame(l) {
            Ok(f) => up.deliver(f),
            Err(e) => tracing::warn!(line = %String::from_utf8_lossy(l), ?e, "malformed slcan frame ignored"),
        },
        // CR, `z`, `Z`: acknowledgements; anything else (V/N/F answers) is not ours.
        Token::Line(l) => {
            if !matches!(l, b"" | b"z" | b"Z") {
                tracing::debug!(line = %String::from_utf8_lossy(l), "slcan line ignored");
            }
        }
        Token::Bell => tracing::debug!("slcan adapter answered BEL (error)"),
    }
}

/// Encodes `first` and the frames already queued behind it into `out`;
/// returns the flush/close request that ended the batch, if any.
fn encode_batch(first: Out, rx: &mut tokio::sync::mpsc::Receiver<Out>, out: &mut Vec<u8>) -> Option<Out> {
    out.clear();
    let mut m = first;
    loop {
        match m {
            Out::Frame(f) => codec::encode(&f, out),
            control => return Some(control),
        }
        if out.len() >= 1024 {
            return None;
        }
        match rx.try_recv() {
            Ok(next) => m = next,
            Err(_) => return None,
        }
    }
}

/// Opens an slcan adapter on serial device `path` at line speed `baud`,
/// sets `bitrate` (if given) and opens the CAN channel.
pub async fn open_serial(path: &str, bitrate: Option<u32>, baud: u32) -> io::Result<CanBus> {
    let init = open_sequence(bitrate)?;
    let path = path.to_owned();
    let port = tokio::task::spawn_blocking(move || -> io::Result<_> {
        let mut port = serialport::new(&path, baud).timeout(POLL).open().map_err(io::Error::from)?;
        port.write_all(&init)?;
        port.flush()?;
        Ok(port)
    })
    .await
    .map_err(io::Error::other)??;
    let mut wport = port.try_clone().map_err(io::Error::from)?;
    let (bus, end) = link(true);
    let up = end.up.clone();
    let mut from_user = end.from_user;
    // Set by `close`; the reader then releases the port (serialport holds
    // an exclusive lock on it) and says so by dropping `released`.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (released, rx_gone) = std::sync::mpsc::channel::<()>();
    let stop_rx = stop.clone();
    std::thread::Builder::new().name("slcan-rx".into()).spawn(move || {
        let _released = released;
        // Declared after `_released`, so dropped before it: the port (and
        // its lock) is closed before `close` hears it was released. Left
        // in the closure, it would be dropped after the closure's locals.
        let mut port = port;
        let mut split = LineSplitter::new();
        let mut buf = [0u8; 1024];
        loop {
            if stop_rx.load(std::sync::atomic::Ordering::Acquire) {
                return;
            }
            if up.to_user.is_closed() {
                // The user is gone: close the CAN channel, release the port.
                let _ = port.write_all(b"C\r");
                return;
            }
            match port.read(&mut buf) {
                Ok(0) => return up.fail("slcan device closed"),
                Ok(n) => split.feed(&buf[..n], |t| on_token(t, &up)),
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::TimedOut | io::ErrorKind::Interrupted | io::ErrorKind::WouldBlock
                    ) => {}
                Err(e) => return up.fail(format!("slcan read: {e}")),
            }
        }
    })?;
    let up = end.up;
    std::thread::Builder::new().name("slcan-tx".into()).spawn(move || {
        let mut out = Vec::with_capacity(1100);
        while let Some(m) = from_user.blocking_recv() {
            let control = encode_batch(m, &mut from_user, &mut out);
            if let Err(e) = wport.write_all(&out) {
                return up.fail(format!("slcan write: {e}"));
            }
            match control {
                None | Some(Out::Frame(_)) => {}
                // `flush` waits until the device has taken the bytes (tcdrain).
                Some(Out::Flush(done)) => {
                    let _ = wport.flush();
                    let _ = done.send(());
                }
                Some(Out::Close(done)) => {
                    // The frames first, then close the CAN channel: an adapter
                    // drops what arrives after `C`.
                    let _ = wport.flush();
                    let _ = wport.write_all(b"C\r");
                    let _ = wport.flush();
                    stop.store(true, std::sync::atomic::Ordering::Release);
                    drop(wport);
                    // The reader notices within one poll period when it is
                    // scheduled; on a loaded host that can take much longer,
                    // and the port stays locked until it lets go (a command
                    // run right after this one could not open it).
                    let _ = rx_gone.recv_timeout(Duration::from_secs(10));
                    let _ = done.send(());
                    return up.fail("closed by the user");
                }
            }
        }
    })?;
    Ok(bus)
}

/// Connects to an slcan adapter reachable as a TCP byte stream (the
/// pyserial `socket://` convention), sets `bitrate` and opens the channel.
pub async fn connect_tcp(addr: impl ToSocketAddrs, bitrate: Option<u32>) -> io::Result<CanBus> {
    let init = open_sequence(bitrate)?;
    let mut stream = TcpStream::connect(addr).await?;
    stream.set_nodelay(true)?;
    stream.write_all(&init).await?;
    let (bus, mut end) = link(true);
    tokio::spawn(async move {
        let mut split = LineSplitter::new();
        let mut buf = [0u8; 2048];
        let mut out = Vec::with_capacity(1100);
        let mut user_sends = true;
        loop {
            tokio::select! {
                r = stream.read(&mut buf) => match r {
                    Ok(0) => return end.fail("slcan peer closed the connection"),
                    Ok(n) => split.feed(&buf[..n], |t| on_token(t, &end.up)),
                    Err(e) => return end.fail(format!("slcan read: {e}")),
                },
                _ = end.up.to_user.closed(), if !user_sends => {
                    let _ = stream.write_all(b"C\r").await;
                    return;
                }
                m = end.from_user.recv(), if user_sends => match m {
                    None => user_sends = false,
                    Some(m) => {
                        let control = encode_batch(m, &mut end.from_user, &mut out);
                        if let Err(e) = stream.write_all(&out).await {
                            return end.fail(format!("slcan write: {e}"));
                        }
                        match control {
                            None | Some(Out::Frame(_)) => {}
                            Some(Out::Flush(done)) => {
                                let _ = stream.flush().await;
                                let _ = done.send(());
                            }
                            Some(Out::Close(done)) => {
                                let _ = stream.write_all(b"C\r").await;
                                let _ = stream.shutdown().await;
                                let _ = done.send(());
                                return end.fail("closed by the user");
                            }
                        }
                    }
                },
            }
        }
    });
    Ok(bus)
}
