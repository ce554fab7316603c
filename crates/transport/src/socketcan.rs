//! Linux SocketCAN (`socketcan://can0`), through the `socketcan` crate's
//! tokio socket. Error frames are counted (`CanTx::bus_errors`), not
//! passed up as frames.

use std::io;

use drivebus_can::{CanId, Frame};
use socketcan::tokio::CanSocket;
use socketcan::{CanFrame, EmbeddedFrame, ExtendedId, Id, SocketOptions, StandardId};

use crate::handle::{CanBus, LinkEnd, Out, link};

/// Opens CAN interface `interface` (e.g. `can0`, `vcan0`) in raw mode.
/// Must be called inside a tokio runtime. Fails with EAFNOSUPPORT on
/// kernels without SocketCAN and ENODEV for an unknown interface.
pub fn open(interface: &str) -> io::Result<CanBus> {
    let sock = CanSocket::open(interface)?;
    // Error frames (bus errors, counters, bus-off) for the statistics.
    sock.set_error_filter_accept_all()?;
    let (bus, end) = link(true);
    end.up.reports_errors();
    tokio::spawn(run(sock, end));
    Ok(bus)
}

fn to_socketcan(f: &Frame) -> Option<CanFrame> {
    let id: Id = match f.id() {
        CanId::Standard(v) => StandardId::new(v)?.into(),
        CanId::Extended(v) => ExtendedId::new(v)?.into(),
    };
    if f.is_rtr() { CanFrame::new_remote(id, f.len()) } else { CanFrame::new(id, f.data()) }
}

fn from_socketcan(f: &CanFrame) -> Option<Frame> {
    if matches!(f, CanFrame::Error(_)) {
        return None;
    }
    let id = match EmbeddedFrame::id(f) {
        Id::Standard(s) => CanId::Standard(s.as_raw()),
        Id::Extended(e) => CanId::Extended(e.as_raw()),
    };
    if EmbeddedFrame::is_remote_frame(f) {
        Frame::try_remote(id, EmbeddedFrame::dlc(f).min(8) as u8).ok()
    } else {
        Frame::try_new(id, EmbeddedFrame::data(f)).ok()
    }
}

async fn run(sock: CanSocket, mut end: LinkEnd) {
    let mut user_sends = true;
    loop {
        tokio::select! {
            r = sock.read_frame() => match r {
                Ok(CanFrame::Error(e)) => end.up.error_frame(e.error_bits(), EmbeddedFrame::data(&e)),
                Ok(f) => {
                    if let Some(f) = from_socketcan(&f) {
                        end.deliver(f);
                    }
                }
                Err(e) => return end.fail(format!("SocketCAN read: {e}")),
            },
            _ = end.up.to_user.closed(), if !user_sends => return,
            m = end.from_user.recv(), if user_sends => match m {
                None => user_sends = false,
                Some(Out::Frame(f)) => {
                    let Some(cf) = to_socketcan(&f) else { continue };
                    if let Err(e) = sock.write_frame(cf).await {
                        return end.fail(format!("SocketCAN write: {e}"));
                    }
                }
                // A written frame is in the kernel's queue already.
                Some(Out::Flush(done)) => { let _ = done.send(()); }
                Some(Out::Close(done)) => {
                    let _ = done.send(());
                    return end.fail("closed by the user");
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip() {
        for f in [
            Frame::new(0x123, &[1, 2, 3]),
            Frame::remote(0x705, 1),
            Frame::try_new(CanId::Extended(0x1ABCDEF), &[]).unwrap(),
        ] {
            assert_eq!(from_socketcan(&to_socketcan(&f).unwrap()), Some(f));
        }
    }
}
