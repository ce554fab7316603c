//! Faults of the line (issue 17 §3): what the segment does to frames while
//! a fault is on, the same for every transport (in-process link, raw
//! socket), so a master meets them exactly as on a wire.

use crate::frame::{DATAGRAM_HEADER_LEN, DatagramHeader, ECAT_HEADER_LEN, ecat_header};
use alloc::vec::Vec;
use drivebus_base::Recurrence;

/// A fault of the line, on until [`Segment::clear_faults`](super::Segment::clear_faults).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineFault {
    /// The link behind slave `after` (0-based) is broken, as a pulled
    /// cable: `after` closes its port 1 and loops frames back, the slaves
    /// behind it neither see nor answer them (the working counter drops)
    /// and count a lost link (0x0310).
    Break {
        /// The last slave frames still reach.
        after: usize,
    },
    /// Frames lost on the master's cable on their way out: no slave sees
    /// them, no reply comes back.
    Lose(Recurrence),
    /// A bit error on the cable in front of slave `at` (0-based): the
    /// slaves before it process the frame, `at` and those behind it see a
    /// bad FCS and leave it unexecuted (their RX error counters 0x0300 and
    /// 0x0308 count it, and on the way back 0x0309 of the slaves before),
    /// and the master's NIC discards the reply.
    Corrupt {
        /// The first slave that sees the damage.
        at: usize,
        /// Which frames.
        pick: Recurrence,
    },
    /// Slave `slave` (0-based) miscounts: every datagram it counts in gets
    /// `skew` added to its working counter, so the master sees a working
    /// counter that does not match although the data moved.
    WkcSkew {
        /// The slave.
        slave: usize,
        /// Added to each of its increments (wrapping).
        skew: i16,
    },
    /// Slave `slave`'s (0-based) oscillator runs off by `ppb` (positive:
    /// fast) instead of its own drift: its DC control loop corrects up to
    /// ±500 ppm (`dc::MAX_FREQ_PPB`), beyond that its system time
    /// difference (0x092C) grows and SYNC0 wanders off the cycle.
    Drift {
        /// The slave.
        slave: usize,
        /// Frequency error in parts per billion.
        ppb: i32,
    },
    /// Slave `slave`'s (0-based) time stamps jitter: each one (receive
    /// times, system time reads, the compare that steers its DC control
    /// loop) is off by a random value in ±`amplitude_ns`
    /// ([`Esc::set_clock_jitter`](crate::Esc::set_clock_jitter)), drawn
    /// from a generator seeded with `seed`, so a run replays.
    Jitter {
        /// The slave.
        slave: usize,
        /// Largest deviation of a stamp, ns (at most 1 ms).
        amplitude_ns: u32,
        /// Seed of the generator.
        seed: u64,
    },
}

impl LineFault {
    /// True if the link behind slave `i` is broken by this fault.
    pub(super) fn breaks(&self, i: usize) -> bool {
        matches!(self, LineFault::Break { after } if *after == i)
    }
}

/// The working counters of the datagrams of an EtherCAT payload: their
/// offsets and values, into `out` (cleared first).
pub(super) fn working_counters(payload: &[u8], out: &mut Vec<(usize, u16)>) {
    out.clear();
    let Some((len, _)) = ecat_header(payload) else { return };
    let end = (ECAT_HEADER_LEN + len).min(payload.len());
    let mut pos = ECAT_HEADER_LEN;
    while let Some(h) = payload.get(pos..end).and_then(DatagramHeader::parse) {
        let total = h.total_len();
        if pos + total > end || total < DATAGRAM_HEADER_LEN + 2 {
            return;
        }
        let w = pos + total - 2;
        out.push((w, u16::from_le_bytes([payload[w], payload[w + 1]])));
        pos += total;
        if !h.more {
            return;
        }
    }
}

/// Adds `skew` to every working counter of `payload` that moved since
/// `before` ([`working_counters`] of the same payload).
pub(super) fn skew_counters(payload: &mut [u8], before: &[(usize, u16)], skew: i16) {
    for &(w, old) in before {
        let Some(b) = payload.get_mut(w..w + 2) else { continue };
        let now = u16::from_le_bytes([b[0], b[1]]);
        if now != old {
            b.copy_from_slice(&now.wrapping_add_signed(skew).to_le_bytes());
        }
    }
}
