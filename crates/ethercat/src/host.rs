//! A segment of slaves on a clock, shared by the transports.
//!
//! [`Host`] is the one place frames enter: it runs every device deadline
//! that came due (in order, at its own instant), passes the frame through
//! the [`Segment`], records it in the capture, and in simulated time
//! moves the clock to when the reply is back (plus a configurable master
//! turnaround), so a run depends only on the frames sent.

use crate::capture::{Capture, Direction, LinkType};
use crate::clock::Clock;
use drivebus_can::{Duration, Instant, earliest};
use drivebus_esc::segment::{Segment, SegmentConfig, SegmentDevice, SegmentReport};
use std::io::Write;
use std::sync::{Arc, Mutex, MutexGuard};

/// A device on a hosted segment.
pub type BoxDevice = Box<dyn SegmentDevice + Send>;

/// Called after every frame a host processed, under its lock, with the
/// segment (a local tool sampling what the frame's process data did,
/// `crate::objects::Watch`). It runs after the reply went back and the
/// slaves' firmware reacted, before the next frame: it must be short.
pub type FrameObserver = Box<dyn FnMut(&mut Segment<BoxDevice>) + Send>;

/// Names an observer of [`Host::observe_frames`] to remove it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObserverId(u64);

/// One slave of a host as it is now (what a status page shows).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlaveState {
    /// Line position, from 1.
    pub position: usize,
    /// The SII General "order" string (the name `scan` gives), empty without one.
    pub name: String,
    /// Vendor, product, revision, serial from the SII.
    pub identity: drivebus_can::Identity,
    /// AL status register (0x0130): the ESM state and the error bit.
    pub al_status: u16,
    /// AL status code register (0x0134).
    pub al_status_code: u16,
    /// False while the slave is powered off (a fault of the line).
    pub powered: bool,
    /// Frames, datagrams and working counter increments its ESC counted.
    pub traffic: drivebus_esc::EscTraffic,
}

/// Counters of a host.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HostStats {
    /// EtherCAT frames processed.
    pub frames: u64,
    /// Frames that were not EtherCAT or were malformed.
    pub bad_frames: u64,
    /// Device polls at deadlines.
    pub deadline_polls: u64,
    /// Frames a fault of the line lost or corrupted (never returned).
    pub lost: u64,
    /// Datagrams in the EtherCAT frames processed (as the first slave
    /// walked them).
    pub datagrams: u64,
}

struct Inner {
    segment: Segment<BoxDevice>,
    next: Option<Instant>,
    capture: Option<Capture<Box<dyn Write + Send>>>,
    turnaround: Duration,
    stats: HostStats,
    observers: Vec<(ObserverId, FrameObserver)>,
    next_observer: u64,
}

impl Inner {
    /// Polls the devices at every deadline up to `now`. Nothing else: a
    /// device's deadline is a promise, polling earlier does nothing.
    fn catch_up(&mut self, now: Instant) {
        let mut guard = 0u32;
        while let Some(d) = self.next.filter(|d| *d <= now) {
            self.stats.deadline_polls += 1;
            let n = self.segment.poll(d);
            guard += 1;
            self.next = n;
            // A deadline that does not move is a broken device; do not spin.
            if n.is_some_and(|n| n <= d) || guard > 1_000_000 {
                self.next = self.segment.poll(now);
                break;
            }
        }
    }
}

/// A segment of devices, its clock and an optional capture (cheap to clone;
/// clones share everything).
#[derive(Clone)]
pub struct Host {
    inner: Arc<Mutex<Inner>>,
    clock: Clock,
}

impl std::fmt::Debug for Host {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Host").field("clock", &self.clock).finish_non_exhaustive()
    }
}

impl Host {
    /// Hosts `segment` on `clock`.
    pub fn new(segment: Segment<BoxDevice>, clock: Clock) -> Host {
        let turnaround = if clock.is_simulated() { Duration::from_micros(5) } else { Duration::ZERO };
        let mut inner = Inner {
            segment,
            next: None,
            capture: None,
            turnaround,
            stats: HostStats::default(),
            observers: Vec::new(),
            next_observer: 0,
        };
        inner.next = inner.segment.poll(clock.now());
        Host { inner: Arc::new(Mutex::new(inner)), clock }
    }

