//! Bus statistics a client can take from what it receives: load, frames
//! per second per COB-ID ([`LoadMeter`]), and the error frames and error
//! counters a transport reports ([`BusErrors`], SocketCAN).
//!
//! Sans-IO: the caller passes each frame with its time. A frame's length
//! on the wire is its exact stuffed bit count plus intermission
//! (`drivebus_can::timing`, the virtual bus's own pacing).

use std::collections::BTreeMap;

use drivebus_can::timing::frame_bits;
use drivebus_can::{CanId, Frame, Instant};

/// Frame, bit and per-identifier counts over a span of time.
#[derive(Clone, Debug, Default)]
pub struct LoadMeter {
    start: Option<Instant>,
    frames: u64,
    bits: u64,
    per_id: BTreeMap<CanId, (u64, u64)>,
}

/// One identifier's share of a [`LoadMeter`] span.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdLoad {
    /// The identifier.
    pub id: CanId,
    /// Frames seen.
    pub frames: u64,
    /// Frames per second over the span.
    pub per_second: f64,
    /// Bits on the wire (stuffing and intermission included).
    pub bits: u64,
}

/// What a [`LoadMeter`] measured.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// Length of the span \[s\].
    pub seconds: f64,
    /// Frames seen.
    pub frames: u64,
    /// Frames per second.
    pub per_second: f64,
    /// Bits on the wire.
    pub bits: u64,
    /// Bits per second.
    pub bits_per_second: f64,
    /// Fraction of the bus's capacity used (0..1), when the bit rate is known.
    pub load: Option<f64>,
    /// Per identifier, in identifier order.
    pub per_id: Vec<IdLoad>,
}

impl LoadMeter {
    /// An empty meter whose span starts at `now`.
    pub fn new(now: Instant) -> LoadMeter {
        LoadMeter { start: Some(now), ..LoadMeter::default() }
    }

    /// Counts `frame`, received at `now` (the span starts at the first frame
    /// when the meter was not given a start).
    pub fn record(&mut self, frame: &Frame, now: Instant) {
        self.start.get_or_insert(now);
        let bits = u64::from(frame_bits(frame).total());
        self.frames += 1;
        self.bits += bits;
        let e = self.per_id.entry(frame.id()).or_default();
        e.0 += 1;
        e.1 += bits;
    }

    /// The span from the start to `now`; `bitrate` (bit/s) gives the load.
    pub fn report(&self, now: Instant, bitrate: Option<u32>) -> LoadReport {
        let seconds = self.start.map_or(0.0, |s| now.saturating_duration_since(s).as_nanos() as f64 / 1e9);
        let rate = |n: u64| if seconds > 0.0 { n as f64 / seconds } else { 0.0 };
        let bits_per_second = rate(self.bits);
        LoadReport {
            seconds,
            frames: self.frames,
            per_second: rate(self.frames),
            bits: self.bits,
            bits_per_second,
            load: bitrate.filter(|&b| b > 0 && seconds > 0.0).map(|b| bits_per_second / f64::from(b)),
            per_id: self
                .per_id
                .iter()
                .map(|(&id, &(frames, bits))| IdLoad { id, frames, per_second: rate(frames), bits })
                .collect(),
        }
    }

    /// Starts a new span at `now`.
    pub fn reset(&mut self, now: Instant) {
        *self = LoadMeter::new(now);
    }
}

/// SocketCAN error class: bus-off (`CAN_ERR_BUSOFF`, linux/can/error.h).
const ERR_BUSOFF: u32 = 0x0040;
/// SocketCAN error class: controller problems (`CAN_ERR_CRTL`).
const ERR_CRTL: u32 = 0x0004;
/// SocketCAN error class: the counters are in data\[6\] and data\[7\] (`CAN_ERR_CNT`).
const ERR_CNT: u32 = 0x0200;

