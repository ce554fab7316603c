//! SDO server (CiA 301 §7.2.4), sans-IO.
//!
//! One [`SdoServer`] serves one server SDO channel (1200h for the default
//! channel, 1201h..127Fh for additional ones). It is driven by the caller:
//! [`SdoServer::handle_frame`] for every frame received on the channel's
//! client→server COB-ID, [`SdoServer::poll`] for the protocol timeout.
//!
//! Protocols: expedited and segmented upload/download (CiA 301 §7.2.4.3), block
//! upload/download with or without CRC (same clause, in `server/block.rs`),
//! abort in both directions (§7.2.4.3.17).
//!
//! Design choices (each covered by a test):
//! - **Frames whose DLC is not 8 are ignored**, as CANopenNode does: CiA 301
//!   defines every SDO frame as 8 bytes, and answering a truncated frame
//!   would echo an index/sub-index the client may not have sent.
//! - **RTR frames** on the SDO COB-ID are ignored.
//! - **A new initiate while a transfer runs starts a new transfer**; the old
//!   one is dropped silently (CANopenNode v4 and the drives we know behave
//!   this way: a client that lost track simply starts over). Inside a block
//!   download sub-block every frame is a segment by definition, so an
//!   initiate cannot be recognised there; only an abort (`80h`) ends it.
//! - **An unexpected command** for the current state (e.g. an upload segment
//!   request during a download) is answered with `0504 0001` and ends the
//!   transfer. When idle, the abort echoes the frame's index/sub-index.
//! - **Timeouts**: every frame of a transfer re-arms a deadline of
//!   `config.timeout`; at the deadline the server sends `0504 0000` and goes
//!   idle. A frame that arrives after an unpolled deadline is handled as if
//!   `poll` had run first.
//! - **Uploads** run the read hook once at initiate and copy the value into a
//!   reusable buffer, so a value changing length mid-transfer cannot tear it.
//! - **Downloads** of more than 4 bytes accumulate into the same buffer
//!   (reserved at initiate from the indicated size) and are written once at
//!   the end, so validation and the write hook see the whole value.

use crate::wire::*;
use alloc::vec::Vec;
use drivebus_can::{CanId, Duration, Frame, Instant, TxSink};
use drivebus_od::{DataType, EntryRef, ObjectDictionary, ObjectHooks, SdoAbort};

// Client command specifiers as `scs` reads them from a request.
const DOWNLOAD_SEGMENT: u8 = CCS_DOWNLOAD_SEGMENT >> 5;
const INITIATE_DOWNLOAD: u8 = CCS_INITIATE_DOWNLOAD >> 5;
const INITIATE_UPLOAD: u8 = CCS_INITIATE_UPLOAD >> 5;
const UPLOAD_SEGMENT: u8 = CCS_UPLOAD_SEGMENT >> 5;
const ABORT: u8 = CS_ABORT >> 5;
const BLOCK_UPLOAD: u8 = CCS_BLOCK_UPLOAD >> 5;
const BLOCK_DOWNLOAD: u8 = CCS_BLOCK_DOWNLOAD >> 5;

mod block;
mod params;
#[cfg(test)]
mod tests;

pub use params::{
    FIRST_PARAM_INDEX, LAST_PARAM_INDEX, ParamHooks, check_write, cob_ids_from_od, install_server_params,
    is_restricted_can_id, parse_cob_id,
};

/// Every SDO frame carries exactly 8 bytes (CiA 301 §7.2.4.3). This is a
/// property of the protocol, not of classic CAN, hence its own constant.
pub const SDO_FRAME_LEN: usize = 8;

/// Largest block size of block transfer (CiA 301 §7.2.4.3, block download/upload).
pub const MAX_BLOCK_SIZE: u8 = 127;

