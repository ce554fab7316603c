//! The mailbox data-link layer (ETG.1000.4 §5.6): the 6-byte header, the
//! mailbox error reply, the response counter and the bounded response queue.

use alloc::vec::Vec;

/// Length of the mailbox header that precedes every mailbox service.
pub const HEADER_LEN: usize = 6;

/// Smallest mailbox (SM0/SM1 length) the server accepts. Every CoE and FoE
/// response of this crate fits in 32 bytes (an SDO Info entry description
/// without optional fields is 22 bytes, an emergency 16).
pub const MIN_MAILBOX_SIZE: usize = 32;

/// Largest mailbox: a whole datagram in one Ethernet frame (1500 bytes minus
/// the 2-byte EtherCAT header, the 10-byte datagram header and the 2-byte
/// working counter).
pub const MAX_MAILBOX_SIZE: usize = 1486;

/// The protocol carried in a mailbox (header byte 5, bits 0-3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MailboxType {
    /// 0: mailbox error reply (slave to master only).
    Error,
    /// 1: ADS over EtherCAT.
    Aoe,
    /// 2: Ethernet over EtherCAT.
    Eoe,
    /// 3: CAN application protocol over EtherCAT.
    Coe,
    /// 4: File access over EtherCAT.
    Foe,
    /// 5: Servo drive profile over EtherCAT.
    Soe,
    /// 15: vendor specific.
    Vendor,
    /// 6..=14: reserved.
    Reserved(u8),
}

impl MailboxType {
    /// From the 4-bit type field (higher bits are ignored).
    pub const fn from_bits(bits: u8) -> MailboxType {
        match bits & 0x0F {
            0 => MailboxType::Error,
            1 => MailboxType::Aoe,
            2 => MailboxType::Eoe,
            3 => MailboxType::Coe,
            4 => MailboxType::Foe,
            5 => MailboxType::Soe,
            15 => MailboxType::Vendor,
            other => MailboxType::Reserved(other),
        }
    }

    /// The 4-bit type field.
    pub const fn bits(self) -> u8 {
        match self {
            MailboxType::Error => 0,
            MailboxType::Aoe => 1,
            MailboxType::Eoe => 2,
            MailboxType::Coe => 3,
            MailboxType::Foe => 4,
            MailboxType::Soe => 5,
            MailboxType::Vendor => 15,
            MailboxType::Reserved(b) => b & 0x0F,
        }
    }
}

/// The mailbox header (ETG.1000.4 §5.6): `length` (bytes of service data
/// after the header), `address` (station address of the source on master
/// requests; 0 on our replies, the master being the destination), channel
/// (6 bits, 0), priority (2 bits), type (4 bits) and counter (3 bits; the
/// byte's top bit is reserved and dropped).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MailboxHeader {
    /// Length of the service data following the header.
    pub length: u16,
    /// Station address.
    pub address: u16,
    /// Channel, 0..=63 (0 is the only valid value).
    pub channel: u8,
    /// Priority, 0..=3.
    pub priority: u8,
    /// Protocol.
    pub mailbox_type: MailboxType,
    /// Counter, 0..=7: 0 means "not counted", 1..=7 count requests (and,
    /// separately, responses) and wrap from 7 to 1.
    pub counter: u8,
}

impl MailboxHeader {
    /// Read a header from the first 6 bytes; `None` if there are fewer.
    pub fn decode(bytes: &[u8]) -> Option<MailboxHeader> {
        let b: &[u8; HEADER_LEN] = bytes.first_chunk()?;
        Some(MailboxHeader {
            length: u16::from_le_bytes([b[0], b[1]]),
            address: u16::from_le_bytes([b[2], b[3]]),
            channel: b[4] & 0x3F,
            priority: b[4] >> 6,
            mailbox_type: MailboxType::from_bits(b[5]),
            counter: (b[5] >> 4) & 0x07,
        })
    }

    /// The 6 header bytes (fields are masked to their widths).
    pub fn encode(&self) -> [u8; HEADER_LEN] {
        let l = self.length.to_le_bytes();
        let a = self.address.to_le_bytes();
        [
            l[0],
            l[1],
            a[0],
            a[1],
            (self.channel & 0x3F) | ((self.priority & 0x03) << 6),
            self.mailbox_type.bits() | ((self.counter & 0x07) << 4),
        ]
    }
}

/// The counter that follows `c` (1..=7, 7 wraps to 1; 0 is never produced).
#[inline]
pub const fn next_counter(c: u8) -> u8 {
    if c >= 7 { 1 } else { c + 1 }
}

