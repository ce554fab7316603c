//! CoE: CAN application protocol over EtherCAT (ETG.1000.6 §5.6).
//!
//! The SDO server (`sdo_server.rs`: initiate, expedited and normal
//! transfers, aborts; `segmented.rs`: segments), complete access
//! (`complete.rs`), SDO Information (`info.rs`, its wire format in
//! `info_codec.rs`, which a master uses too) and emergencies
//! (`emergency.rs`). The CoE header is 2 bytes: a 9-bit number (0 for every
//! service used here), 3 reserved bits and the service in bits 12-15
//! (ETG.1000.6 §5.6.1 Table 29).
//!
//! Choices, each covered by a test:
//! - **A new initiate while a segmented transfer runs starts over**; the old
//!   transfer is dropped silently (a master that lost track simply begins
//!   again, as on the CAN side).
//! - **A segment with no transfer to belong to** is answered with
//!   `0504 0001` for the running transfer's object (0000h:00 when idle).
//! - **Timeouts drop a transfer silently.** An unsolicited abort would sit
//!   in SM1 and be taken, by a master that does not drain the mailbox
//!   first, as the answer to its next request.
//! - **Any new CoE request ends a fragmented SDO Information answer**: the
//!   master has stopped reading it.

mod complete;
pub(crate) mod emergency;
mod info;
pub mod info_codec;
mod sdo_server;
mod segmented;

use crate::access::ObjectAccess;
use crate::mailbox::{MailboxErrorCode, ResponseQueue};
use alloc::vec::Vec;
use drivebus_base::{Duration, Instant};

pub use complete::split_image;
pub use info::list_type;

/// CoE services (ETG.1000.6 §5.6.1 Table 29).
pub mod service {
    /// Emergency.
    pub const EMERGENCY: u8 = 0x01;
    /// SDO request (and abort, in both directions).
    pub const SDO_REQUEST: u8 = 0x02;
    /// SDO response.
    pub const SDO_RESPONSE: u8 = 0x03;
    /// TxPDO over the mailbox.
    pub const TXPDO: u8 = 0x04;
    /// RxPDO over the mailbox.
    pub const RXPDO: u8 = 0x05;
    /// TxPDO remote request.
    pub const TXPDO_REMOTE: u8 = 0x06;
    /// RxPDO remote request.
    pub const RXPDO_REMOTE: u8 = 0x07;
    /// SDO Information.
    pub const SDO_INFO: u8 = 0x08;
}

/// The SDO abort codes EtherCAT adds to the CiA 301 list (ETG.1000.6, SDO
/// abort codes). The CiA 301 codes are the constants of `SdoAbort`.
pub mod abort {
    use drivebus_od::SdoAbort;
    /// `0601 0003`: sub-index cannot be written, sub 0 must be 0 first.
    pub const SI0_MUST_BE_ZERO: SdoAbort = SdoAbort(0x0601_0003);
    /// `0601 0004`: complete access not supported for objects of variable length.
    pub const CA_VARIABLE_LENGTH: SdoAbort = SdoAbort(0x0601_0004);
    /// `0601 0005`: object length exceeds the mailbox size.
    pub const EXCEEDS_MAILBOX: SdoAbort = SdoAbort(0x0601_0005);
    /// `0601 0006`: object mapped to an RxPDO, SDO download blocked.
    pub const MAPPED_TO_RXPDO: SdoAbort = SdoAbort(0x0601_0006);
}

/// CoE part of the server configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CoeConfig {
    pub(crate) timeout: Duration,
    pub(crate) max_download: usize,
    pub(crate) complete_access: bool,
    pub(crate) sdo_info: bool,
}

/// Index, sub-index and complete-access flag of a transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Mux {
    pub(crate) index: u16,
    pub(crate) sub: u8,
    pub(crate) ca: bool,
}

impl Mux {
    const NONE: Mux = Mux { index: 0, sub: 0, ca: false };
}

/// A multi-mailbox SDO transfer in progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Transfer {
    Idle,
    /// Segmented upload: `self.buf[pos..]` still to send; next request's toggle.
    Upload {
        mux: Mux,
        pos: usize,
        toggle: bool,
    },
    /// Segmented download into `self.buf` until `total` bytes; next toggle.
    Download {
        mux: Mux,
        total: usize,
        toggle: bool,
    },
}

