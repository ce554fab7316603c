//! The LSS master's fastscan (CiA 305 v3.0.0 Fig. 46), sans-IO.
//!
//! Finds the 128-bit LSS address of one non-configured slave by asking
//! yes/no questions every such slave answers at once:
//!
//! 1. Reset: BitChecked 80h. No answer within the timeout: there is no
//!    non-configured slave in waiting.
//! 2. For each part (vendor, product, revision, serial), for bit 31 down
//!    to 0: send the bits found so far with the tested bit 0 and
//!    BitChecked = bit. A slave whose bits 31..bit equal that answers. An
//!    answer means some slave has a 0 there; **silence means the bit is 1**.
//!    Because a 0 is kept whenever any slave has it, the scan converges on
//!    the numerically lowest address among the slaves still taking part.
//! 3. Confirm the part with BitChecked 0 and LSSNext = the next part; the
//!    matching slave(s) move on. Silence here means the slave went away.
//!    The confirm of the serial number has LSSNext 0 (< LSSSub 3): the one
//!    slave that matched all 128 bits enters LSS configuration.
//!
//! Several slaves may answer the same question; on CAN their identical
//! frames merge, and the master only cares whether *any* answer came.
//! Known parts (e.g. the vendor-ID of the drives being commissioned) skip
//! the bit loop and are only confirmed.

use drivebus_can::{Duration, Frame, Instant, TxSink};

use crate::Identity;
use crate::codec::{LssField, LssResponse};
use crate::master;

/// How a fastscan ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FastScanOutcome {
    /// This slave's address; it is now in LSS configuration, alone, so the
    /// master can configure its node-ID and store.
    Found(Identity),
    /// Nobody answered the reset: no non-configured slave is in LSS waiting.
    NoneFound,
    /// The confirm of this part went unanswered (a slave left, a known part
    /// did not match, or frames were lost).
    Lost(LssField),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    Reset,
    Bit(u8),
    Confirm,
    Done,
}

/// The fastscan state machine. Drive it with [`FastScan::start`], then
/// [`FastScan::handle_frame`] for every received frame and
/// [`FastScan::poll`] at the deadline it returns.
#[derive(Clone, Debug)]
pub struct FastScan {
    timeout: Duration,
    early_advance: bool,
    known: [Option<u32>; 4],
    id: [u32; 4],
    sub: u8,
    step: Step,
    deadline: Option<Instant>,
    responded: bool,
    outcome: Option<FastScanOutcome>,
    frames_sent: u32,
}

impl FastScan {
    /// A fastscan waiting `timeout` for answers to each question. The
    /// timeout must exceed the slowest slave's response time: a late answer
    /// turns a 0 into a 1 (CANopenNode and canopen-python use 10..500 ms on
    /// real buses).
    pub fn new(timeout: Duration) -> FastScan {
        FastScan {
            timeout,
            early_advance: false,
            known: [None; 4],
            id: [0; 4],
            sub: 0,
            step: Step::Idle,
            deadline: None,
            responded: false,
            outcome: None,
            frames_sent: 0,
        }
    }

    /// Skip the bit loop for a part whose value is known; it is only confirmed.
    pub fn with_known(mut self, field: LssField, value: u32) -> FastScan {
        self.known[usize::from(field.index())] = Some(value);
        self
    }

    /// Move to the next question as soon as one answer arrives instead of
    /// waiting out the timeout. Faster, but only safe where every slave
    /// answers within the same frame time (their answers merge on the bus):
    /// a late answer would be taken for an answer to the next question. Off
    /// by default, as in the established stacks.
    pub fn with_early_advance(mut self, on: bool) -> FastScan {
        self.early_advance = on;
        self
    }

    /// (Re)start the scan: sends the reset frame.
    pub fn start(&mut self, now: Instant, out: &mut impl TxSink) {
        self.id = [0; 4];
        self.sub = 0;
        self.outcome = None;
        self.frames_sent = 0;
        self.step = Step::Reset;
        self.send(now, master::fastscan_reset(), out);
    }

    /// True between [`FastScan::start`] and the outcome.
    #[inline]
    pub fn is_running(&self) -> bool {
        matches!(self.step, Step::Reset | Step::Bit(_) | Step::Confirm)
    }

