//! The adapter side of slcan, sans-IO: what an slcan USB adapter does with
//! the host's command lines. [`SlcanPty`](super::SlcanPty) runs it on a
//! pseudo-terminal.

use drivebus_can::Frame;

use super::codec::{self, LineError};

/// Version answered to `V` (hardware 1.0, software 1.3).
pub const VERSION: &[u8] = b"V1013\r";
/// Serial number answered to `N`.
pub const SERIAL: &[u8] = b"NDB01\r";

/// An emulated slcan adapter's state.
#[derive(Clone, Debug, Default)]
pub struct SlcanDevice {
    open: bool,
    listen_only: bool,
    timestamps: bool,
    bitrate: Option<u32>,
}

/// What one command line did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Nothing beyond the reply.
    None,
    /// Put this frame on the bus.
    Send(Frame),
    /// The channel was closed (`C`): pending bus frames are stale.
    Closed,
}

impl SlcanDevice {
    /// A closed adapter.
    pub fn new() -> Self {
        Self::default()
    }
    /// True between `O`/`L` and `C`: bus frames are forwarded to the host.
    pub fn is_open(&self) -> bool {
        self.open
    }
    /// The bit rate last set with `S<n>`.
    pub fn bitrate(&self) -> Option<u32> {
        self.bitrate
    }

    /// Handles one line from the host (without CR); appends the answer to
    /// `reply`. Answers CR for success and BEL for errors, like an adapter.
    /// python-can opens with `C`, `S6`, an empty line, `O`, `O`: all accepted.
    pub fn handle_line(&mut self, line: &[u8], reply: &mut Vec<u8>) -> Action {
        const OK: &[u8] = b"\r";
        const ERR: &[u8] = b"\x07";
        let (ans, action): (&[u8], Action) = match line {
            b"" => (OK, Action::None),
            b"C" => {
                self.open = false;
                (OK, Action::Closed)
            }
            // A repeated O is harmless (python-can sends two).
            b"O" | b"L" => {
                self.open = true;
                self.listen_only = line == b"L";
                (OK, Action::None)
            }
            [b'S', d] if !self.open => match codec::bitrate_of(*d) {
                Some(b) => {
                    self.bitrate = Some(b);
                    (OK, Action::None)
                }
                None => (ERR, Action::None),
            },
            [b's', rest @ ..] if !self.open && rest.len() == 4 && rest.iter().all(u8::is_ascii_hexdigit) => {
                (OK, Action::None)
            }
            b"V" => (VERSION, Action::None),
            b"N" => (SERIAL, Action::None),
            // Status flags: no error, no overrun.
            b"F" => (b"F00\r", Action::None),
            b"Z0" | b"Z1" => {
                self.timestamps = line == b"Z1";
                (OK, Action::None)
            }
            [b'M' | b'm', rest @ ..] if rest.len() == 8 && rest.iter().all(u8::is_ascii_hexdigit) => {
                (OK, Action::None)
            }
            [b't' | b'T' | b'r' | b'R', ..] => match codec::parse_frame(line) {
                Ok(f) if self.open && !self.listen_only => {
                    (if f.id().is_extended() { b"Z\r" } else { b"z\r" }, Action::Send(f))
                }
                Ok(_) | Err(LineError::NotAFrame | LineError::Malformed | LineError::BadId) => {
                    (ERR, Action::None)
                }
            },
            _ => (ERR, Action::None),
        };
        reply.extend_from_slice(ans);
        action
    }

    /// Appends a bus frame for the host if the channel is open; `now_ms` is
    /// used when timestamps are on (`Z1`).
    pub fn bus_frame(&self, frame: &Frame, now_ms: u64, out: &mut Vec<u8>) -> bool {
        if !self.open {
            return false;
        }
        let ts = self.timestamps.then_some((now_ms % 60_000) as u16);
        codec::encode_stamped(frame, ts, out);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn python_can_open_sequence() {
        let mut d = SlcanDevice::new();
        let mut r = Vec::new();
        for l in [&b"C"[..], b"S6", b"", b"O", b"O"] {
            d.handle_line(l, &mut r);
        }
        assert_eq!(r, b"\r\r\r\r\r");
        assert!(d.is_open());
        assert_eq!(d.bitrate(), Some(500_000));
    }

    #[test]
    fn frames_only_when_open() {
        let mut d = SlcanDevice::new();
        let mut r = Vec::new();
        assert_eq!(d.handle_line(b"t0800", &mut r), Action::None);
        assert_eq!(r, b"\x07");
        let mut out = Vec::new();
        assert!(!d.bus_frame(&Frame::new(1, &[]), 0, &mut out));
        d.handle_line(b"O", &mut r);
        r.clear();
        assert_eq!(d.handle_line(b"r7051", &mut r), Action::Send(Frame::remote(0x705, 1)));
        assert_eq!(
            d.handle_line(b"T000000010", &mut r),
            Action::Send(Frame::try_new(drivebus_can::CanId::Extended(1), &[]).unwrap())
        );
        assert_eq!(d.handle_line(b"t08", &mut r), Action::None);
        assert_eq!(r, b"z\rZ\r\x07");
        assert!(d.bus_frame(&Frame::remote(0x705, 1), 0, &mut out));
        assert_eq!(out, b"r7051\r");
        r.clear();
        for l in [&b"V"[..], b"N", b"F", b"S6", b"X", b"Z1"] {
            d.handle_line(l, &mut r);
        }
        assert_eq!(r, b"V1013\rNDB01\rF00\r\x07\x07\r");
        out.clear();
        d.bus_frame(&Frame::new(1, &[]), 61_234, &mut out);
        assert_eq!(out, b"t001004D2\r");
        assert_eq!(d.handle_line(b"C", &mut r), Action::Closed);
        assert!(!d.is_open());
    }
}
