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
use crate::handle::{CanBus, Uplink, link};

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

fn encode_batch(
    first: drivebus_can::Frame,
    rx: &mut tokio::sync::mpsc::Receiver<drivebus_can::Frame>,
    out: &mut Vec<u8>,
) {
    out.clear();
    codec::encode(&first, out);
    while out.len() < 1024 {
        match rx.try_recv() {
            Ok(f) => codec::encode(&f, out),
            Err(_) => break,
        }
    }
}

/// Opens an slcan adapter on serial device `path` at line speed `baud`,
/// sets `bitrate` (if given) and opens the CAN channel.
pub async fn open_serial(path: &str, bitrate: Option<u32>, baud: u32) -> io::Result<CanBus> {
    let init = open_sequence(bitrate)?;
    let path = path.to_owned();
    let mut port = tokio::task::spawn_blocking(move || -> io::Result<_> {
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
    std::thread::Builder::new().name("slcan-rx".into()).spawn(move || {
        let mut split = LineSplitter::new();
        let mut buf = [0u8; 1024];
        loop {
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
        while let Some(f) = from_user.blocking_recv() {
            encode_batch(f, &mut from_user, &mut out);
            if let Err(e) = wport.write_all(&out) {
                return up.fail(format!("slcan write: {e}"));
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
                f = end.from_user.recv(), if user_sends => match f {
                    None => user_sends = false,
                    Some(f) => {
                        encode_batch(f, &mut end.from_user, &mut out);
                        if let Err(e) = stream.write_all(&out).await {
                            return end.fail(format!("slcan write: {e}"));
                        }
                    }
                },
            }
        }
    });
    Ok(bus)
}