    /// Hosts `devices` in line order with default delays.
    pub fn line(devices: Vec<BoxDevice>, clock: Clock) -> Host {
        Host::new(Segment::with_devices(SegmentConfig::default(), devices), clock)
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic elsewhere cannot leave the segment half-updated in a way
        // that matters more than losing the test; keep serving.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The clock.
    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    /// Records every frame in and out as pcapng into `w`.
    pub fn set_capture(&self, w: Box<dyn Write + Send>, interface: &str) -> std::io::Result<()> {
        self.lock().capture = Some(Capture::new(w, interface, LinkType::Ethernet)?);
        Ok(())
    }

    /// Stops capturing and flushes.
    pub fn stop_capture(&self) -> std::io::Result<()> {
        match self.lock().capture.take() {
            Some(mut c) => c.flush(),
            None => Ok(()),
        }
    }

    /// Simulated time: how long the master takes between receiving a reply
    /// and sending the next frame (default 5 µs).
    pub fn set_turnaround(&self, d: Duration) {
        self.lock().turnaround = d;
    }

    /// Processes one Ethernet frame in place, arriving now. Returns when
    /// the reply is back at the master; a transport sends nothing back
    /// when [`SegmentReport::lost`] says a fault of the line took it.
    pub fn process_frame(&self, frame: &mut [u8]) -> SegmentReport {
        self.process_frame_then(frame, |_, _| ())
    }

    /// As [`Host::process_frame`], calling `reply(frame, lost)` as soon as
    /// the ESCs have passed the frame and before the slaves' firmware
    /// reacts to it: a transport sends the reply from there, so the
    /// firmware's work is not in the master's round trip (a real slave's
    /// ESC forwards the frame while its firmware is still asleep).
    pub fn process_frame_then(&self, frame: &mut [u8], reply: impl FnOnce(&[u8], bool)) -> SegmentReport {
        let mut g = self.lock();
        let now = self.clock.now();
        g.catch_up(now);
        let unix = self.clock.unix_ns(now);
        if let Some(c) = g.capture.as_mut() {
            let _ = c.write(frame, unix, Direction::Inbound);
        }
        let mut r = g.segment.pass_frame(frame, now);
        // No slave reached (the first one has no power): the master's port
        // has no link, so nothing comes back.
        r.lost |= r.reached == 0 && !r.frame.ignored;
        reply(frame, r.lost);
        r.next_deadline = g.segment.run_touched();
        let Inner { observers, segment, .. } = &mut *g;
        for (_, o) in observers.iter_mut() {
            o(segment);
        }
        g.stats.frames += 1;
        if r.frame.ignored || r.frame.malformed {
            g.stats.bad_frames += 1;
        }
        g.stats.lost += u64::from(r.lost);
        g.stats.datagrams += u64::from(r.frame.datagrams);
        let unix = self.clock.unix_ns(r.returns_at);
        if let Some(c) = g.capture.as_mut().filter(|_| !r.lost) {
            let _ = c.write(frame, unix, Direction::Outbound);
        }
        if self.clock.is_simulated() {
            self.clock.advance_to(r.returns_at + g.turnaround);
        }
        // Devices the frame touched ran at their own arrival instants inside
        // the segment; the others' deadlines stand.
        g.next = earliest(g.next, r.next_deadline);
        r
    }

    /// Runs due device deadlines; returns the next one.
    pub fn poll(&self) -> Option<Instant> {
        let mut g = self.lock();
        g.catch_up(self.clock.now());
        g.next
    }

    /// Simulated time: moves forward by `d`, running every device deadline
    /// on the way at its own instant. Real time: just polls.
    pub fn advance(&self, d: Duration) {
        let target = self.clock.now() + d;
        let mut g = self.lock();
        while let Some(n) = g.next.filter(|n| *n <= target) {
            self.clock.advance_to(n);
            g.catch_up(n);
            if g.next.is_some_and(|m| m <= n) {
                break;
            }
        }
        self.clock.advance_to(target);
        g.catch_up(self.clock.now());
    }

    /// Runs `f` on the segment (inspect or change devices, cables…).
    pub fn with_segment<R>(&self, f: impl FnOnce(&mut Segment<BoxDevice>) -> R) -> R {
        let mut g = self.lock();
        let r = f(&mut g.segment);
        let now = self.clock.now();
        g.next = g.segment.poll(now);
        r
    }

    /// Calls `f` after every frame processed from now on, until
    /// [`Host::stop_observing`].
    pub fn observe_frames(&self, f: impl FnMut(&mut Segment<BoxDevice>) + Send + 'static) -> ObserverId {
        let mut g = self.lock();
        let id = ObserverId(g.next_observer);
        g.next_observer += 1;
        g.observers.push((id, Box::new(f)));
        id
    }

    /// Removes an observer (nothing if it is gone already).
    pub fn stop_observing(&self, id: ObserverId) {
        self.lock().observers.retain(|(i, _)| *i != id);
    }

    /// Every slave's identity and ESM state, in line order.
    pub fn slaves(&self) -> Vec<SlaveState> {
        let g = self.lock();
        g.segment
            .devices()
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let esc = d.esc();
                let sii = esc.sii_image().parse().ok();
                let name = sii
                    .as_ref()
                    .and_then(|c| {
                        let at = usize::from(c.general.as_ref()?.order_idx).checked_sub(1)?;
                        c.strings.get(at).cloned()
                    })
                    .unwrap_or_default();
                SlaveState {
                    position: i + 1,
                    name,
                    identity: sii.map(|c| c.identity).unwrap_or_default(),
                    al_status: esc.al_status(),
                    al_status_code: esc.peek_u16(drivebus_esc::registers::AL_STATUS_CODE),
                    powered: g.segment.is_powered(i),
                    traffic: esc.traffic(),
                }
            })
            .collect()
    }

    /// Every slave's AL status (0x0130) and AL status code (0x0134), in
    /// line order: what [`Host::slaves`] gives of the ESM, without
    /// parsing the SII, for a watcher that polls often.
    pub fn al_states(&self) -> Vec<(u16, u16)> {
        let g = self.lock();
        g.segment
            .devices()
            .iter()
            .map(|d| (d.esc().al_status(), d.esc().peek_u16(drivebus_esc::registers::AL_STATUS_CODE)))
            .collect()
    }

    /// Counters.
    pub fn stats(&self) -> HostStats {
        self.lock().stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::described::{self, Member};

    /// A fresh line: every slave in INIT (AL status 1, code 0) with the
    /// identity and name of its SII.
    #[test]
    fn slaves_report_identity_and_esm_state() {
        let members = vec![
            Member::Drive(crate::drive::profile("ipos").unwrap()),
            Member::Drive(crate::drive::profile("generic").unwrap()),
        ];
        let host = Host::line(described::devices(&members, None).unwrap(), Clock::simulated(Instant::ZERO));
        let s = host.slaves();
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].position, s[1].position), (1, 2));
        for x in &s {
            assert_eq!((x.al_status & 0x0F, x.al_status_code, x.powered), (1, 0, true), "{x:?}");
            assert!(!x.name.is_empty() && x.identity.product_code != 0, "{x:?}");
        }
        assert_ne!(s[0].identity, s[1].identity);
        let al: Vec<(u16, u16)> = s.iter().map(|x| (x.al_status, x.al_status_code)).collect();
        assert_eq!(host.al_states(), al);
        host.with_segment(|seg| seg.power_off(1));
        assert!(!host.slaves()[1].powered);
    }

    /// An observer sees every frame after the segment processed it, until
    /// it is removed.
    #[test]
    fn observers_see_every_frame_until_removed() {
        use std::sync::atomic::{AtomicU64, Ordering};
        let members = vec![Member::Drive(crate::drive::profile("generic").unwrap())];
        let host = Host::line(described::devices(&members, None).unwrap(), Clock::simulated(Instant::ZERO));
        let seen = Arc::new(AtomicU64::new(0));
        let id = {
            let seen = seen.clone();
            host.observe_frames(move |seg| {
                assert_eq!(seg.devices().len(), 1);
                seen.fetch_add(1, Ordering::Relaxed);
            })
        };
        let mut frame = [0u8; 60];
        host.process_frame(&mut frame);
        host.process_frame(&mut frame);
        assert_eq!(seen.load(Ordering::Relaxed), 2);
        host.stop_observing(id);
        host.process_frame(&mut frame);
        assert_eq!(seen.load(Ordering::Relaxed), 2);
    }

    /// The counters a status page shows: frames and datagrams of the
    /// line, and per slave the working counter increments its ESC made
    /// (a broadcast read counts at each slave, an APRD at one).
    #[test]
    fn counters_of_the_line_and_each_slave() {
        use drivebus_esc::frame::{
            DatagramCommand, FrameBuilder, datagrams, position_address, station_address,
        };
        let members = vec![
            Member::Drive(crate::drive::profile("generic").unwrap()),
            Member::Drive(crate::drive::profile("generic").unwrap()),
        ];
        let host = Host::line(described::devices(&members, None).unwrap(), Clock::simulated(Instant::ZERO));
        let before: Vec<_> = host.slaves().iter().map(|s| s.traffic).collect();
        let mut buf = [0u8; 200];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
        b.push(DatagramCommand::Brd, 1, station_address(0, 0x0130), &[0, 0]).unwrap();
        b.push(DatagramCommand::Aprd, 2, position_address(1, 0x0130), &[0, 0]).unwrap();
        let n = b.finish();
        host.process_frame(&mut buf[..n]);
        let wkcs: Vec<u16> = datagrams(&buf[14..n]).map(|d| d.wkc).collect();
        assert_eq!(wkcs, [2, 1]);
        let st = host.stats();
        assert_eq!((st.frames, st.datagrams, st.bad_frames), (1, 2, 0));
        let after = host.slaves();
        let delta: Vec<(u64, u64, u64)> = after
            .iter()
            .zip(&before)
            .map(|(a, b)| {
                (a.traffic.frames - b.frames, a.traffic.datagrams - b.datagrams, a.traffic.wkc - b.wkc)
            })
            .collect();
        assert_eq!(delta, [(1, 2, 1), (1, 2, 2)]);
    }

    /// A device that counts its firmware runs.
    struct Counted(BoxDevice, Arc<std::sync::atomic::AtomicUsize>);

    impl SegmentDevice for Counted {
        fn esc(&self) -> &drivebus_esc::Esc {
            self.0.esc()
        }
        fn esc_mut(&mut self) -> &mut drivebus_esc::Esc {
            self.0.esc_mut()
        }
        fn poll(&mut self, now: Instant) -> Option<Instant> {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.0.poll(now)
        }
    }

    /// The server sends the reply before the slaves' firmware reacts to
    /// the frame (it is not in the master's round trip), and the firmware
    /// of a slave the frame touched still runs before the call returns.
    #[test]
    fn the_reply_leaves_before_the_firmware_runs() {
        use drivebus_esc::frame::{DatagramCommand, FrameBuilder, station_address};
        use std::sync::atomic::{AtomicUsize, Ordering};
        let runs = Arc::new(AtomicUsize::new(0));
        let members = vec![Member::Drive(crate::drive::profile("generic").unwrap())];
        let devices: Vec<BoxDevice> = described::devices(&members, None)
            .unwrap()
            .into_iter()
            .map(|d| Box::new(Counted(d, runs.clone())) as BoxDevice)
            .collect();
        let host = Host::line(devices, Clock::simulated(Instant::ZERO));
        let mut buf = [0u8; 100];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
        b.push(DatagramCommand::Brd, 1, station_address(0, 0x0130), &[0, 0]).unwrap();
        let n = b.finish();
        let before = runs.load(Ordering::Relaxed);
        let mut at_reply = None;
        let r = host.process_frame_then(&mut buf[..n], |reply, lost| {
            assert!(!lost && reply.len() == n);
            at_reply = Some(runs.load(Ordering::Relaxed));
        });
        assert_eq!(at_reply, Some(before), "no firmware ran before the reply");
        assert_eq!(
            runs.load(Ordering::Relaxed),
            before + 1,
            "the touched slave's firmware ran once after it"
        );
        assert!(!r.lost && r.reached == 1);
        // The old order (firmware first) is still what `process_frame` gives
        // the callers that need no early reply: it runs the firmware too.
        host.process_frame(&mut buf[..n]);
        assert_eq!(runs.load(Ordering::Relaxed), before + 2);
    }
}
