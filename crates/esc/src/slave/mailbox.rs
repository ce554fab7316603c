//! Mailbox data link layer (ETG.1000.4 §5.6 "Mailbox", ETG.1000.6 §5.6).
//!
//! Requests arrive in the receive mailbox (SM0, master → slave); the
//! firmware reads the whole buffer (which frees it for the master) and
//! hands the message to the application. Responses and unsolicited
//! messages wait in two FIFO queues and go into the send mailbox (SM1) one
//! at a time whenever it is empty, responses first; an unsolicited message
//! (a CoE emergency) goes only when no response is queued and the mailbox
//! has been idle for [`super::SlaveConfig::unsolicited_quiet`].
//!
//! The framework sets the 3-bit counter of every message it sends
//! (1…7, wrapping to 1) and drops a request whose non-zero counter equals
//! the previous request's (a repeated frame). When the master toggles the
//! repeat request bit of SM1 (0x0806 + 8 bit 1), the last message the
//! master read is written again: a message still waiting unread in SM1 goes
//! back to the front of its queue, SM1 is emptied by deactivating it from
//! the PDI side, and the repeat acknowledge bit (0x0807 + 8 bit 1) follows.

use crate::esc::Esc;
use alloc::collections::VecDeque;
use alloc::vec::Vec;
use drivebus_base::{Duration, Instant};

/// Mailbox header length.
pub const HEADER_LEN: usize = 6;

/// Mailbox types (ETG.1000.4 Table 29).
pub mod mailbox_type {
    /// Error reply.
    pub const ERROR: u8 = 0x00;
    /// ADS over EtherCAT.
    pub const AOE: u8 = 0x01;
    /// Ethernet over EtherCAT.
    pub const EOE: u8 = 0x02;
    /// CANopen over EtherCAT.
    pub const COE: u8 = 0x03;
    /// File access over EtherCAT.
    pub const FOE: u8 = 0x04;
    /// Servo profile over EtherCAT.
    pub const SOE: u8 = 0x05;
    /// Vendor specific.
    pub const VOE: u8 = 0x0F;
}

/// Mailbox error reply codes (ETG.1000.4 Table 30).
pub mod mailbox_error {
    /// Syntax of the header is wrong.
    pub const SYNTAX: u16 = 0x0001;
    /// The protocol is not supported.
    pub const UNSUPPORTED_PROTOCOL: u16 = 0x0002;
    /// Channel field wrong.
    pub const INVALID_CHANNEL: u16 = 0x0003;
    /// Service not supported.
    pub const SERVICE_NOT_SUPPORTED: u16 = 0x0004;
    /// Invalid header.
    pub const INVALID_HEADER: u16 = 0x0005;
    /// Length of the data too short.
    pub const SIZE_TOO_SHORT: u16 = 0x0006;
    /// No more memory.
    pub const NO_MORE_MEMORY: u16 = 0x0007;
    /// Length of the data inconsistent.
    pub const INVALID_SIZE: u16 = 0x0008;
}

/// A FIFO of messages whose buffers are reused (no allocation once warm).
#[derive(Debug, Default)]
pub(crate) struct MessageQueue {
    q: VecDeque<Vec<u8>>,
    free: Vec<Vec<u8>>,
    depth: usize,
}

impl MessageQueue {
    fn new(depth: usize) -> Self {
        MessageQueue { q: VecDeque::with_capacity(depth), free: Vec::new(), depth }
    }

    fn push(&mut self, msg: &[u8]) -> bool {
        if self.q.len() >= self.depth {
            return false;
        }
        let mut b = self.free.pop().unwrap_or_default();
        b.clear();
        b.extend_from_slice(msg);
        self.q.push_back(b);
        true
    }

    fn push_front(&mut self, b: Vec<u8>) {
        self.q.push_front(b);
    }

    fn pop(&mut self) -> Option<Vec<u8>> {
        self.q.pop_front()
    }

    fn recycle(&mut self, b: Vec<u8>) {
        if self.free.len() < self.depth {
            self.free.push(b);
        }
    }

    fn len(&self) -> usize {
        self.q.len()
    }
}