/// Configuration of one server channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServerConfig {
    /// Protocol timeout between two frames of a transfer (default 1000 ms).
    pub timeout: Duration,
    /// Block size the server offers in block download (1..=127, default 127;
    /// out-of-range values are clamped).
    pub block_size: u8,
    /// Whether block transfer is supported at all. Devices without block SDO
    /// (e.g. Kollmorgen KC1/AKD) answer block initiates with `0504 0001`.
    pub block_transfer: bool,
    /// Whether the server supports the block-transfer CRC (the `sc` bit).
    pub crc: bool,
    /// Largest download the server accepts into its buffer; above it the
    /// initiate (or the segment that crosses it) is refused with `0504 0005`.
    /// Default 1 MiB; raise it for large DOMAINs such as 1F50h program data.
    pub max_download: usize,
    /// The abort for an index the dictionary does not have. CiA 301 says
    /// `0602 0000`; some drives answer otherwise (the SSD 630 sends
    /// `0601 0000`, seed003 EX14.1), and a faithful personality does too.
    pub missing_object: SdoAbort,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            timeout: Duration::from_millis(1000),
            block_size: MAX_BLOCK_SIZE,
            block_transfer: true,
            crc: true,
            max_download: 1 << 20,
            missing_object: SdoAbort::NO_OBJECT,
        }
    }
}

/// Where the channel's transfer stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    /// Segmented download: next segment must carry this toggle (00h/10h).
    DownSeg {
        toggle: u8,
    },
    /// Segmented upload: next request must carry this toggle (00h/10h).
    UpSeg {
        toggle: u8,
    },
    /// Block download, receiving a sub-block. `last` is the last in-order
    /// sequence number; `resync` ignores stale segments after a partial ack
    /// until the client restarts at sequence number 1.
    BlkDownSub {
        last: u8,
        resync: bool,
    },
    /// Block download: last segment acknowledged, waiting for the end frame.
    BlkDownEnd,
    /// Block upload initiated, waiting for the start command (A3h).
    BlkUpStart,
    /// Block upload: a sub-block of `seqs` segments was sent, `last` when it
    /// held the final segment; waiting for the client's ack (A2h).
    BlkUpAck {
        seqs: u8,
        last: bool,
    },
    /// Block upload end frame sent, waiting for the client's end response (A1h).
    BlkUpEnd,
}

/// One server SDO channel. See the module documentation for the behaviour.
#[derive(Clone, Debug)]
pub struct SdoServer {
    rx: Option<CanId>,
    tx: CanId,
    param_index: Option<u16>,
    config: ServerConfig,
    state: State,
    /// Index LSB, index MSB, sub-index of the running transfer (response bytes 1..4).
    mux: [u8; 3],
    /// Upload snapshot or download accumulator; capacity reused across transfers.
    buf: Vec<u8>,
    /// Upload: bytes already sent (block upload: start of the current sub-block).
    pos: usize,
    /// Download: size indicated by the client (`None`: not indicated).
    size: Option<usize>,
    /// Download: largest number of bytes accepted before refusing.
    limit: usize,
    /// Block transfer: both sides support CRC.
    use_crc: bool,
    /// Block transfer: current sub-block size.
    blksize: u8,
    deadline: Instant,
    /// Recently resolved entries (see [`SdoServer::resolve`]).
    cache: [Slot; CACHE_SLOTS],
}

/// Entries remembered by the lookup cache; a power of two.
const CACHE_SLOTS: usize = 8;

/// One remembered lookup: `(index, sub)` was found at these positions.
#[derive(Clone, Copy, Debug)]
struct Slot {
    key: u32,
    obj: u32,
    sub: u32,
    r: Option<EntryRef>,
}

