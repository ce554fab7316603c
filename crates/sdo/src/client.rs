//! SDO client (CiA 301 §7.2.4), sans-IO.
//!
//! One [`SdoClient`] talks to one SDO server over a pair of COB-IDs and runs
//! one transfer at a time: expedited, segmented or block, upload or download.
//! The caller starts a transfer, feeds every received frame to
//! [`SdoClient::handle_frame`], calls [`SdoClient::poll`] at the deadline it
//! returns, and collects the outcome with [`SdoClient::take_result`].
//!
//! ```
//! use drivebus_can::{Frame, Instant};
//! use drivebus_sdo::client::{Completed, Protocol, SdoClient, SdoClientConfig};
//!
//! let mut client = SdoClient::new(SdoClientConfig::for_node(3));
//! let mut out: Vec<Frame> = Vec::new();
//! client.start_upload(0x6041, 0, Protocol::Auto, Instant::ZERO, &mut out).unwrap();
//! assert_eq!(out[0], Frame::new(0x603, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]));
//! // The drive answers with a 2-byte expedited upload response.
//! let resp = Frame::new(0x583, &[0x4B, 0x41, 0x60, 0, 0x40, 0x02, 0, 0]);
//! client.handle_frame(&resp, Instant::from_millis(2), &mut out);
//! assert_eq!(client.take_result(), Some(Ok(Completed::Upload(vec![0x40, 0x02]))));
//! ```
//!
//! Design choices:
//! - **Protocol checks.** A response that does not fit the state is answered
//!   with an abort frame and ends the transfer with
//!   [`ClientError::ProtocolViolation`] carrying the code sent: wrong command
//!   specifier `0504 0001`, wrong toggle `0503 0000`, block size 0 or > 127
//!   `0504 0002`, block sequence number 0, above the block size or an ack
//!   beyond what was sent `0504 0003`, CRC mismatch `0504 0004`, size
//!   mismatch `0607 0010`.
//! - **Multiplexer check: another client's answers.** A response naming
//!   another index or sub-index is never taken (it could return a value of
//!   another object, CiA 301 asks the client to check), and it is not
//!   aborted either: on a bus where a second client talks to the same
//!   server (a monitor next to a command), it is that client's answer, and
//!   an abort would break its transfer. It is ignored, counted
//!   ([`SdoClient::foreign_answers`]) and does not re-arm the timeout; the
//!   transfer waits for its own answer. So are initiate responses arriving
//!   in the middle of a segmented transfer.
//! - **Server aborts** are frames whose byte 0 is exactly `80h`. One whose
//!   multiplexer names another object is another transfer's (ignored and
//!   counted); 0000h:00 counts as ours (some servers send it). Inside a
//!   block upload sub-block `80h` would be "last segment, seqno 0", which is
//!   invalid anyway, so it is read as the abort there too.
//! - **Lost block segments** are not errors: in a block upload the client
//!   drops out-of-sequence segments and acknowledges the last in-sequence
//!   one at the end of the sub-block so the server resends from there.
//! - **Timeouts.** Every accepted response re-arms `timeout`. At the deadline
//!   [`SdoClient::poll`] sends `0504 0000` and, while retries are left,
//!   restarts the whole transfer from its initiate. A response that arrives
//!   after the deadline but before `poll` ran is still accepted.
//! - **Short frames.** CiA 301 SDO frames are 8 bytes; a shorter response is
//!   read zero-padded rather than dropped, because some devices send a short
//!   DLC for expedited responses.
//! - **Memory.** Downloads are copied (or moved) into the client at start.
//!   Uploads reserve the announced size at the initiate response, capped by
//!   [`SdoClientConfig::max_upload`] (`0504 0005` above it); only an upload
//!   without indicated size grows its buffer while receiving.
//! - **One transfer at a time**: starting while busy gives
//!   [`ClientError::Busy`]; starting drops a result nobody took.

mod block;

