//! FoE: file access over EtherCAT (ETG.1000.6, FoE).
//!
//! Every FoE mailbox is an opcode byte, a reserved byte, a 32-bit field
//! (password of a request, packet number of DATA/ACK, error code of ERR;
//! for BUSY two UNSIGNED16: done and entire) and the data (file name,
//! file bytes, error text). Opcodes: RRQ 1, WRQ 2, DATA 3, ACK 4, ERR 5,
//! BUSY 6.
//!
//! Writing a file (master to device): WRQ → ACK 0, DATA n → ACK n, ...; a
//! DATA shorter than the mailbox allows (SM0 length − 12) is the last, so
//! a file of an exact multiple ends with an empty DATA. Reading: RRQ →
//! DATA 1, ACK 1 → DATA 2, ...; the last DATA is shorter than SM1
//! length − 12 and its ACK ends the transfer.
//!
//! What a file is, who may send it and where its bytes go is the device's
//! decision, through [`FileHandler`]. The handler may answer BUSY (a flash
//! being erased or written): the packet is then not taken and the master
//! sends it again, as SOEM's `ecx_FOEwrite` does; after the last packet a
//! BUSY from [`FileHandler::finish_write`] is repeated until the device
//! reports it ready.
//!
//! Choices, each covered by a test:
//! - A DATA repeating the packet just acknowledged is acknowledged again
//!   (the master lost our ACK); any other wrong number ends the transfer
//!   with 0x8005.
//! - The master's ERR ends the transfer without an answer.
//! - A new RRQ/WRQ ends a running transfer and starts the new one.
//! - A timeout between two packets ends the transfer silently.

use crate::AlState;
use crate::coe::Out;
use crate::mailbox::{MailboxErrorCode, MailboxType, Put};
use drivebus_base::{Duration, Instant};

/// FoE header in front of the data.
pub const FOE_HEADER_LEN: usize = 6;

/// FoE opcodes.
pub mod opcode {
    /// Read request (master reads a file from the device).
    pub const RRQ: u8 = 1;
    /// Write request (master writes a file to the device).
    pub const WRQ: u8 = 2;
    /// File data.
    pub const DATA: u8 = 3;
    /// Acknowledge of a DATA packet.
    pub const ACK: u8 = 4;
    /// Error.
    pub const ERR: u8 = 5;
    /// Busy: the device cannot take the packet now.
    pub const BUSY: u8 = 6;
}

/// An FoE error code (ERR packet).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct FoeError(pub u32);

macro_rules! foe_errors {
    ($($name:ident = $code:expr, $text:expr;)*) => {
        impl FoeError {
            $(#[doc = $text] pub const $name: FoeError = FoeError($code);)*

            /// The standard meaning, or `None` for a vendor code.
            pub fn description(self) -> Option<&'static str> {
                match self.0 {
                    $($code => Some($text),)*
                    _ => None,
                }
            }
        }
    };
}

foe_errors! {
    NOT_DEFINED = 0x8000, "Not defined";
    NOT_FOUND = 0x8001, "Not found";
    ACCESS_DENIED = 0x8002, "Access denied";
    DISK_FULL = 0x8003, "Disk full";
    ILLEGAL = 0x8004, "Illegal";
    PACKET_NUMBER_WRONG = 0x8005, "Packet number wrong";
    ALREADY_EXISTS = 0x8006, "Already exists";
    NO_USER = 0x8007, "No user";
    BOOTSTRAP_ONLY = 0x8008, "Bootstrap only";
    NOT_BOOTSTRAP = 0x8009, "Not bootstrap";
    NO_RIGHTS = 0x800A, "No rights";
    PROGRAM_ERROR = 0x800B, "Program error";
}

impl core::fmt::Debug for FoeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "FoeError({:#06x}", self.0)?;
        match self.description() {
            Some(t) => write!(f, " {t})"),
            None => f.write_str(")"),
        }
    }
}

/// What the device says to a packet or to the end of a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoeProgress {
    /// Taken (the data, or the finished file).
    Ready,
    /// Not now: answered with BUSY (`done` of `entire`, e.g. percent); the
    /// master repeats the packet.
    Busy {
        /// Work done.
        done: u16,
        /// Work in all.
        entire: u16,
    },
}

/// How an accepted transfer ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoeEnd {
    /// Written file finished, or read file acknowledged to the end.
    Completed,
    /// The master sent ERR with this code.
    AbortedByMaster(u32),
    /// Ended with this error (sent to the master in an ERR).
    Error(FoeError),
    /// No packet within the FoE timeout.
    Timeout,
    /// Replaced by a new request, or the mailbox was reset.
    Reset,
}