/// Where the application puts mailbox messages.
#[derive(Debug)]
pub struct MailboxOut<'a> {
    responses: &'a mut MessageQueue,
    unsolicited: &'a mut MessageQueue,
    max_len: usize,
    dropped: &'a mut u32,
}

impl MailboxOut<'_> {
    /// Largest message the send mailbox holds (header included).
    pub fn max_len(&self) -> usize {
        self.max_len
    }

    /// Queues a response (a whole message, header first; the framework
    /// sets the counter). False if it is too long or the queue is full.
    pub fn respond(&mut self, msg: &[u8]) -> bool {
        let ok = msg.len() >= HEADER_LEN && msg.len() <= self.max_len && self.responses.push(msg);
        if !ok {
            *self.dropped += 1;
        }
        ok
    }

    /// Queues an unsolicited message (e.g. a CoE emergency); it never
    /// overtakes a queued response.
    pub fn unsolicited(&mut self, msg: &[u8]) -> bool {
        let ok = msg.len() >= HEADER_LEN && msg.len() <= self.max_len && self.unsolicited.push(msg);
        if !ok {
            *self.dropped += 1;
        }
        ok
    }

    /// Queues a mailbox error reply (ETG.1000.4 Table 30) to `request`.
    pub fn error_reply(&mut self, request: &[u8], code: u16) -> bool {
        let mut m = [0u8; HEADER_LEN + 4];
        m[0..2].copy_from_slice(&4u16.to_le_bytes());
        if request.len() >= 4 {
            m[2..4].copy_from_slice(&request[2..4]);
        }
        m[5] = mailbox_type::ERROR;
        m[6..8].copy_from_slice(&1u16.to_le_bytes());
        m[8..10].copy_from_slice(&code.to_le_bytes());
        self.respond(&m)
    }

    /// Messages queued and not yet sent (responses, unsolicited).
    pub fn pending(&self) -> (usize, usize) {
        (self.responses.len(), self.unsolicited.len())
    }
}

/// Mailbox state of one slave.
#[derive(Debug)]
pub(crate) struct Mailbox {
    pub rx_start: u16,
    pub rx_len: u16,
    pub tx_start: u16,
    pub tx_len: u16,
    pub tx_sm: usize,
    req: Vec<u8>,
    out: Vec<u8>,
    responses: MessageQueue,
    unsolicited: MessageQueue,
    in_sm: Option<(Vec<u8>, bool)>,
    last_read: Option<Vec<u8>>,
    last_counter: Option<u8>,
    counter: u8,
    pub last_activity: Instant,
    pub dropped: u32,
}

impl Mailbox {
    pub fn new(rx: (u16, u16), tx: (u16, u16), tx_sm: usize, depth: usize) -> Self {
        Mailbox {
            rx_start: rx.0,
            rx_len: rx.1,
            tx_start: tx.0,
            tx_len: tx.1,
            tx_sm,
            req: alloc::vec![0; usize::from(rx.1)],
            out: alloc::vec![0; usize::from(tx.1)],
            responses: MessageQueue::new(depth),
            unsolicited: MessageQueue::new(depth),
            in_sm: None,
            last_read: None,
            last_counter: None,
            counter: 0,
            last_activity: Instant::ZERO,
            dropped: 0,
        }
    }

    /// True if the slave has a mailbox at all.
    pub fn present(&self) -> bool {
        self.rx_len > 0 && self.tx_len > 0
    }

