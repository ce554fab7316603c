//! Two tiny nodes exchange 1000 frames; the run is deterministic.

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Device, Duration, Frame, Instant, TxSink};

/// Sends 0x200 with a counter; each answer 0x201 triggers the next ping.
struct Pinger {
    next: u16,
    limit: u16,
    started: bool,
}

impl Device for Pinger {
    fn handle_frame(&mut self, frame: &Frame, _now: Instant, out: &mut dyn TxSink) {
        if frame.std_id() == Some(0x201) && self.next < self.limit {
            out.send(Frame::new(0x200, &self.next.to_le_bytes()));
            self.next += 1;
        }
    }
    fn poll(&mut self, _now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        if !self.started {
            self.started = true;
            out.send(Frame::new(0x200, &self.next.to_le_bytes()));
            self.next += 1;
        }
        None
    }
    fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Answers each 0x200 after a 100 µs reaction time, echoing the counter.
struct Ponger {
    due: Option<(Instant, [u8; 2])>,
    answered: u32,
}

impl Device for Ponger {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, _out: &mut dyn TxSink) {
        if frame.std_id() == Some(0x200) && frame.len() == 2 {
            let d = frame.data();
            self.due = Some((now + Duration::from_micros(100), [d[0], d[1]]));
        }
    }
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        match self.due {
            Some((t, d)) if t <= now => {
                out.send(Frame::new(0x201, &d));
                self.answered += 1;
                self.due = None;
                None
            }
            other => other.map(|(t, _)| t),
        }
    }
    fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

fn run(cfg: BusConfig) -> (Vec<String>, u32) {
    let mut bus = Bus::new(cfg);
    bus.attach(Pinger { next: 0, limit: 500, started: false });
    let pong = bus.attach(Ponger { due: None, answered: 0 });
    bus.run_until(Instant::from_millis(1000));
    assert_eq!(bus.stats().frames, 1000);
    (bus.log_lines(), bus.node::<Ponger>(pong).map_or(0, |p| p.answered))
}

#[test]
fn thousand_frames_same_log_twice() {
    for cfg in [BusConfig::with_bitrate(1_000_000), BusConfig::zero_time()] {
        let (a, answered) = run(cfg.clone());
        let (b, _) = run(cfg);
        assert_eq!(a.len(), 1000);
        assert_eq!(answered, 500);
        assert_eq!(a, b);
        assert!(a[0].ends_with("can0 200#0000"));
        assert!(a[999].ends_with("can0 201#F301"));
    }
    // At 1 Mbit/s a round takes 2 frames plus 100 µs reaction time.
    let (a, _) = run(BusConfig::with_bitrate(1_000_000));
    let ping = drivebus_bus::timing::frame_bits(&Frame::new(0x200, &[0, 0])).to_end_of_frame();
    assert!(a[0].starts_with(&format!("(0.{ping:06})")), "{}", a[0]);
}