impl SdoServer {
    /// A server receiving on `rx` (client→server) and answering on `tx`.
    /// Identifiers out of range disable the channel.
    pub fn new(rx: CanId, tx: CanId, config: ServerConfig) -> SdoServer {
        let mut s = SdoServer {
            rx: None,
            tx,
            param_index: None,
            config: ServerConfig { block_size: config.block_size.clamp(1, MAX_BLOCK_SIZE), ..config },
            state: State::Idle,
            mux: [0; 3],
            buf: Vec::new(),
            pos: 0,
            size: None,
            limit: 0,
            use_crc: false,
            blksize: 0,
            deadline: Instant::ZERO,
            cache: [Slot { key: 0, obj: 0, sub: 0, r: None }; CACHE_SLOTS],
        };
        s.set_cob_ids(rx, tx);
        s
    }

    /// The default server channel of `node_id` (600h+id / 580h+id, 1200h).
    pub fn default_channel(node_id: u8, config: ServerConfig) -> SdoServer {
        let id = u16::from(node_id & 0x7F);
        let mut s = SdoServer::new(CanId::Standard(0x600 + id), CanId::Standard(0x580 + id), config);
        s.param_index = Some(FIRST_PARAM_INDEX);
        s
    }

    /// The client→server COB-ID, or `None` while the channel is disabled.
    #[inline]
    pub fn rx_cob_id(&self) -> Option<CanId> {
        self.rx
    }

    /// The server→client COB-ID.
    #[inline]
    pub fn tx_cob_id(&self) -> CanId {
        self.tx
    }

    /// The 12xxh record this channel was built from, if any.
    #[inline]
    pub fn param_index(&self) -> Option<u16> {
        self.param_index
    }

    /// Change both COB-IDs; drops a running transfer silently. Identifiers
    /// out of range (a `CanId` built by hand) disable the channel.
    pub fn set_cob_ids(&mut self, rx: CanId, tx: CanId) {
        self.reset();
        if valid_id(rx) && valid_id(tx) {
            self.rx = Some(rx);
            self.tx = tx;
        } else {
            self.rx = None;
        }
    }

    /// Disable the channel (its COB-ID was made invalid); drops a transfer.
    pub fn disable(&mut self) {
        self.reset();
        self.rx = None;
    }

    /// The configuration in force.
    #[inline]
    pub fn config(&self) -> &ServerConfig {
        &self.config
    }

    /// Replace the configuration (drops a running transfer).
    pub fn set_config(&mut self, config: ServerConfig) {
        self.reset();
        self.config = ServerConfig { block_size: config.block_size.clamp(1, MAX_BLOCK_SIZE), ..config };
    }

    /// NMT reset communication / stopped: drop a running transfer silently
    /// (no abort frame). Buffers keep their capacity.
    #[inline]
    pub fn reset(&mut self) {
        self.state = State::Idle;
    }

    /// No transfer in progress.
    #[inline]
    pub fn is_idle(&self) -> bool {
        self.state == State::Idle
    }