    /// The outcome once the scan has ended.
    #[inline]
    pub fn outcome(&self) -> Option<FastScanOutcome> {
        self.outcome
    }

    /// Fastscan frames sent since the last start (33 per scanned part, 1 per
    /// known part, plus the reset).
    #[inline]
    pub fn frames_sent(&self) -> u32 {
        self.frames_sent
    }

    /// Handle a received frame: an identify slave (4Fh) on 7E4h counts as
    /// an answer to the current question; everything else is ignored.
    /// Returns the outcome if this frame ended the scan.
    pub fn handle_frame(
        &mut self,
        frame: &Frame,
        now: Instant,
        out: &mut impl TxSink,
    ) -> Option<FastScanOutcome> {
        if !self.is_running() || LssResponse::from_frame(frame) != Some(LssResponse::IdentifySlave) {
            return None;
        }
        self.responded = true;
        if self.early_advance {
            self.advance(now, out);
            return self.outcome;
        }
        None
    }

    /// Evaluate the current question once its timeout has passed and ask
    /// the next. Returns the next deadline, `None` when not running.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if let Some(deadline) = self.deadline
            && self.is_running()
            && now >= deadline
        {
            self.advance(now, out);
        }
        if self.is_running() { self.deadline } else { None }
    }

    fn send(&mut self, now: Instant, frame: Frame, out: &mut impl TxSink) {
        self.responded = false;
        self.deadline = Some(now + self.timeout);
        self.frames_sent = self.frames_sent.saturating_add(1);
        out.send(frame);
    }

    fn finish(&mut self, outcome: FastScanOutcome) {
        self.step = Step::Done;
        self.deadline = None;
        self.outcome = Some(outcome);
    }

    /// The current question has been answered (or timed out): record the
    /// result and ask the next one.
    fn advance(&mut self, now: Instant, out: &mut impl TxSink) {
        let sub = usize::from(self.sub & 3);
        match self.step {
            Step::Reset => {
                if !self.responded {
                    return self.finish(FastScanOutcome::NoneFound);
                }
                self.begin_part(now, out);
            }
            Step::Bit(bit) => {
                if !self.responded {
                    self.id[sub] |= 1 << bit;
                }
                if bit == 0 {
                    self.ask_confirm(now, out);
                } else {
                    self.ask_bit(bit - 1, now, out);
                }
            }
            Step::Confirm => {
                if !self.responded {
                    let field = LssField::from_index(self.sub).unwrap_or(LssField::Vendor);
                    return self.finish(FastScanOutcome::Lost(field));
                }
                if self.sub >= 3 {
                    let [vendor_id, product_code, revision, serial] = self.id;
                    return self.finish(FastScanOutcome::Found(Identity {
                        vendor_id,
                        product_code,
                        revision,
                        serial,
                    }));
                }
                self.sub += 1;
                self.begin_part(now, out);
            }
            Step::Idle | Step::Done => {}
        }
    }

    fn begin_part(&mut self, now: Instant, out: &mut impl TxSink) {
        let sub = usize::from(self.sub & 3);
        match self.known[sub] {
            Some(value) => {
                self.id[sub] = value;
                self.ask_confirm(now, out);
            }
            None => {
                self.id[sub] = 0;
                self.ask_bit(31, now, out);
            }
        }
    }

    /// Ask whether some slave has bits 31..`bit` equal to the bits found so
    /// far with `bit` = 0. LSSNext = LSSSub, so matching slaves stay on this part.
    fn ask_bit(&mut self, bit: u8, now: Instant, out: &mut impl TxSink) {
        self.step = Step::Bit(bit);
        let frame = master::fastscan(self.id[usize::from(self.sub & 3)], bit, self.sub, self.sub);
        self.send(now, frame, out);
    }

    /// Confirm the whole part (BitChecked 0) and point the slave at the next
    /// one; after the serial number LSSNext wraps to 0.
    fn ask_confirm(&mut self, now: Instant, out: &mut impl TxSink) {
        self.step = Step::Confirm;
        let next = (self.sub + 1) & 3;
        let frame = master::fastscan(self.id[usize::from(self.sub & 3)], 0, self.sub, next);
        self.send(now, frame, out);
    }
}