use crate::wire::*;
use alloc::vec::Vec;
use core::fmt;
use drivebus_can::{CanId, Duration, Frame, Instant, TxSink};
use drivebus_od::SdoAbort;

/// Default response timeout of a client (CiA 301 leaves it to the application).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_millis(1000);
/// Largest block size (segments per sub-block) CiA 301 allows.
pub const MAX_BLOCK_SIZE: u8 = 127;
/// Default cap on the size of an upload, guarding memory against a server
/// that announces (or streams) an absurd amount of data.
pub const DEFAULT_MAX_UPLOAD: usize = 16 * 1024 * 1024;

/// Which SDO protocol a transfer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Protocol {
    /// Download: expedited for 1..=4 bytes, block at or above
    /// [`SdoClientConfig::block_threshold`], segmented otherwise.
    /// Upload: a normal initiate; the server picks expedited or segmented.
    #[default]
    Auto,
    /// Expedited download (1..=4 bytes). For an upload the same as `Auto`.
    Expedited,
    /// Segmented download with size indicated. For an upload the same as `Auto`.
    Segmented,
    /// Block transfer (CRC per [`SdoClientConfig::crc`]).
    Block,
}

/// Configuration of one client (CiA 301 objects 1280h..12FFh hold the ids).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SdoClientConfig {
    /// COB-ID client → server (600h + node for the default SDO).
    pub tx_id: CanId,
    /// COB-ID server → client (580h + node for the default SDO).
    pub rx_id: CanId,
    /// Time allowed for each server response.
    pub timeout: Duration,
    /// How many times a transfer that timed out is started again.
    pub retries: u8,
    /// Block size the client asks for in block upload (1..=127; clamped).
    pub block_size: u8,
    /// Offer CRC in block transfers (used only if the server agrees).
    pub crc: bool,
    /// Protocol switch threshold sent in a block upload request: the server
    /// may answer with an expedited/segmented upload for objects of at most
    /// this many bytes. 0 forbids the switch.
    pub pst: u8,
    /// `Protocol::Auto` downloads of at least this many bytes use block
    /// transfer. `None`: Auto never chooses block.
    pub block_threshold: Option<usize>,
    /// Largest upload accepted; bigger ones are aborted with `0504 0005`.
    pub max_upload: usize,
}

impl SdoClientConfig {
    /// The default SDO of node `node` (1..=127): 600h+node / 580h+node, the
    /// default timeout, one retry, block size 127 with CRC, pst 0.
    pub fn for_node(node: u8) -> Self {
        let node = u16::from(node & 0x7F);
        SdoClientConfig {
            tx_id: CanId::Standard(0x600 + node),
            rx_id: CanId::Standard(0x580 + node),
            timeout: DEFAULT_TIMEOUT,
            retries: 1,
            block_size: MAX_BLOCK_SIZE,
            crc: true,
            pst: 0,
            block_threshold: None,
            max_upload: DEFAULT_MAX_UPLOAD,
        }
    }
}

/// A successful transfer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Completed {
    /// The uploaded bytes.
    Upload(Vec<u8>),
    /// The server confirmed the download.
    Download,
}

impl Completed {
    /// The uploaded bytes (empty for a download).
    pub fn into_data(self) -> Vec<u8> {
        match self {
            Completed::Upload(d) => d,
            Completed::Download => Vec::new(),
        }
    }
}

/// Why a transfer failed or could not start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClientError {
    /// The server sent an abort frame with this code.
    ServerAbort(SdoAbort),
    /// No response within the timeout, after every retry (the client sent
    /// `0504 0000` to the server each time).
    Timeout,
    /// The server broke the protocol; the client sent it this abort code.
    ProtocolViolation(SdoAbort),
    /// The client aborted for a local reason (upload too large, or
    /// [`SdoClient::abort`]) and sent this code.
    LocalAbort(SdoAbort),
    /// A transfer is already running on this client.
    Busy,
    /// The request cannot be sent as asked (expedited with 0 or > 4 bytes,
    /// or more than 2^32 - 1 bytes).
    InvalidRequest,
}