    /// Handle one frame. Frames on other identifiers, RTR frames and frames
    /// with a DLC other than 8 are ignored; everything else is answered as
    /// CiA 301 says, responses going to `out` in bus order.
    pub fn handle_frame<H: ObjectHooks + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        if self.rx != Some(frame.id()) || frame.is_rtr() || frame.len() != SDO_FRAME_LEN {
            return;
        }
        let d = frame.raw_data();
        if self.state != State::Idle {
            if now >= self.deadline {
                self.poll(now, out);
            } else {
                self.transfer(d, now, od, hooks, out);
                return;
            }
        }
        self.idle(d, now, od, hooks, out);
    }

    /// Send the timeout abort (`0504 0000`) when the deadline has passed.
    /// Returns the deadline of the running transfer, `None` when idle.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if self.state == State::Idle {
            return None;
        }
        if now >= self.deadline {
            self.abort(SdoAbort::TIMEOUT, out);
            return None;
        }
        Some(self.deadline)
    }

    /// A frame while no transfer runs: only initiates are valid.
    fn idle<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        match scs(d[0]) {
            INITIATE_DOWNLOAD => self.initiate_download(d, now, od, hooks, out),
            INITIATE_UPLOAD => self.initiate_upload(d, now, od, hooks, out),
            // Abort from the client: nothing to end, never answered.
            ABORT => {}
            BLOCK_UPLOAD if d[0] & 0x03 == BLOCK_INITIATE => {
                self.block_upload_initiate(d, now, od, hooks, out)
            }
            BLOCK_DOWNLOAD if d[0] & 0x01 == BLOCK_INITIATE => self.block_download_initiate(d, now, od, out),
            _ => self.abort_with(&[d[1], d[2], d[3]], SdoAbort::INVALID_COMMAND, out),
        }
    }

    /// A frame during a transfer.
    fn transfer<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let b0 = d[0];
        if b0 == CS_ABORT || (scs(b0) == ABORT && !matches!(self.state, State::BlkDownSub { .. })) {
            // Client abort (§7.2.4.3.17): end silently, no response.
            self.state = State::Idle;
            return;
        }
        self.deadline = now + self.config.timeout;
        match (self.state, scs(b0)) {
            (State::BlkDownSub { last, resync }, _) => self.block_segment(d, last, resync, out),
            (State::UpSeg { toggle }, UPLOAD_SEGMENT) => self.upload_segment(b0, toggle, out),
            (State::DownSeg { toggle }, DOWNLOAD_SEGMENT) => self.download_segment(d, toggle, od, hooks, out),
            (State::BlkDownEnd, BLOCK_DOWNLOAD) if b0 & 0x01 == BLOCK_END => {
                self.block_download_end(d, od, hooks, out)
            }
            (State::BlkUpStart, BLOCK_UPLOAD) if b0 & 0x03 == BLOCK_START => self.block_upload_start(out),
            (State::BlkUpAck { seqs, last }, BLOCK_UPLOAD) if b0 & 0x03 == BLOCK_ACK => {
                self.block_upload_ack(d, seqs, last, out)
            }
            (State::BlkUpEnd, BLOCK_UPLOAD) if b0 & 0x03 == BLOCK_END => self.state = State::Idle,
            // A new initiate: start over (see the module documentation).
            _ if is_initiate(b0) => {
                self.state = State::Idle;
                self.idle(d, now, od, hooks, out);
            }
            _ => self.abort(SdoAbort::INVALID_COMMAND, out),
        }
    }

    /// Initiate upload (ccs=2): expedited for 1..=4 bytes, else segmented.
    fn initiate_upload<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let mux = [d[1], d[2], d[3]];
        match self.resolve(od, u16::from_le_bytes([d[1], d[2]]), d[3]) {
            Ok(r) => match od.read_ref(hooks, r) {
                Ok(()) => self.answer_upload(mux, od.bytes(r), now, out),
                Err(e) => self.abort_with(&mux, e, out),
            },
            Err(e) => self.abort_with(&mux, e, out),
        }
    }

    /// Answer an upload of `value` (already read through the hook): the
    /// expedited response, or the segmented initiate response after taking a
    /// snapshot. Also the block upload fallback below the pst threshold.
    fn answer_upload(&mut self, mux: [u8; 3], value: &[u8], now: Instant, out: &mut impl TxSink) {
        let n = value.len();
        if (1..=4).contains(&n) {
            let mut resp = [expedited(SCS_INITIATE_UPLOAD << 5, n), mux[0], mux[1], mux[2], 0, 0, 0, 0];
            resp[4..4 + n].copy_from_slice(value);
            self.state = State::Idle;
            self.send(resp, out);
            return;
        }
        let size = match self.snapshot(value) {
            Ok(size) => size,
            Err(e) => return self.abort_with(&mux, e, out),
        };
        self.mux = mux;
        self.pos = 0;
        self.state = State::UpSeg { toggle: 0 };
        self.deadline = now + self.config.timeout;
        let s = size.to_le_bytes();
        let b0 = (SCS_INITIATE_UPLOAD << 5) | SIZE_INDICATED;
        self.send([b0, mux[0], mux[1], mux[2], s[0], s[1], s[2], s[3]], out);
    }

    /// Copy an upload value into the reusable buffer; returns its size as
    /// sent on the wire.
    fn snapshot(&mut self, value: &[u8]) -> Result<u32, SdoAbort> {
        let size = u32::try_from(value.len()).map_err(|_| SdoAbort::OUT_OF_MEMORY)?;
        self.buf.clear();
        self.buf.try_reserve(value.len()).map_err(|_| SdoAbort::OUT_OF_MEMORY)?;
        self.buf.extend_from_slice(value);
        Ok(size)
    }

    /// Upload segment request (ccs=3): the next 7 bytes at most.
    fn upload_segment(&mut self, b0: u8, toggle: u8, out: &mut impl TxSink) {
        if b0 & TOGGLE != toggle {
            return self.abort(SdoAbort::TOGGLE_NOT_ALTERNATED, out);
        }
        let rest = self.buf.get(self.pos..).unwrap_or(&[]);
        let k = rest.len().min(SEG);
        let last = rest.len() <= SEG;
        let mut resp = [segment(SCS_UPLOAD_SEGMENT << 5, toggle, k, last), 0, 0, 0, 0, 0, 0, 0];
        copy_segment(&mut resp, rest);
        self.pos += k;
        self.state = if last { State::Idle } else { State::UpSeg { toggle: toggle ^ TOGGLE } };
        self.send(resp, out);
    }

    /// Initiate download (ccs=1): expedited writes at once; segmented
    /// prepares the buffer.
    fn initiate_download<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let b0 = d[0];
        let mux = [d[1], d[2], d[3]];
        let r = match self.resolve(od, u16::from_le_bytes([d[1], d[2]]), d[3]) {
            Ok(r) => r,
            Err(e) => return self.abort_with(&mux, e, out),
        };
        if b0 & EXPEDITED != 0 {
            // Expedited (e=1): n is only meaningful with s=1.
            let len = expedited_len(b0).unwrap_or_else(|| expedited_unsized_len(od.entry(r).data_type));
            match od.write_ref(hooks, r, &d[4..4 + len]) {
                Ok(()) => self.send([SCS_INITIATE_DOWNLOAD << 5, mux[0], mux[1], mux[2], 0, 0, 0, 0], out),
                Err(e) => self.abort_with(&mux, e, out),
            }
            return;
        }
        let size = (b0 & SIZE_INDICATED != 0).then(|| u32::from_le_bytes([d[4], d[5], d[6], d[7]]) as usize);
        if let Err(e) = self.prepare_download(od, r, size) {
            return self.abort_with(&mux, e, out);
        }
        self.mux = mux;
        self.state = State::DownSeg { toggle: 0 };
        self.deadline = now + self.config.timeout;
        self.send([SCS_INITIATE_DOWNLOAD << 5, mux[0], mux[1], mux[2], 0, 0, 0, 0], out);
    }

    /// Check a segmented or block download against the object before any
    /// data flows, and reserve the buffer (the only allocation of a download).
    fn prepare_download(
        &mut self,
        od: &ObjectDictionary,
        r: EntryRef,
        size: Option<usize>,
    ) -> Result<(), SdoAbort> {
        let e = od.entry(r);
        if !e.access.writable() {
            return Err(SdoAbort::WRITE_READ_ONLY);
        }
        let max = self.config.max_download;
        let mut limit = max;
        if let Some(n) = e.data_type.fixed_size() {
            limit = limit.min(n);
        }
        if let Some(m) = e.max_len {
            limit = limit.min(m);
        }
        if let Some(s) = size {
            drivebus_od::check_len(e.data_type, s)?;
            if e.max_len.is_some_and(|m| s > m) {
                return Err(SdoAbort::DATA_TOO_LONG);
            }
            if s > max {
                return Err(SdoAbort::OUT_OF_MEMORY);
            }
            limit = s;
        }
        self.size = size;
        self.limit = limit;
        self.buf.clear();
        // Block download writes whole 7-byte segments before it learns how
        // many bytes of the last one are padding: reserve for that too.
        let want = size.unwrap_or(limit.min(4096)).saturating_add(7);
        self.buf.try_reserve(want).map_err(|_| SdoAbort::OUT_OF_MEMORY)
    }

    /// The abort for data beyond `self.limit`: the buffer limit without an
    /// indicated size, otherwise the length error.
    #[inline]
    fn over_limit(&self) -> SdoAbort {
        if self.size.is_none() && self.limit == self.config.max_download {
            SdoAbort::OUT_OF_MEMORY
        } else {
            SdoAbort::DATA_TOO_LONG
        }
    }

    /// Download segment (ccs=0).
    fn download_segment<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        toggle: u8,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let b0 = d[0];
        if b0 & TOGGLE != toggle {
            return self.abort(SdoAbort::TOGGLE_NOT_ALTERNATED, out);
        }
        let k = segment_len(b0);
        if self.buf.len() + k > self.limit {
            let e = self.over_limit();
            return self.abort(e, out);
        }
        // Without an indicated size the buffer may still grow here (up to
        // `limit`); its capacity is kept, so repeated transfers do not
        // allocate. A constant-length copy for full segments (no memcpy call).
        if k == 7 {
            self.buf.extend_from_slice(&d[1..8]);
        } else {
            self.buf.extend_from_slice(&d[1..1 + k]);
        }
        let ack = (SCS_DOWNLOAD_SEGMENT << 5) | toggle;
        if b0 & LAST_SEGMENT == 0 {
            self.state = State::DownSeg { toggle: toggle ^ TOGGLE };
            self.send([ack, 0, 0, 0, 0, 0, 0, 0], out);
        } else {
            self.finish_download(ack, od, hooks, out);
        }
    }

    /// Last data of a download received: check the size, write the object
    /// once, answer with `resp0` or the abort the dictionary gave.
    fn finish_download<H: ObjectHooks + ?Sized>(
        &mut self,
        resp0: u8,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        self.state = State::Idle;
        if let Some(s) = self.size {
            if self.buf.len() > s {
                return self.abort(SdoAbort::DATA_TOO_LONG, out);
            }
            if self.buf.len() < s {
                return self.abort(SdoAbort::DATA_TOO_SHORT, out);
            }
        }
        // Resolve again: the dictionary may have changed shape since the
        // initiate (one lookup per transfer, not per segment).
        let m = self.mux;
        let res = match self.resolve(od, u16::from_le_bytes([m[0], m[1]]), m[2]) {
            Ok(r) => od.write_ref(hooks, r, &self.buf),
            Err(e) => Err(e),
        };
        match res {
            Ok(()) => self.send([resp0, 0, 0, 0, 0, 0, 0, 0], out),
            Err(e) => self.abort(e, out),
        }
    }

    /// `od.find` with a small cache in front: SDO clients poll the same few
    /// objects over and over, and the dictionary's binary search was half
    /// the cost of an expedited transfer. A hit is only trusted after
    /// checking, through the dictionary's public slices, that the remembered
    /// positions still hold `(index, sub)` — an [`EntryRef`] is those
    /// positions — so inserts, removals and replacements can never make it
    /// return a stale or out-of-range handle.
    #[inline(always)]
    fn resolve(&mut self, od: &ObjectDictionary, index: u16, sub: u8) -> Result<EntryRef, SdoAbort> {
        let key = (u32::from(index) << 8) | u32::from(sub);
        let slot = &self.cache[usize::from(index ^ u16::from(sub)) & (CACHE_SLOTS - 1)];
        if let Some(r) = slot.r
            && slot.key == key
            && let Some(o) = od.objects().get(slot.obj as usize)
            && o.index == index
            && o.subs().get(slot.sub as usize).is_some_and(|s| s.sub == sub)
        {
            return Ok(r);
        }
        self.resolve_miss(od, index, sub)
    }

    /// [`resolve`](Self::resolve) past the cache: search and remember.
    #[inline(never)]
    fn resolve_miss(&mut self, od: &ObjectDictionary, index: u16, sub: u8) -> Result<EntryRef, SdoAbort> {
        let key = (u32::from(index) << 8) | u32::from(sub);
        let slot = &mut self.cache[usize::from(index ^ u16::from(sub)) & (CACHE_SLOTS - 1)];
        let r = od
            .find(index, sub)
            .map_err(|e| if e == SdoAbort::NO_OBJECT { self.config.missing_object } else { e })?;
        let objs = od.objects();
        if let Ok(p) = objs.binary_search_by_key(&index, |o| o.index)
            && let Ok(sp) = objs[p].subs().binary_search_by_key(&sub, |s| s.sub)
        {
            *slot = Slot { key, obj: p as u32, sub: sp as u32, r: Some(r) };
        }
        Ok(r)
    }

    /// Send an abort for the running transfer and go idle.
    #[inline]
    fn abort(&mut self, code: SdoAbort, out: &mut impl TxSink) {
        let m = self.mux;
        self.abort_with(&m, code, out);
    }

    /// Send an abort for `mux` (index LSB, MSB, sub-index) and go idle.
    fn abort_with(&mut self, mux: &[u8; 3], code: SdoAbort, out: &mut impl TxSink) {
        self.state = State::Idle;
        let c = code.0.to_le_bytes();
        self.send([CS_ABORT, mux[0], mux[1], mux[2], c[0], c[1], c[2], c[3]], out);
    }

    /// Emit one response on the server→client COB-ID.
    #[inline]
    fn send(&self, data: [u8; 8], out: &mut impl TxSink) {
        let frame = match self.tx {
            CanId::Standard(id) => Frame::new8(id, data),
            // Range checked by `set_cob_ids`, so this cannot fail.
            id => match Frame::try_new(id, &data) {
                Ok(f) => f,
                Err(_) => return,
            },
        };
        out.send(frame);
    }
}