/// The device's file policy and storage.
///
/// `begin_*` decide from the name (trailing NUL bytes removed), the
/// password and the ESM state whether a transfer may start; a refusal is
/// sent as ERR with its code. Once a `begin_*` returned `Ok`, [`end`] is
/// called exactly once for that transfer.
///
/// [`end`]: FileHandler::end
pub trait FileHandler {
    /// False: FoE is not offered (requests get a mailbox error,
    /// "unsupported protocol").
    fn supported(&self) -> bool {
        true
    }
    /// A write request (master → device).
    fn begin_write(
        &mut self,
        name: &[u8],
        password: u32,
        state: AlState,
        now: Instant,
    ) -> Result<(), FoeError>;
    /// The next `data` of the file, at byte `offset`. `Busy` leaves it
    /// untaken: the master sends the same packet again.
    fn write(&mut self, offset: u32, data: &[u8], now: Instant) -> Result<FoeProgress, FoeError>;
    /// The last packet was taken: finish the file (flash it, check it).
    /// `Busy` is sent to the master and asked again when it repeats the
    /// last packet.
    fn finish_write(&mut self, now: Instant) -> Result<FoeProgress, FoeError>;
    /// A read request (device → master). The default knows no files.
    fn begin_read(
        &mut self,
        name: &[u8],
        password: u32,
        state: AlState,
        now: Instant,
    ) -> Result<(), FoeError> {
        let _ = (name, password, state, now);
        Err(FoeError::NOT_FOUND)
    }
    /// Fill `buf` with file bytes from `offset`; fewer than `buf.len()`
    /// marks the end of the file.
    fn read(&mut self, offset: u32, buf: &mut [u8], now: Instant) -> Result<usize, FoeError> {
        let _ = (offset, buf, now);
        Err(FoeError::ILLEGAL)
    }
    /// The transfer is over.
    fn end(&mut self, how: FoeEnd) {
        let _ = how;
    }
}

/// A device without FoE.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFiles;

impl FileHandler for NoFiles {
    fn supported(&self) -> bool {
        false
    }
    fn begin_write(&mut self, _: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        Err(FoeError::ACCESS_DENIED)
    }
    fn write(&mut self, _: u32, _: &[u8], _: Instant) -> Result<FoeProgress, FoeError> {
        Err(FoeError::ILLEGAL)
    }
    fn finish_write(&mut self, _: Instant) -> Result<FoeProgress, FoeError> {
        Err(FoeError::ILLEGAL)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    /// Receiving: `packet` is the last one taken, `offset` the bytes so far;
    /// `finishing` once the last packet was taken and the device is busy.
    Write {
        packet: u32,
        offset: u32,
        finishing: bool,
    },
    /// Sending: `packet` is the last DATA sent; `last` if it ended the file.
    Read {
        packet: u32,
        offset: u32,
        last: bool,
    },
}

/// The FoE protocol machine.
#[derive(Clone, Debug)]
pub(crate) struct FoeServer {
    state: State,
    deadline: Instant,
    pub(crate) timeout: Duration,
}

fn trim_nul(name: &[u8]) -> &[u8] {
    let end = name.iter().rposition(|&b| b != 0).map_or(0, |i| i + 1);
    &name[..end]
}

fn send_ack(out: &mut Out<'_>, packet: u32) {
    let w = out.q.begin();
    w.extend_from_slice(&[opcode::ACK, 0]);
    w.put_u32(packet);
    out.q.commit(MailboxType::Foe);
}

fn send_busy(out: &mut Out<'_>, done: u16, entire: u16) {
    let w = out.q.begin();
    w.extend_from_slice(&[opcode::BUSY, 0]);
    w.put_u16(done);
    w.put_u16(entire);
    out.q.commit(MailboxType::Foe);
}

fn send_err(out: &mut Out<'_>, e: FoeError) {
    let limit = crate::mailbox::HEADER_LEN + out.cap;
    let w = out.q.begin();
    w.extend_from_slice(&[opcode::ERR, 0]);
    w.put_u32(e.0);
    let text = e.description().unwrap_or("").as_bytes();
    w.extend_from_slice(&text[..text.len().min(limit.saturating_sub(w.len()))]);
    out.q.commit(MailboxType::Foe);
}

impl FoeServer {
    pub(crate) fn new(timeout: Duration) -> Self {
        FoeServer { state: State::Idle, deadline: Instant::ZERO, timeout }
    }

    pub(crate) fn is_idle(&self) -> bool {
        self.state == State::Idle
    }

    pub(crate) fn deadline(&self) -> Option<Instant> {
        (!self.is_idle()).then_some(self.deadline)
    }