impl fmt::Display for ClientError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ClientError::ServerAbort(a) => write!(f, "server aborted the transfer: {a}"),
            ClientError::Timeout => f.write_str("SDO server did not respond in time"),
            ClientError::ProtocolViolation(a) => {
                write!(f, "server violated the SDO protocol, sent abort {a}")
            }
            ClientError::LocalAbort(a) => write!(f, "transfer aborted by the client: {a}"),
            ClientError::Busy => f.write_str("an SDO transfer is already in progress"),
            ClientError::InvalidRequest => f.write_str("the request cannot be sent with this protocol"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ClientError {}

/// Where the transfer is: which response the client waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    /// Sent an initiate download (expedited or segmented); expect `60h`.
    InitDownload,
    /// Sent a download segment; expect `20h | t`.
    DownSegment,
    /// Sent an initiate upload; expect `4xh`.
    InitUpload,
    /// Sent an upload segment request; expect a segment with the same toggle.
    UpSegment,
    /// Sent a block download initiate; expect `A0h | sc`.
    BlockDownInit,
    /// Sent a sub-block; expect the block ack `A2h`.
    BlockDownAck,
    /// Sent the block download end; expect `A1h`.
    BlockDownEnd,
    /// Sent a block upload initiate; expect `C0h | sc | s` (or `4xh` with pst).
    BlockUpInit,
    /// Receiving sub-block segments.
    BlockUpData,
    /// Acked the last segment; expect the end `C1h | n`.
    BlockUpEnd,
}

/// What a transfer was started as, to restart it on a timeout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Upload,
    Download,
}

/// A sans-IO SDO client for one server.
#[derive(Debug)]
pub struct SdoClient {
    cfg: SdoClientConfig,
    state: State,
    kind: Kind,
    /// Resolved protocol of the running transfer (never `Auto` for downloads).
    proto: Protocol,
    index: u16,
    sub: u8,
    /// Download source or upload destination; kept between downloads so a
    /// borrowed-slice download reuses its capacity.
    data: Vec<u8>,
    /// Bytes confirmed by the server (download) or received (upload).
    pos: usize,
    /// Total size, when known.
    size: Option<usize>,
    toggle: bool,
    retries_left: u8,
    deadline: Instant,
    /// Negotiated CRC use in a block transfer.
    crc: bool,
    /// Block download: the server's block size; block upload: ours.
    blksize: u8,
    /// Block download: first segment of the current sub-block.
    seg_base: usize,
    /// Block download: segments sent in the current sub-block.
    seg_sent: u8,
    /// Block upload: next expected sequence number.
    expected: u8,
    result: Option<Result<Completed, ClientError>>,
    /// Answers of another transfer seen during this one (another client).
    foreign: u32,
    /// The object the last of them named.
    last_foreign: Option<(u16, u8)>,
}