/// True for the initiate commands of every protocol (ccs 1, 2; block
/// upload cs=0; block download cs=0).
#[inline]
fn is_initiate(b0: u8) -> bool {
    match scs(b0) {
        INITIATE_DOWNLOAD | INITIATE_UPLOAD => true,
        BLOCK_UPLOAD => b0 & 0x03 == BLOCK_INITIATE,
        BLOCK_DOWNLOAD => b0 & 0x01 == BLOCK_INITIATE,
        _ => false,
    }
}

#[inline]
fn valid_id(id: CanId) -> bool {
    match id {
        CanId::Standard(v) => v <= 0x7FF,
        CanId::Extended(v) => v <= 0x1FFF_FFFF,
    }
}

/// Copy up to 7 bytes of `src` into segment bytes 1..8: a fixed 7-byte move
/// for every full segment (a variable-length copy is a memcpy call, which
/// was a third of the segmented upload cost).
#[inline(always)]
fn copy_segment(seg: &mut [u8; 8], src: &[u8]) {
    if let Some(full) = src.first_chunk::<7>() {
        seg[1..8].copy_from_slice(full);
    } else {
        for (d, s) in seg[1..].iter_mut().zip(src) {
            *d = *s;
        }
    }
}

/// Bytes a download of `dt` takes when an expedited download does not say
/// (e=1, s=0): the object's own size, or all 4 bytes for larger/variable types.
#[inline]
fn expedited_unsized_len(dt: DataType) -> usize {
    match dt.fixed_size() {
        Some(n) if n <= 4 => n,
        _ => 4,
    }
}