    /// End a running transfer, telling the handler.
    pub(crate) fn end<F: FileHandler + ?Sized>(&mut self, files: &mut F, how: FoeEnd) {
        if self.state != State::Idle {
            self.state = State::Idle;
            files.end(how);
        }
    }

    /// End a transfer whose deadline has passed.
    pub(crate) fn expire<F: FileHandler + ?Sized>(&mut self, now: Instant, files: &mut F) {
        if !self.is_idle() && now >= self.deadline {
            self.end(files, FoeEnd::Timeout);
        }
    }

    /// One FoE mailbox. `rx_cap` is the service data a request may carry
    /// (SM0 length − 6), which sets the size of a full DATA packet.
    pub(crate) fn handle<F: FileHandler + ?Sized>(
        &mut self,
        body: &[u8],
        now: Instant,
        esm: AlState,
        rx_cap: usize,
        files: &mut F,
        out: &mut Out<'_>,
    ) {
        self.expire(now, files);
        let Some(head) = body.first_chunk::<FOE_HEADER_LEN>() else {
            out.q.push_error(MailboxErrorCode::SIZE_TOO_SHORT);
            return;
        };
        let word = u32::from_le_bytes([head[2], head[3], head[4], head[5]]);
        let data = &body[FOE_HEADER_LEN..];
        match (head[0], self.state) {
            (opcode::WRQ, _) => {
                self.end(files, FoeEnd::Reset);
                match files.begin_write(trim_nul(data), word, esm, now) {
                    Ok(()) => {
                        self.state = State::Write { packet: 0, offset: 0, finishing: false };
                        self.deadline = now + self.timeout;
                        send_ack(out, 0);
                    }
                    Err(e) => send_err(out, e),
                }
            }
            (opcode::RRQ, _) => {
                self.end(files, FoeEnd::Reset);
                match files.begin_read(trim_nul(data), word, esm, now) {
                    Ok(()) => {
                        self.state = State::Read { packet: 0, offset: 0, last: false };
                        self.send_data(now, files, out);
                    }
                    Err(e) => send_err(out, e),
                }
            }
            (opcode::DATA, State::Write { packet, offset, finishing }) => {
                let full = rx_cap.saturating_sub(FOE_HEADER_LEN);
                self.data(word, data, data.len() < full, (packet, offset, finishing), now, files, out);
            }
            (opcode::ACK, State::Read { packet, last, .. }) => {
                if word != packet {
                    self.fail(files, out, FoeError::PACKET_NUMBER_WRONG);
                } else if last {
                    self.end(files, FoeEnd::Completed);
                } else {
                    self.send_data(now, files, out);
                }
            }
            (opcode::ERR, _) => self.end(files, FoeEnd::AbortedByMaster(word)),
            (opcode::DATA | opcode::ACK | opcode::BUSY, _) => self.fail(files, out, FoeError::ILLEGAL),
            _ => {
                out.q.push_error(MailboxErrorCode::SERVICE_NOT_SUPPORTED);
            }
        }
    }

    /// End the transfer (if any) with `e` and tell the master.
    fn fail<F: FileHandler + ?Sized>(&mut self, files: &mut F, out: &mut Out<'_>, e: FoeError) {
        self.end(files, FoeEnd::Error(e));
        send_err(out, e);
    }

    /// A DATA packet during a write.
    #[allow(clippy::too_many_arguments)]
    fn data<F: FileHandler + ?Sized>(
        &mut self,
        n: u32,
        data: &[u8],
        last: bool,
        (packet, offset, finishing): (u32, u32, bool),
        now: Instant,
        files: &mut F,
        out: &mut Out<'_>,
    ) {
        self.deadline = now + self.timeout;
        if finishing {
            if n == packet {
                return self.finish(packet, files, now, out);
            }
            return self.fail(files, out, FoeError::PACKET_NUMBER_WRONG);
        }
        if n == packet && n != 0 {
            // Our ACK was lost and the master sent the packet again.
            return send_ack(out, n);
        }
        if n != packet.wrapping_add(1) {
            return self.fail(files, out, FoeError::PACKET_NUMBER_WRONG);
        }
        match files.write(offset, data, now) {
            Err(e) => self.fail(files, out, e),
            Ok(FoeProgress::Busy { done, entire }) => send_busy(out, done, entire),
            Ok(FoeProgress::Ready) => {
                let offset = offset.saturating_add(data.len() as u32);
                self.state = State::Write { packet: n, offset, finishing: last };
                if last {
                    self.finish(n, files, now, out);
                } else {
                    send_ack(out, n);
                }
            }
        }
    }