/// Error frames and error counters, as a transport reports them (SocketCAN
/// error frames; the other transports report none).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BusErrors {
    /// Error frames received.
    pub error_frames: u64,
    /// Times the controller went bus-off.
    pub bus_off: u64,
    /// Transmit error counter, from the latest frame that carried it.
    pub tx_errors: Option<u8>,
    /// Receive error counter, from the latest frame that carried it.
    pub rx_errors: Option<u8>,
    /// The classes of the latest error frame, named.
    pub last: Vec<&'static str>,
}

impl BusErrors {
    /// Takes one SocketCAN error frame: `class` is its identifier's error
    /// bits (`CAN_ERR_*` classes), `data` its eight bytes.
    pub fn record_socketcan(&mut self, class: u32, data: &[u8]) {
        const NAMES: [(u32, &str); 10] = [
            (0x0001, "TX timeout"),
            (0x0002, "lost arbitration"),
            (ERR_CRTL, "controller problem"),
            (0x0008, "protocol violation"),
            (0x0010, "transceiver status"),
            (0x0020, "no ACK on transmission"),
            (ERR_BUSOFF, "bus-off"),
            (0x0080, "bus error"),
            (0x0100, "controller restarted"),
            (ERR_CNT, "error counters"),
        ];
        self.error_frames += 1;
        if class & ERR_BUSOFF != 0 {
            self.bus_off += 1;
        }
        if class & (ERR_CNT | ERR_CRTL) != 0
            && let (Some(&tx), Some(&rx)) = (data.get(6), data.get(7))
        {
            self.tx_errors = Some(tx);
            self.rx_errors = Some(rx);
        }
        self.last = NAMES.iter().filter(|(bit, _)| class & bit != 0).map(|&(_, n)| n).collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_and_rates_per_identifier() {
        let t0 = Instant::from_millis(1000);
        let mut m = LoadMeter::new(t0);
        // 1 kHz SYNC (0-byte frames) and a TPDO every other ms, for 1 s.
        for k in 0..1000u64 {
            let at = Instant::from_nanos(t0.as_nanos() + k * 1_000_000);
            m.record(&Frame::new(0x080, &[]), at);
            if k % 2 == 0 {
                m.record(&Frame::new(0x181, &[0x37, 0x02, 1, 2, 3, 4, 5, 6]), at);
            }
        }
        let r = m.report(Instant::from_millis(2000), Some(1_000_000));
        assert_eq!(r.frames, 1500);
        assert!((r.per_second - 1500.0).abs() < 1e-9, "{}", r.per_second);
        let sync_bits = u64::from(frame_bits(&Frame::new(0x080, &[])).total());
        assert_eq!(r.per_id[0].id, CanId::Standard(0x080));
        assert_eq!(r.per_id[0].bits, 1000 * sync_bits);
        assert!((r.per_id[1].per_second - 500.0).abs() < 1e-9);
        // SYNC: 47 + stuffing bits; 8-byte TPDO ~ 111 + stuffing + 3.
        let load = r.load.unwrap();
        assert!((0.09..0.12).contains(&load), "{load}");
        assert_eq!(r.bits as f64 / 1e6, load);
        assert_eq!(m.report(Instant::from_millis(2000), None).load, None);
    }

    #[test]
    fn socketcan_error_frames_counted_with_counters() {
        let mut e = BusErrors::default();
        e.record_socketcan(0x0080, &[0; 8]);
        assert_eq!((e.error_frames, e.tx_errors), (1, None));
        assert_eq!(e.last, ["bus error"]);
        e.record_socketcan(ERR_CRTL | ERR_CNT, &[0, 0x04, 0, 0, 0, 0, 96, 12]);
        assert_eq!((e.tx_errors, e.rx_errors), (Some(96), Some(12)));
        e.record_socketcan(ERR_BUSOFF, &[0; 8]);
        assert_eq!((e.error_frames, e.bus_off), (3, 1));
        assert_eq!(e.last, ["bus-off"]);
    }
}