/// Detail code of a mailbox error reply (ETG.1000.4 §5.6, service 1
/// "mailbox command").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MailboxErrorCode(pub u16);

impl MailboxErrorCode {
    /// 0x01: the 6-byte mailbox header is wrong (e.g. type 0 from the master).
    pub const SYNTAX: Self = Self(0x01);
    /// 0x02: the mailbox protocol is not supported.
    pub const UNSUPPORTED_PROTOCOL: Self = Self(0x02);
    /// 0x03: the channel field is not 0.
    pub const INVALID_CHANNEL: Self = Self(0x03);
    /// 0x04: the service of the mailbox protocol is not supported.
    pub const SERVICE_NOT_SUPPORTED: Self = Self(0x04);
    /// 0x05: the protocol header (after the mailbox header) is wrong.
    pub const INVALID_HEADER: Self = Self(0x05);
    /// 0x06: the mailbox data is too short for the protocol.
    pub const SIZE_TOO_SHORT: Self = Self(0x06);
    /// 0x07: no resources to process the request.
    pub const NO_MORE_MEMORY: Self = Self(0x07);
    /// 0x08: the length field is inconsistent with the data.
    pub const INVALID_SIZE: Self = Self(0x08);
    /// 0x09: the service is already in work.
    pub const SERVICE_IN_WORK: Self = Self(0x09);
}

/// Service data of a mailbox error reply: type `0x0001` (mailbox command),
/// then the detail code.
pub(crate) fn error_body(code: MailboxErrorCode) -> [u8; 4] {
    let d = code.0.to_le_bytes();
    [0x01, 0x00, d[0], d[1]]
}

/// Little-endian writers for response bodies.
pub(crate) trait Put {
    fn put_u16(&mut self, v: u16);
    fn put_u32(&mut self, v: u32);
}

impl Put for Vec<u8> {
    #[inline]
    fn put_u16(&mut self, v: u16) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    #[inline]
    fn put_u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
}

/// A bounded FIFO of complete response mailboxes (header included), in
/// buffers allocated once. The last slot is kept for mailbox error replies,
/// so a request that finds the queue full can still be refused with
/// "no more memory" instead of vanishing.
#[derive(Clone, Debug)]
pub(crate) struct ResponseQueue {
    slots: Vec<Vec<u8>>,
    head: usize,
    len: usize,
    tx_size: usize,
    /// Written instead of a queued slot if the queue is full, and dropped:
    /// never reached (callers check for room and a request yields at most
    /// one response), but a full queue must not overwrite its head.
    overflow: Vec<u8>,
    /// Mailbox error replies queued so far.
    pub(crate) errors: u64,
}

impl ResponseQueue {
    /// `n` slots (at least 2) of `tx_size` bytes.
    pub(crate) fn new(n: usize, tx_size: usize) -> Self {
        let n = n.max(2);
        let slots = (0..n).map(|_| Vec::with_capacity(tx_size)).collect();
        ResponseQueue { slots, head: 0, len: 0, tx_size, overflow: Vec::with_capacity(tx_size), errors: 0 }
    }

    /// Change the mailbox size (drops queued responses).
    pub(crate) fn resize(&mut self, tx_size: usize) {
        self.clear();
        self.tx_size = tx_size;
        for s in self.slots.iter_mut().chain(core::iter::once(&mut self.overflow)) {
            s.clear();
            s.reserve(tx_size);
        }
    }

    pub(crate) fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Room for one more protocol response (the reserve slot excluded).
    pub(crate) fn has_room(&self) -> bool {
        self.len + 1 < self.slots.len()
    }

    /// Room for a mailbox error reply (the reserve slot included).
    pub(crate) fn has_error_room(&self) -> bool {
        self.len < self.slots.len()
    }

    /// The slot at the tail, cleared, with the 6 header bytes reserved. The
    /// caller appends the service data and then calls [`Self::commit`];
    /// calling `begin` again before that starts the same slot over.
    /// Callers check [`Self::has_room`] first.
    pub(crate) fn begin(&mut self) -> &mut Vec<u8> {
        let n = self.slots.len();
        let slot =
            if self.len < n { &mut self.slots[(self.head + self.len) % n] } else { &mut self.overflow };
        slot.clear();
        slot.extend_from_slice(&[0; HEADER_LEN]);
        slot
    }