    /// The last packet is in: ask the device to finish the file.
    fn finish<F: FileHandler + ?Sized>(
        &mut self,
        packet: u32,
        files: &mut F,
        now: Instant,
        out: &mut Out<'_>,
    ) {
        match files.finish_write(now) {
            Ok(FoeProgress::Ready) => {
                self.end(files, FoeEnd::Completed);
                send_ack(out, packet);
            }
            Ok(FoeProgress::Busy { done, entire }) => send_busy(out, done, entire),
            Err(e) => self.fail(files, out, e),
        }
    }

    /// Send the next DATA of a read.
    fn send_data<F: FileHandler + ?Sized>(&mut self, now: Instant, files: &mut F, out: &mut Out<'_>) {
        let State::Read { packet, offset, .. } = self.state else {
            return;
        };
        let full = out.cap.saturating_sub(FOE_HEADER_LEN);
        let packet = packet.wrapping_add(1);
        let w = out.q.begin();
        w.extend_from_slice(&[opcode::DATA, 0]);
        w.put_u32(packet);
        let start = w.len();
        // The file bytes go straight into the response buffer.
        w.resize(start + full, 0);
        match files.read(offset, &mut w[start..], now) {
            Ok(k) => {
                let k = k.min(full);
                w.truncate(start + k);
                out.q.commit(MailboxType::Foe);
                let offset = offset.saturating_add(k as u32);
                self.state = State::Read { packet, offset, last: k < full };
                self.deadline = now + self.timeout;
            }
            // The slot was not committed: `send_err` starts it over.
            Err(e) => self.fail(files, out, e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mailbox::ResponseQueue;
    use alloc::vec::Vec;

    #[derive(Default)]
    struct Keep(Vec<u8>, Vec<FoeEnd>);
    impl FileHandler for Keep {
        fn begin_write(&mut self, name: &[u8], pw: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
            if name == b"ok" && pw == 7 { Ok(()) } else { Err(FoeError::NO_RIGHTS) }
        }
        fn write(&mut self, _: u32, data: &[u8], _: Instant) -> Result<FoeProgress, FoeError> {
            self.0.extend_from_slice(data);
            Ok(FoeProgress::Ready)
        }
        fn finish_write(&mut self, _: Instant) -> Result<FoeProgress, FoeError> {
            Ok(FoeProgress::Ready)
        }
        fn end(&mut self, how: FoeEnd) {
            self.1.push(how);
        }
    }

    fn run(s: &mut FoeServer, k: &mut Keep, body: &[u8]) -> Vec<u8> {
        let mut q = ResponseQueue::new(4, 32);
        s.handle(body, Instant::ZERO, AlState::PreOp, 26, k, &mut Out { q: &mut q, cap: 26 });
        let mut m = Vec::new();
        q.pop_into(&mut m);
        m.get(6..).map(<[u8]>::to_vec).unwrap_or_default()
    }

    #[test]
    fn write_in_two_packets() {
        let (mut s, mut k) = (FoeServer::new(Duration::from_secs(1)), Keep::default());
        // Name with a trailing NUL, as some masters send it.
        assert_eq!(run(&mut s, &mut k, &[2, 0, 7, 0, 0, 0, b'o', b'k', 0]), [4, 0, 0, 0, 0, 0]);
        // Full packet: 26 − 6 = 20 bytes.
        let mut d = alloc::vec![3, 0, 1, 0, 0, 0];
        d.extend_from_slice(&[1; 20]);
        assert_eq!(run(&mut s, &mut k, &d), [4, 0, 1, 0, 0, 0]);
        assert_eq!(run(&mut s, &mut k, &[3, 0, 2, 0, 0, 0, 9]), [4, 0, 2, 0, 0, 0]);
        assert!(s.is_idle());
        assert_eq!((k.0.len(), k.1.as_slice()), (21, &[FoeEnd::Completed][..]));
        // Refused by the handler: ERR with the standard text cut to the mailbox.
        let e = run(&mut s, &mut k, &[2, 0, 0, 0, 0, 0, b'x']);
        assert_eq!(e, [5, 0, 0x0A, 0x80, 0, 0, b'N', b'o', b' ', b'r', b'i', b'g', b'h', b't', b's']);
    }

    #[test]
    fn names_and_codes() {
        assert_eq!(trim_nul(b"a\0\0"), b"a");
        assert_eq!(trim_nul(b"\0"), b"");
        assert_eq!(FoeError::BOOTSTRAP_ONLY.description(), Some("Bootstrap only"));
        assert_eq!(FoeError(0x9000).description(), None);
        assert_eq!(alloc::format!("{:?}", FoeError::NOT_FOUND), "FoeError(0x8001 Not found)");
    }
}