    /// An output handle for the application.
    pub fn out(&mut self) -> MailboxOut<'_> {
        MailboxOut {
            responses: &mut self.responses,
            unsolicited: &mut self.unsolicited,
            max_len: usize::from(self.tx_len),
            dropped: &mut self.dropped,
        }
    }

    /// The master filled the receive mailbox: read it (emptying it) and
    /// return the message to dispatch, or `None` for a repeated frame.
    /// Malformed messages are answered here with a mailbox error.
    pub fn take_request(&mut self, esc: &mut Esc, now: Instant) -> Option<usize> {
        self.last_activity = now;
        if !esc.pdi_read(self.rx_start, &mut self.req) {
            return None;
        }
        let len = usize::from(u16::from_le_bytes([self.req[0], self.req[1]]));
        let counter = (self.req[5] >> 4) & 0x07;
        if counter != 0 && Some(counter) == self.last_counter {
            return None;
        }
        self.last_counter = Some(counter);
        if HEADER_LEN + len > self.req.len() {
            let mut hdr = [0u8; HEADER_LEN];
            hdr.copy_from_slice(&self.req[..HEADER_LEN]);
            self.out().error_reply(&hdr, mailbox_error::INVALID_SIZE);
            return None;
        }
        Some(HEADER_LEN + len)
    }

    /// The request read by [`Mailbox::take_request`] and the output handle.
    pub fn request_and_out(&mut self, len: usize) -> (&[u8], MailboxOut<'_>) {
        let out = MailboxOut {
            responses: &mut self.responses,
            unsolicited: &mut self.unsolicited,
            max_len: usize::from(self.tx_len),
            dropped: &mut self.dropped,
        };
        (&self.req[..len], out)
    }

    /// The master read the send mailbox.
    pub fn on_read(&mut self, now: Instant) {
        self.last_activity = now;
        if let Some((m, _)) = self.in_sm.take()
            && let Some(old) = self.last_read.replace(m)
        {
            self.responses.recycle(old);
        }
    }

    fn sm_full(&self, esc: &Esc) -> Option<bool> {
        let sm = esc.sync_manager(self.tx_sm)?;
        (sm.enabled && sm.pdi_control & 1 == 0).then_some(sm.status & 0x08 != 0)
    }

    /// Puts the next message into an empty send mailbox.
    pub fn pump(&mut self, esc: &mut Esc, now: Instant, quiet: Duration) {
        if self.in_sm.is_some() || self.sm_full(esc) != Some(false) {
            return;
        }
        let (msg, response) = if let Some(m) = self.responses.pop() {
            (m, true)
        } else if self.unsolicited.len() > 0 && now >= self.last_activity + quiet {
            match self.unsolicited.pop() {
                Some(m) => (m, false),
                None => return,
            }
        } else {
            return;
        };
        self.counter = if self.counter >= 7 { 1 } else { self.counter + 1 };
        self.write(esc, msg, response, true);
    }

    fn write(&mut self, esc: &mut Esc, mut msg: Vec<u8>, response: bool, new_counter: bool) {
        if new_counter && msg.len() > 5 {
            msg[5] = (msg[5] & 0x8F) | (self.counter << 4);
        }
        let n = msg.len().min(self.out.len());
        self.out[..n].copy_from_slice(&msg[..n]);
        self.out[n..].fill(0);
        if esc.pdi_write(self.tx_start, &self.out) {
            self.in_sm = Some((msg, response));
        } else {
            self.requeue(msg, response);
        }
    }

    fn requeue(&mut self, msg: Vec<u8>, response: bool) {
        if response {
            self.responses.push_front(msg);
        } else {
            self.unsolicited.push_front(msg);
        }
    }

    /// Handles a change of the send mailbox's activate register: a toggled
    /// repeat request re-sends the last message the master read.
    pub fn on_sm_change(&mut self, esc: &mut Esc, now: Instant) {
        let base = 0x0800 + 8 * self.tx_sm as u16;
        let mut act = [0u8; 2];
        esc.pdi_read(base + 6, &mut act);
        let (request, ack) = (act[0] & 0x02, act[1] & 0x02);
        if request == ack {
            return;
        }
        self.last_activity = now;
        if let Some((m, response)) = self.in_sm.take() {
            self.requeue(m, response);
        }
        // Empty SM1 by deactivating it from the PDI side, then re-enable.
        esc.pdi_write(base + 7, &[(act[1] & !0x03) | 0x01 | ack]);
        esc.pdi_write(base + 7, &[(act[1] & !0x03) | ack]);
        if let Some(m) = self.last_read.take() {
            self.write(esc, m, true, false);
        }
        esc.pdi_write(base + 7, &[(act[1] & !0x03) | request]);
    }
}