impl SdoClient {
    /// A client for the server described by `cfg` (block size clamped to 1..=127).
    pub fn new(mut cfg: SdoClientConfig) -> Self {
        cfg.block_size = cfg.block_size.clamp(1, MAX_BLOCK_SIZE);
        SdoClient {
            cfg,
            state: State::Idle,
            kind: Kind::Upload,
            proto: Protocol::Auto,
            index: 0,
            sub: 0,
            data: Vec::new(),
            pos: 0,
            size: None,
            toggle: false,
            retries_left: 0,
            foreign: 0,
            last_foreign: None,
            deadline: Instant::MAX,
            crc: false,
            blksize: 1,
            seg_base: 0,
            seg_sent: 0,
            expected: 1,
            result: None,
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &SdoClientConfig {
        &self.cfg
    }

    /// True while a transfer runs.
    pub fn is_busy(&self) -> bool {
        self.state != State::Idle
    }

    /// Read `index`/`sub` from the server. Sends the initiate request into
    /// `out`. A result still pending from an earlier transfer is dropped.
    pub fn start_upload(
        &mut self,
        index: u16,
        sub: u8,
        protocol: Protocol,
        now: Instant,
        out: &mut impl TxSink,
    ) -> Result<(), ClientError> {
        if self.is_busy() {
            return Err(ClientError::Busy);
        }
        self.begin(Kind::Upload, index, sub, protocol);
        self.data = Vec::new();
        self.initiate(now, out);
        Ok(())
    }

    /// Write `data` to `index`/`sub`. The bytes are copied into a buffer the
    /// client keeps and reuses for later downloads.
    pub fn start_download(
        &mut self,
        index: u16,
        sub: u8,
        data: &[u8],
        protocol: Protocol,
        now: Instant,
        out: &mut impl TxSink,
    ) -> Result<(), ClientError> {
        if self.is_busy() {
            return Err(ClientError::Busy);
        }
        let proto = self.resolve_download(data.len(), protocol)?;
        self.data.clear();
        self.data.extend_from_slice(data);
        self.begin(Kind::Download, index, sub, proto);
        self.initiate(now, out);
        Ok(())
    }

    /// Write `data` to `index`/`sub`, taking ownership of the buffer.
    pub fn start_download_owned(
        &mut self,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        protocol: Protocol,
        now: Instant,
        out: &mut impl TxSink,
    ) -> Result<(), ClientError> {
        if self.is_busy() {
            return Err(ClientError::Busy);
        }
        let proto = self.resolve_download(data.len(), protocol)?;
        self.data = data;
        self.begin(Kind::Download, index, sub, proto);
        self.initiate(now, out);
        Ok(())
    }

    /// Abort the running transfer with `code` (sent to the server); the
    /// result becomes [`ClientError::LocalAbort`]. Does nothing when idle.
    pub fn abort(&mut self, code: SdoAbort, out: &mut impl TxSink) {
        if self.is_busy() {
            self.fail_with_abort(code, ClientError::LocalAbort(code), out);
        }
    }

    /// Bytes transferred so far and the total when known; `None` when idle.
    pub fn progress(&self) -> Option<(usize, Option<usize>)> {
        if !self.is_busy() {
            return None;
        }
        let done = match self.size {
            Some(total) => self.pos.min(total),
            None => self.pos,
        };
        Some((done, self.size))
    }

    /// The outcome of the last finished transfer, once.
    pub fn take_result(&mut self) -> Option<Result<Completed, ClientError>> {
        self.result.take()
    }

    /// Feed a received frame. Frames on other COB-IDs, remote frames and
    /// frames arriving while idle are ignored.
    pub fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) {
        if frame.id() != self.cfg.rx_id || frame.is_rtr() || frame.is_empty() || !self.is_busy() {
            return;
        }
        // Servers should always send 8 bytes; a shorter frame reads as zero-padded.
        let d = *frame.raw_data();
        if self.is_foreign(&d) {
            self.foreign = self.foreign.saturating_add(1);
            self.last_foreign = Some(mux_of(&d));
            return;
        }
        // An abort is exactly 80h (cs = 4, other bits 0). Inside a block upload
        // sub-block 80h would read as "last segment, seqno 0", which is
        // invalid anyway, so it is the server's abort there too.
        if d[0] == CS_ABORT {
            self.finish(Err(ClientError::ServerAbort(SdoAbort(u32_at4(&d)))));
            return;
        }
        self.deadline = now + self.cfg.timeout;
        match self.state {
            State::Idle => {}
            State::InitDownload => self.on_init_download(&d, out),
            State::DownSegment => self.on_download_segment(&d, out),
            State::InitUpload => self.on_init_upload(&d, out),
            State::UpSegment => self.on_upload_segment(&d, out),
            State::BlockDownInit => self.on_block_down_init(&d, out),
            State::BlockDownAck => self.on_block_down_ack(&d, out),
            State::BlockDownEnd => self.on_block_down_end(&d, out),
            State::BlockUpInit => self.on_block_up_init(&d, out),
            State::BlockUpData => self.on_block_up_segment(&d, out),
            State::BlockUpEnd => self.on_block_up_end(&d, out),
        }
    }

    /// Handle the response timeout: at or after the deadline, send abort
    /// `0504 0000`, then restart the transfer if retries are left, else fail
    /// with [`ClientError::Timeout`]. Returns the next deadline.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if !self.is_busy() {
            return None;
        }
        if now >= self.deadline {
            self.send(out, abort_frame(self.index, self.sub, SdoAbort::TIMEOUT));
            if self.retries_left > 0 {
                self.retries_left -= 1;
                self.initiate(now, out);
            } else {
                self.finish(Err(ClientError::Timeout));
                return None;
            }
        }
        Some(self.deadline)
    }

    /// The current deadline, without doing any work.
    pub fn deadline(&self) -> Option<Instant> {
        self.is_busy().then_some(self.deadline)
    }

    // ---- common plumbing ----

    fn resolve_download(&self, len: usize, protocol: Protocol) -> Result<Protocol, ClientError> {
        if u32::try_from(len).is_err() {
            return Err(ClientError::InvalidRequest);
        }
        Ok(match protocol {
            Protocol::Auto => match self.cfg.block_threshold {
                Some(t) if len >= t => Protocol::Block,
                _ if (1..=4).contains(&len) => Protocol::Expedited,
                _ => Protocol::Segmented,
            },
            Protocol::Expedited if !(1..=4).contains(&len) => return Err(ClientError::InvalidRequest),
            p => p,
        })
    }

    fn begin(&mut self, kind: Kind, index: u16, sub: u8, proto: Protocol) {
        self.kind = kind;
        self.index = index;
        self.sub = sub;
        self.proto = proto;
        self.retries_left = self.cfg.retries;
        self.result = None;
        self.foreign = 0;
        self.last_foreign = None;
    }

    /// Answers that belonged to another transfer (another client talking
    /// to the same server) seen since the current or last transfer began.
    pub fn foreign_answers(&self) -> u32 {
        self.foreign
    }

    /// The object (index, sub-index) the last foreign answer named.
    pub fn last_foreign(&self) -> Option<(u16, u8)> {
        self.last_foreign
    }

    /// True when `d` is another transfer's answer: an abort or initiate
    /// response naming another object, or an initiate response in the
    /// middle of a segmented transfer (ours carry no multiplexer there).
    fn is_foreign(&self, d: &[u8; 8]) -> bool {
        let mux = mux_of(d);
        let ours = mux == (self.index, self.sub);
        match self.state {
            _ if d[0] == CS_ABORT => !ours && mux != (0, 0),
            State::InitDownload | State::InitUpload | State::BlockDownInit | State::BlockUpInit => !ours,
            State::UpSegment | State::DownSegment => {
                matches!(scs(d[0]), SCS_INITIATE_UPLOAD | SCS_INITIATE_DOWNLOAD) && !ours
            }
            _ => false,
        }
    }

    /// Send the initiate request of the current transfer (first attempt or retry).
    fn initiate(&mut self, now: Instant, out: &mut impl TxSink) {
        self.pos = 0;
        self.toggle = false;
        self.seg_base = 0;
        self.seg_sent = 0;
        self.expected = 1;
        self.deadline = now + self.cfg.timeout;
        let (index, sub) = (self.index, self.sub);
        match (self.kind, self.proto) {
            (Kind::Upload, Protocol::Block) => {
                self.data.clear();
                self.size = None;
                self.blksize = self.cfg.block_size;
                let cmd = CCS_BLOCK_UPLOAD | (u8::from(self.cfg.crc) << 2) | BLOCK_INITIATE;
                self.send(out, mux_frame(cmd, index, sub, [self.blksize, self.cfg.pst, 0, 0]));
                self.state = State::BlockUpInit;
            }
            (Kind::Upload, _) => {
                self.data.clear();
                self.size = None;
                self.send(out, mux_frame(CCS_INITIATE_UPLOAD, index, sub, [0; 4]));
                self.state = State::InitUpload;
            }
            (Kind::Download, Protocol::Expedited) => {
                let len = self.data.len().min(4);
                self.size = Some(len);
                let mut d = [0u8; 4];
                d[..len].copy_from_slice(&self.data[..len]);
                let cmd = expedited(CCS_INITIATE_DOWNLOAD, len);
                self.send(out, mux_frame(cmd, index, sub, d));
                self.state = State::InitDownload;
            }
            (Kind::Download, Protocol::Block) => {
                self.size = Some(self.data.len());
                // cs = 0 initiate, s = 1 size indicated, cc = CRC offered.
                let crc = if self.cfg.crc { BLOCK_CRC } else { 0 };
                let cmd = CCS_BLOCK_DOWNLOAD | crc | BLOCK_SIZE_INDICATED;
                self.send(out, mux_frame(cmd, index, sub, (self.data.len() as u32).to_le_bytes()));
                self.state = State::BlockDownInit;
            }
            (Kind::Download, _) => {
                self.size = Some(self.data.len());
                // e = 0, s = 1: segmented with the size in bytes 4..8.
                let cmd = CCS_INITIATE_DOWNLOAD | SIZE_INDICATED;
                self.send(out, mux_frame(cmd, index, sub, (self.data.len() as u32).to_le_bytes()));
                self.state = State::InitDownload;
            }
        }
    }

    #[inline]
    fn send(&self, out: &mut impl TxSink, data: [u8; 8]) {
        out.send(frame(self.cfg.tx_id, data));
    }

    fn finish(&mut self, result: Result<Completed, ClientError>) {
        self.state = State::Idle;
        self.deadline = Instant::MAX;
        self.result = Some(result);
    }

    fn complete(&mut self) {
        let r = match self.kind {
            Kind::Upload => Completed::Upload(core::mem::take(&mut self.data)),
            Kind::Download => Completed::Download,
        };
        self.finish(Ok(r));
    }

    /// Send abort `code` to the server and end the transfer with `err`.
    fn fail_with_abort(&mut self, code: SdoAbort, err: ClientError, out: &mut impl TxSink) {
        self.send(out, abort_frame(self.index, self.sub, code));
        self.finish(Err(err));
    }

    /// The server broke the protocol: abort with `code`.
    fn violation(&mut self, code: SdoAbort, out: &mut impl TxSink) {
        self.fail_with_abort(code, ClientError::ProtocolViolation(code), out);
    }

    /// Check the multiplexer of an initiate response; aborts on mismatch.
    fn mux_ok(&mut self, d: &[u8; 8], out: &mut impl TxSink) -> bool {
        if mux_of(d) == (self.index, self.sub) {
            return true;
        }
        // Foreign answers are filtered before; this is a block upload's
        // protocol switch (pst) answer naming another object.
        self.violation(SdoAbort::PARAM_INCOMPATIBLE, out);
        false
    }

    /// Reserve room for an upload of `size` bytes (+ one segment of slack for
    /// block padding), or abort `0504 0005` if it is over the configured cap.
    fn reserve_upload(&mut self, size: Option<usize>, out: &mut impl TxSink) -> bool {
        if let Some(n) = size {
            if n > self.cfg.max_upload {
                self.fail_with_abort(
                    SdoAbort::OUT_OF_MEMORY,
                    ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY),
                    out,
                );
                return false;
            }
            // try_reserve: a failed allocation is an abort, never a panic.
            if self.data.try_reserve(n.saturating_add(SEG)).is_err() {
                self.fail_with_abort(
                    SdoAbort::OUT_OF_MEMORY,
                    ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY),
                    out,
                );
                return false;
            }
        }
        true
    }

    /// Append received upload bytes, enforcing the announced size and the cap.
    fn push_upload(&mut self, bytes: &[u8], out: &mut impl TxSink) -> bool {
        let new_len = self.data.len() + bytes.len();
        if let Some(n) = self.size
            && new_len > n
        {
            self.violation(SdoAbort::TYPE_MISMATCH, out);
            return false;
        }
        if new_len > self.cfg.max_upload {
            self.fail_with_abort(
                SdoAbort::OUT_OF_MEMORY,
                ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY),
                out,
            );
            return false;
        }
        self.data.extend_from_slice(bytes);
        self.pos = self.data.len();
        true
    }

    // ---- expedited and segmented download (CiA 301 §7.2.4.3.3..6) ----

    fn on_init_download(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_INITIATE_DOWNLOAD {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        if !self.mux_ok(d, out) {
            return;
        }
        if self.proto == Protocol::Expedited {
            self.pos = self.data.len();
            return self.complete();
        }
        self.send_download_segment(out);
    }

    fn send_download_segment(&mut self, out: &mut impl TxSink) {
        let n = (self.data.len() - self.pos).min(SEG);
        let last = self.pos + n == self.data.len();
        let mut f = [0u8; 8];
        f[0] = CCS_DOWNLOAD_SEGMENT
            | if self.toggle { TOGGLE } else { 0 }
            | (((SEG - n) as u8) << 1)
            | u8::from(last);
        f[1..=n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.send(out, f);
        self.state = State::DownSegment;
    }

    fn on_download_segment(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_DOWNLOAD_SEGMENT {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        if (d[0] & TOGGLE != 0) != self.toggle {
            return self.violation(SdoAbort::TOGGLE_NOT_ALTERNATED, out);
        }
        let n = (self.data.len() - self.pos).min(SEG);
        self.pos += n;
        if self.pos == self.data.len() {
            return self.complete();
        }
        self.toggle = !self.toggle;
        self.send_download_segment(out);
    }

    // ---- expedited and segmented upload (CiA 301 §7.2.4.3.7..10) ----

    fn on_init_upload(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_INITIATE_UPLOAD {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        self.accept_init_upload(d, out);
    }

    /// An initiate upload response (also the pst fallback of a block upload).
    fn accept_init_upload(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if !self.mux_ok(d, out) {
            return;
        }
        let sized = d[0] & SIZE_INDICATED != 0;
        if d[0] & EXPEDITED != 0 {
            // With s = 0 the size is unspecified: take all 4 bytes.
            let len = expedited_len(d[0]).unwrap_or(4);
            self.data.clear();
            self.data.extend_from_slice(&d[4..4 + len]);
            self.pos = len;
            return self.complete();
        }
        let size = sized.then(|| u32_at4(d) as usize);
        if !self.reserve_upload(size, out) {
            return;
        }
        self.size = size;
        self.toggle = false;
        self.request_upload_segment(out);
    }

    fn request_upload_segment(&mut self, out: &mut impl TxSink) {
        let cmd = CCS_UPLOAD_SEGMENT | if self.toggle { TOGGLE } else { 0 };
        self.send(out, [cmd, 0, 0, 0, 0, 0, 0, 0]);
        self.state = State::UpSegment;
    }

    fn on_upload_segment(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_UPLOAD_SEGMENT {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        if (d[0] & TOGGLE != 0) != self.toggle {
            return self.violation(SdoAbort::TOGGLE_NOT_ALTERNATED, out);
        }
        let len = segment_len(d[0]);
        if !self.push_upload(&d[1..=len], out) {
            return;
        }
        if d[0] & LAST_SEGMENT != 0 {
            if self.size.is_some_and(|n| n != self.data.len()) {
                return self.violation(SdoAbort::TYPE_MISMATCH, out);
            }
            return self.complete();
        }
        self.toggle = !self.toggle;
        self.request_upload_segment(out);
    }
}