    /// Seal the slot filled after [`Self::begin`]: header length and type
    /// (the counter is set when the response leaves, see [`Self::pop_into`]).
    pub(crate) fn commit(&mut self, mailbox_type: MailboxType) {
        if self.len >= self.slots.len() {
            debug_assert!(false, "response queue overflow");
            return;
        }
        let n = self.slots.len();
        let tx = self.tx_size;
        let slot = &mut self.slots[(self.head + self.len) % n];
        // Bodies are sized from the mailbox length; a longer one is a bug
        // here, and truncating keeps the header honest instead of panicking.
        debug_assert!(slot.len() <= tx, "response of {} bytes in a {tx}-byte mailbox", slot.len());
        slot.truncate(tx);
        let length = slot.len().saturating_sub(HEADER_LEN) as u16;
        let h = MailboxHeader { length, address: 0, channel: 0, priority: 0, mailbox_type, counter: 0 };
        slot[..HEADER_LEN].copy_from_slice(&h.encode());
        self.len += 1;
    }

    /// Queue a mailbox error reply if there is any room left.
    pub(crate) fn push_error(&mut self, code: MailboxErrorCode) -> bool {
        if !self.has_error_room() {
            return false;
        }
        self.begin().extend_from_slice(&error_body(code));
        self.commit(MailboxType::Error);
        self.errors += 1;
        true
    }

    /// Move the oldest response into `out` (swapping buffers, no copy).
    pub(crate) fn pop_into(&mut self, out: &mut Vec<u8>) -> bool {
        if self.len == 0 {
            return false;
        }
        core::mem::swap(out, &mut self.slots[self.head]);
        self.head = (self.head + 1) % self.slots.len();
        self.len -= 1;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_from_ethercrab_capture() {
        // ethercrab 0.7.1 `decode_header` test, from a SOEM capture of an AKD:
        // length 10, CoE, counter 2.
        let h = MailboxHeader::decode(&[0x0a, 0x00, 0x00, 0x00, 0x00, 0x23, 0x00, 0x20]).unwrap();
        assert_eq!(h.length, 10);
        assert_eq!(h.mailbox_type, MailboxType::Coe);
        assert_eq!(h.counter, 2);
        assert_eq!(h.encode(), [0x0a, 0x00, 0x00, 0x00, 0x00, 0x23]);
        assert_eq!(MailboxHeader::decode(&[1, 2, 3, 4, 5]), None);
    }

    #[test]
    fn header_fields_are_masked() {
        let h = MailboxHeader {
            length: 0x1234,
            address: 0xBEEF,
            channel: 0xFF,
            priority: 0xFF,
            mailbox_type: MailboxType::Reserved(0x1C),
            counter: 0x0F,
        };
        assert_eq!(h.encode(), [0x34, 0x12, 0xEF, 0xBE, 0xFF, 0x7C]);
        // The reserved top bit of byte 5 is dropped on decode.
        let d = MailboxHeader::decode(&[0, 0, 0, 0, 0x41, 0xF4]).unwrap();
        assert_eq!((d.channel, d.priority, d.mailbox_type, d.counter), (1, 1, MailboxType::Foe, 7));
    }

    #[test]
    fn counter_wraps_from_7_to_1() {
        assert_eq!(next_counter(0), 1);
        assert_eq!(next_counter(6), 7);
        assert_eq!(next_counter(7), 1);
    }

    #[test]
    fn error_reply_layout() {
        assert_eq!(error_body(MailboxErrorCode::UNSUPPORTED_PROTOCOL), [0x01, 0x00, 0x02, 0x00]);
    }

    #[test]
    fn queue_keeps_a_slot_for_errors() {
        let mut q = ResponseQueue::new(2, 32);
        assert!(q.has_room());
        q.begin().extend_from_slice(&[1, 2, 3]);
        q.commit(MailboxType::Coe);
        assert!(!q.has_room() && q.has_error_room());
        assert!(q.push_error(MailboxErrorCode::NO_MORE_MEMORY));
        assert!(!q.push_error(MailboxErrorCode::NO_MORE_MEMORY));
        let mut out = Vec::new();
        assert!(q.pop_into(&mut out));
        assert_eq!(out, [3, 0, 0, 0, 0, 3, 1, 2, 3]);
        assert!(q.pop_into(&mut out));
        assert_eq!(out, [4, 0, 0, 0, 0, 0, 1, 0, 7, 0]);
        assert!(!q.pop_into(&mut out) && q.is_empty());
    }
}
