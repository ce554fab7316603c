//! Fault injection rules and the deterministic PRNG behind probabilities.
//!
//! [`FaultRule`] is the one rule type of the project, here beside the
//! frame it matches: the simulated bus (`drivebus_bus::Bus::add_fault`)
//! and the real-time hub of `drivebus_transport` both apply it. A rule
//! names a transmitting station by its number on that bus.

use crate::Frame;
use alloc::boxed::Box;
use core::fmt;
use core::ops::{Bound, RangeBounds};
use core::time::Duration;

pub use drivebus_base::{Recurrence, XorShift64};

/// What a rule does to a matching transmission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultAction {
    /// The frame occupies the bus but no receiver gets it (and it is not logged).
    Drop,
    /// A bit is flipped on the wire: every receiver detects a CRC error and
    /// sends an error frame, the transmitter's error counter rises by 8 and it
    /// retransmits the frame automatically (it competes in arbitration again).
    Corrupt,
    /// Receivers get altered data with a valid CRC, as if the corruption
    /// escaped detection. `xor` is applied to the data bytes; `None` flips one
    /// pseudo-random data bit. Frames without data are delivered unaltered.
    CorruptSilently {
        /// Mask XORed onto the payload, or `None` for one random bit.
        xor: Option<[u8; 8]>,
    },
    /// Delivered (and logged) this long after its end of frame. The bus time
    /// is spent as usual.
    Delay(Duration),
    /// Delivered, then transmitted again (as after an ACK error seen only by
    /// the transmitter): receivers get it twice. Rules do not apply to that
    /// second transmission.
    Duplicate,
    /// The transmitter goes bus-off: the frame is destroyed by an error frame
    /// and the node's queue is flushed.
    BusOff,
}

/// A frame predicate for [`FaultRule::when`] (`Send` so a rule can be
/// handed to a hub shared by threads).
type Predicate = Box<dyn Fn(&Frame) -> bool + Send + Sync>;

/// A fault injection rule: which transmissions it matches and what it does.
///
/// A rule matches by identifier range, transmitting station and a
/// predicate (all optional, all must hold); its [`Recurrence`] then
/// decides which matches it fires on.
/// Rules are tried in the order added; at most one fires per transmission.
pub struct FaultRule {
    action: FaultAction,
    ids: Option<(u32, u32)>,
    extended: Option<bool>,
    from: Option<u32>,
    predicate: Option<Predicate>,
    pick: Recurrence,
}

impl fmt::Debug for FaultRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FaultRule")
            .field("action", &self.action)
            .field("ids", &self.ids)
            .field("from", &self.from)
            .field("pick", &self.pick)
            .finish_non_exhaustive()
    }
}

impl FaultRule {
    /// A rule with `action` matching every transmission, always, forever.
    pub fn new(action: FaultAction) -> Self {
        FaultRule {
            action,
            ids: None,
            extended: None,
            from: None,
            predicate: None,
            pick: Recurrence::always(),
        }
    }
    /// See [`FaultAction::Drop`].
    pub fn drop_frames() -> Self {
        Self::new(FaultAction::Drop)
    }
    /// See [`FaultAction::Corrupt`].
    pub fn corrupt() -> Self {
        Self::new(FaultAction::Corrupt)
    }
    /// See [`FaultAction::CorruptSilently`] (one random bit).
    pub fn corrupt_silently() -> Self {
        Self::new(FaultAction::CorruptSilently { xor: None })
    }
    /// See [`FaultAction::CorruptSilently`] with a fixed mask.
    pub fn corrupt_with(xor: [u8; 8]) -> Self {
        Self::new(FaultAction::CorruptSilently { xor: Some(xor) })
    }
    /// See [`FaultAction::Delay`].
    pub fn delay(by: Duration) -> Self {
        Self::new(FaultAction::Delay(by))
    }
    /// See [`FaultAction::Duplicate`].
    pub fn duplicate() -> Self {
        Self::new(FaultAction::Duplicate)
    }
    /// See [`FaultAction::BusOff`].
    pub fn bus_off() -> Self {
        Self::new(FaultAction::BusOff)
    }

