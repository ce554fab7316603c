//! slcan adapter emulated on a pseudo-terminal (Unix).
//!
//! The slave side is what a host program opens as its "serial port"
//! (python-can `can.Bus(interface='slcan', channel=PATH)`, our
//! [`open_serial`](super::open_serial)). We keep our own slave fd open for
//! the emulator's lifetime: otherwise the master reads EIO whenever no
//! client has the slave open (between clients).

use std::fs::File;
use std::io::{self, Read, Write};
use std::os::fd::OwnedFd;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::sys::termios::{self, FlushArg, SetArg};
use tokio::io::unix::AsyncFd;
use tokio::task::JoinHandle;

use super::codec::{LineSplitter, Token};
use super::device::{Action, SlcanDevice};
use crate::handle::CanBus;

/// Bytes queued towards the pty before bus frames are left in the bus
/// receiver (which then counts overruns): a host that stops reading must
/// not make the emulator grow without bound.
const OUT_MAX: usize = 16 * 1024;

/// A running slcan adapter emulator on a pty; stops when dropped.
pub struct SlcanPty {
    path: PathBuf,
    task: JoinHandle<()>,
}

impl SlcanPty {
    /// Opens a pty, puts its slave in raw mode and relays between it and
    /// `bus` (for example [`Hub::attach`](crate::Hub::attach)). Returns at
    /// once; [`path`](SlcanPty::path) is the device to open.
    pub fn spawn(bus: CanBus) -> io::Result<SlcanPty> {
        let pty = nix::pty::openpty(None, None).map_err(io::Error::from)?;
        let mut t = termios::tcgetattr(&pty.slave).map_err(io::Error::from)?;
        termios::cfmakeraw(&mut t);
        termios::tcsetattr(&pty.slave, SetArg::TCSANOW, &t).map_err(io::Error::from)?;
        let path = nix::unistd::ttyname(&pty.slave).map_err(io::Error::from)?;
        let flags =
            OFlag::from_bits_truncate(fcntl(&pty.master, FcntlArg::F_GETFL).map_err(io::Error::from)?);
        fcntl(&pty.master, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK)).map_err(io::Error::from)?;
        // `AsyncFd::new` is deprecated for types whose fd could be closed
        // or swapped behind the registration; a `File` we own outright keeps
        // its fd until the `AsyncFd` drops, so it is sound here, and the
        // replacement (`register`) is `unsafe`, which this workspace denies.
        #[allow(deprecated)]
        let master = AsyncFd::new(File::from(pty.master))?;
        tracing::info!(path = %path.display(), "slcan pty ready");
        let task = tokio::spawn(async move {
            if let Err(e) = run(master, pty.slave, bus).await {
                tracing::warn!(error = %e, "slcan pty stopped");
            }
        });
        Ok(SlcanPty { path, task })
    }

    /// The slave device path (e.g. `/dev/pts/3`).
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for SlcanPty {
    fn drop(&mut self) {
        self.task.abort();
    }
}

fn now_ms() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64)
}

async fn run(master: AsyncFd<File>, slave: OwnedFd, bus: CanBus) -> io::Result<()> {
    let (tx, mut rx) = bus.split();
    let mut dev = SlcanDevice::new();
    let mut split = LineSplitter::new();
    let mut buf = [0u8; 1024];
    let mut out: Vec<u8> = Vec::with_capacity(OUT_MAX);
    let mut to_bus = Vec::new();
    loop {
        tokio::select! {
            r = master.readable() => {
                let mut guard = r?;
                let n = match guard.try_io(|f| f.get_ref().read(&mut buf)) {
                    Ok(Ok(n)) => n,
                    Ok(Err(e)) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Ok(Err(e)) => return Err(e),
                    Err(_would_block) => continue,
                };
                let mut closed = false;
                split.feed(&buf[..n], |t| match t {
                    Token::Line(l) => {
                        // Replies are tiny; cap them anyway against a flood
                        // of commands from a host that never reads.
                        let mut reply = Vec::new();
                        match dev.handle_line(l, &mut reply) {
                            Action::Send(f) => to_bus.push(f),
                            Action::Closed => {
                                out.clear();
                                closed = true;
                            }
                            Action::None => {}
                        }
                        if out.len() < 2 * OUT_MAX {
                            out.extend_from_slice(&reply);
                        }
                    }
                    Token::Bell => {}
                });
                if closed {
                    // Stale frames the last host did not read must not reach
                    // the next one.
                    let _ = termios::tcflush(&slave, FlushArg::TCIFLUSH);
                }
                for f in to_bus.drain(..) {
                    tx.send(f).await?;
                }
            }
            f = rx.recv(), if out.len() < OUT_MAX => {
                let f = f?;
                dev.bus_frame(&f, now_ms(), &mut out);
            }
            w = master.writable(), if !out.is_empty() => {
                let mut guard = w?;
                match guard.try_io(|f| f.get_ref().write(&out)) {
                    Ok(Ok(n)) => { out.drain(..n); }
                    Ok(Err(e)) if e.kind() == io::ErrorKind::Interrupted => {}
                    Ok(Err(e)) => return Err(e),
                    Err(_would_block) => {}
                }
            }
        }
    }
}