/// Where a response goes: the queue and the mailbox's data capacity.
pub(crate) struct Out<'a> {
    pub(crate) q: &'a mut ResponseQueue,
    /// Bytes of service data a response may carry (SM1 size minus header).
    pub(crate) cap: usize,
}

/// The CoE protocol machine.
#[derive(Clone, Debug)]
pub(crate) struct CoeServer {
    pub(crate) cfg: CoeConfig,
    transfer: Transfer,
    /// Upload snapshot, download accumulator or complete-access image;
    /// capacity kept across transfers.
    buf: Vec<u8>,
    deadline: Instant,
    info: info::Fragments,
}

impl CoeServer {
    pub(crate) fn new(cfg: CoeConfig) -> Self {
        CoeServer {
            cfg,
            transfer: Transfer::Idle,
            buf: Vec::new(),
            deadline: Instant::ZERO,
            info: info::Fragments::default(),
        }
    }

    /// Drop every transfer silently (mailbox reset, ESM change).
    pub(crate) fn reset(&mut self) {
        self.transfer = Transfer::Idle;
        self.info.cancel();
    }

    /// A conversation of several mailboxes is under way: a segmented
    /// transfer or the rest of a fragmented SDO Information answer.
    pub(crate) fn busy(&self) -> bool {
        self.transfer != Transfer::Idle || self.info.pending()
    }

    /// SDO Information fragments wait to be sent (they need no request).
    pub(crate) fn fragments_pending(&self) -> bool {
        self.info.pending()
    }

    /// Deadline of the running transfer.
    pub(crate) fn deadline(&self) -> Option<Instant> {
        self.busy().then_some(self.deadline)
    }

    /// Drop a transfer whose deadline has passed.
    pub(crate) fn expire(&mut self, now: Instant) {
        if self.busy() && now >= self.deadline {
            self.reset();
        }
    }

    /// Produce the next fragment of an SDO Information answer, if one is
    /// waiting (called when the response queue is empty).
    pub(crate) fn next_fragment(&mut self, now: Instant, out: &mut Out<'_>) -> bool {
        if !self.info.next(out) {
            return false;
        }
        self.deadline = now + self.cfg.timeout;
        true
    }

    /// One CoE mailbox: `body` is the service data (CoE header first),
    /// exactly `length` bytes of the mailbox header.
    pub(crate) fn handle<A: ObjectAccess + ?Sized>(
        &mut self,
        body: &[u8],
        now: Instant,
        objects: &mut A,
        out: &mut Out<'_>,
    ) {
        self.expire(now);
        self.info.cancel();
        let Some(&hi) = body.get(1) else {
            out.q.push_error(MailboxErrorCode::SIZE_TOO_SHORT);
            return;
        };
        match hi >> 4 {
            service::SDO_REQUEST if body.len() < sdo_server::SDO_LEN => {
                out.q.push_error(MailboxErrorCode::SIZE_TOO_SHORT);
            }
            service::SDO_REQUEST => self.sdo_request(body, now, objects, out),
            service::SDO_INFO if !self.cfg.sdo_info => {
                out.q.push_error(MailboxErrorCode::SERVICE_NOT_SUPPORTED);
            }
            service::SDO_INFO if body.len() < info_codec::HEADER_LEN => {
                out.q.push_error(MailboxErrorCode::SIZE_TOO_SHORT);
            }
            service::SDO_INFO => self.info.handle(body, objects, out),
            // Valid CoE services this slave does not offer as a server:
            // emergencies and responses come from a slave, PDOs over the
            // mailbox are not supported.
            service::EMERGENCY..=service::RXPDO_REMOTE => {
                out.q.push_error(MailboxErrorCode::SERVICE_NOT_SUPPORTED);
            }
            _ => {
                out.q.push_error(MailboxErrorCode::INVALID_HEADER);
            }
        }
        if self.info.pending() {
            self.deadline = now + self.cfg.timeout;
        }
    }
}