    /// Only identifiers (raw numeric value) in `range`.
    pub fn ids(mut self, range: impl RangeBounds<u32>) -> Self {
        let lo = match range.start_bound() {
            Bound::Included(&v) => v,
            Bound::Excluded(&v) => v.saturating_add(1),
            Bound::Unbounded => 0,
        };
        let hi = match range.end_bound() {
            Bound::Included(&v) => v,
            Bound::Excluded(&v) => v.saturating_sub(1),
            Bound::Unbounded => u32::MAX,
        };
        self.ids = Some((lo, hi));
        self
    }
    /// Only this identifier.
    pub fn id(self, id: u32) -> Self {
        self.ids(id..=id)
    }
    /// Only extended (`true`) or only standard (`false`) identifiers.
    pub fn extended(mut self, extended: bool) -> Self {
        self.extended = Some(extended);
        self
    }
    /// Only frames transmitted by this station (its number on the bus:
    /// `drivebus_bus::NodeId`/`ProbeId`, a hub participant).
    pub fn from(mut self, station: impl Into<u32>) -> Self {
        self.from = Some(station.into());
        self
    }
    /// Only frames for which `pred` holds.
    pub fn when(mut self, pred: impl Fn(&Frame) -> bool + Send + Sync + 'static) -> Self {
        self.predicate = Some(Box::new(pred));
        self
    }
    /// Let the first `n` matching transmissions through.
    pub fn skip(mut self, n: u32) -> Self {
        self.pick = self.pick.skip(n);
        self
    }
    /// After the skipped matches, take only every `n`-th match (`n` ≥ 1:
    /// the 1st, the `n+1`-th, …).
    pub fn every(mut self, n: u32) -> Self {
        self.pick = self.pick.every(n);
        self
    }
    /// Fire at most `n` times.
    pub fn times(mut self, n: u32) -> Self {
        self.pick = self.pick.times(n);
        self
    }
    /// Fire with probability `p` (clamped to 0..=1) on each match, drawn from
    /// the bus's seeded PRNG.
    pub fn probability(mut self, p: f64) -> Self {
        self.pick = self.pick.probability(p);
        self
    }
    /// How many times the rule has fired.
    pub fn fired(&self) -> u32 {
        self.pick.fired()
    }
    /// What the rule does when it fires.
    pub fn action(&self) -> FaultAction {
        self.action
    }
    /// Whether the rule will never fire again (`times` used up).
    pub fn is_spent(&self) -> bool {
        self.pick.is_spent()
    }

    fn matches(&self, frame: &Frame, from: u32) -> bool {
        if let Some((lo, hi)) = self.ids {
            let id = frame.id().raw();
            if id < lo || id > hi {
                return false;
            }
        }
        if self.extended.is_some_and(|e| e != frame.id().is_extended()) {
            return false;
        }
        if self.from.is_some_and(|n| n != from) {
            return false;
        }
        self.predicate.as_ref().is_none_or(|p| p(frame))
    }

    /// Decides whether the rule fires for this transmission by station
    /// `from`, updating its counters; `rng` draws the probability.
    pub fn try_fire(&mut self, frame: &Frame, from: u32, rng: &mut XorShift64) -> bool {
        if self.pick.is_spent() || !self.matches(frame, from) {
            return false;
        }
        self.pick.fire(rng)
    }
}

/// `frame` with [`FaultAction::CorruptSilently`] applied: `xor` onto its
/// data, or one bit drawn from `rng` when `None`; frames without data
/// come back unaltered.
pub fn corrupt_data(frame: &Frame, xor: Option<[u8; 8]>, rng: &mut XorShift64) -> Frame {
    let data = frame.data();
    if data.is_empty() {
        return *frame;
    }
    let mut buf = [0u8; 8];
    let n = data.len().min(8);
    buf[..n].copy_from_slice(&data[..n]);
    match xor {
        Some(mask) => buf.iter_mut().zip(mask).for_each(|(b, m)| *b ^= m),
        None => {
            let bit = rng.below(n as u64 * 8) as usize;
            buf[bit / 8] ^= 0x80 >> (bit % 8);
        }
    }
    Frame::try_new(frame.id(), &buf[..n]).unwrap_or(*frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xorshift_is_deterministic_and_nonzero() {
        let mut a = XorShift64::new(0);
        let mut b = XorShift64::new(0);
        for _ in 0..100 {
            let x = a.next_u64();
            assert_eq!(x, b.next_u64());
        }
        assert_ne!(XorShift64::new(1).next_u64(), XorShift64::new(2).next_u64());
    }

    #[test]
    fn probability_edges() {
        let mut rng = XorShift64::new(7);
        let f = Frame::new(0x100, &[]);
        let mut never = FaultRule::drop_frames().probability(0.0);
        let mut always = FaultRule::drop_frames().probability(1.0);
        let mut nan = FaultRule::drop_frames().probability(f64::NAN);
        for _ in 0..50 {
            assert!(!never.try_fire(&f, 0, &mut rng));
            assert!(!nan.try_fire(&f, 0, &mut rng));
            assert!(always.try_fire(&f, 0, &mut rng));
        }
    }

    #[test]
    fn skip_every_times_count_matches() {
        let mut rng = XorShift64::new(1);
        let mut r = FaultRule::drop_frames().ids(0x100..=0x1FF).skip(1).every(2).times(2);
        let f = Frame::new(0x180, &[1]);
        let got: alloc::vec::Vec<bool> = (0..8).map(|_| r.try_fire(&f, 0, &mut rng)).collect();
        assert_eq!(got, [false, true, false, true, false, false, false, false]);
        assert!(r.is_spent());
        assert!(!r.try_fire(&Frame::new(0x80, &[]), 0, &mut rng));
    }
}
