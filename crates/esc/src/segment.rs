//! A line of ESCs, as on a real EtherCAT segment (ESC data sheet Section I
//! "Frame processing order", "Loop control"; ETG.1000.4 §5.2).
//!
//! A frame from the master enters slave 0 on port 0, passes its processing
//! unit, leaves on port 1 to the next slave, and so on, until a slave whose
//! port 1 is closed (no link, or closed by DL control 0x0101) loops it
//! back. On the way back it passes every slave again from port 1 to port 0
//! without processing (forwarding order 0 → 3 → 1 → 2 with ports 2 and 3
//! absent). So every slave processes the whole frame once, in line order,
//! each at its own arrival time, and auto-increment addresses count up
//! from slave to slave.
//!
//! Timing: each hop (cable and PHYs) takes [`SegmentConfig::link_delay`];
//! passing an ESC, processed or forwarded, takes
//! [`SegmentConfig::esc_delay`]. Port receive times (latched by a write to
//! 0x0900) are therefore consistent: for slave i the difference between
//! port 1 and port 0 receive times shrinks by `2·(link + esc)` per slave
//! down the line, and a master that halves those differences (as ethercrab
//! and SOEM do) gets `link + esc` per hop: exactly the time between two
//! slaves processing the same datagram.
//!
//! Slaves can be inserted, removed, disconnected and powered off and on
//! at run time; DL status and the lost-link counters follow. Faults of the
//! line ([`LineFault`]: a broken link, lost or corrupted frames, a skewed
//! working counter) act on every frame until cleared.

use crate::datagram::FrameIndex;
use crate::esc::{Esc, FrameReport, FrameTiming};
use crate::frame;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_base::XorShift64;
use drivebus_base::{Duration, Instant, earliest};

mod fault;
pub use fault::LineFault;

/// Something on the segment: an ESC, with or without firmware on its PDI.
pub trait SegmentDevice {
    /// The slave controller.
    fn esc(&self) -> &Esc;
    /// The slave controller, mutable.
    fn esc_mut(&mut self) -> &mut Esc;
    /// Runs the firmware (if any) at `now`; returns the next deadline.
    fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.esc_mut().poll(now)
    }
    /// The device as [`Any`](core::any::Any), so a host of boxed devices
    /// reaches its concrete type (a slave's application); `None` when it
    /// does not expose itself.
    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        None
    }
    /// Power comes back: the ESC starts from its reset values with its
    /// EEPROM as it was ([`Esc::reset`]); firmware restarts in INIT.
    fn power_on(&mut self) {
        self.esc_mut().reset();
    }
}

impl SegmentDevice for Esc {
    fn esc(&self) -> &Esc {
        self
    }
    fn esc_mut(&mut self) -> &mut Esc {
        self
    }
}

impl<D: SegmentDevice + ?Sized> SegmentDevice for Box<D> {
    fn esc(&self) -> &Esc {
        (**self).esc()
    }
    fn esc_mut(&mut self) -> &mut Esc {
        (**self).esc_mut()
    }
    fn poll(&mut self, now: Instant) -> Option<Instant> {
        (**self).poll(now)
    }
    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        (**self).as_any_mut()
    }
    fn power_on(&mut self) {
        (**self).power_on()
    }
}

/// Propagation delays of the segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentConfig {
    /// One hop: cable plus transmitting and receiving PHY.
    pub link_delay: Duration,
    /// Passing an ESC from one port to the next (processing or forwarding).
    pub esc_delay: Duration,
}

impl Default for SegmentConfig {
    fn default() -> Self {
        SegmentConfig { link_delay: Duration::from_nanos(300), esc_delay: Duration::from_nanos(200) }
    }
}

/// What happened to a frame on the segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SegmentReport {
    /// Slaves the frame reached.
    pub reached: usize,
    /// When the frame is back at the master.
    pub returns_at: Instant,
    /// The first slave's report (all slaves see the same frame layout).
    pub frame: FrameReport,
    /// The earliest deadline of the devices the frame touched (polled after
    /// it); the others' deadlines are unchanged by the frame.
    pub next_deadline: Option<Instant>,
    /// The master never gets the frame back: it was lost on the way
    /// ([`LineFault::Lose`]) or arrives with a bad FCS that the master's
    /// NIC discards ([`LineFault::Corrupt`]). Transports do not deliver it.
    pub lost: bool,
}

/// A line of devices.
#[derive(Debug)]
pub struct Segment<D> {
    devices: Vec<D>,
    cables: Vec<bool>,
    /// Devices with their power off.
    unpowered: Vec<bool>,
    faults: Vec<LineFault>,
    rng: XorShift64,
    cfg: SegmentConfig,
    scratch: Vec<FrameTiming>,
    /// Which reached slaves a frame's datagrams touched (their firmware runs).
    touched: Vec<bool>,
    /// The frame's datagrams, parsed once for every slave.
    index: FrameIndex,
    /// Working counters before a skewed slave ran.
    wkcs: Vec<(usize, u16)>,
}

impl<D: SegmentDevice> Segment<D> {
    /// An empty segment.
    pub fn new(cfg: SegmentConfig) -> Self {
        Segment {
            devices: Vec::new(),
            cables: Vec::new(),
            unpowered: Vec::new(),
            faults: Vec::new(),
            rng: XorShift64::new(0),
            cfg,
            scratch: Vec::new(),
            touched: Vec::new(),
            index: FrameIndex::default(),
            wkcs: Vec::new(),
        }
    }

    /// A segment of `devices` in line order.
    pub fn with_devices(cfg: SegmentConfig, devices: Vec<D>) -> Self {
        let mut s = Segment::new(cfg);
        for d in devices {
            s.push(d);
        }
        s
    }

    /// Number of devices.
    pub fn len(&self) -> usize {
        self.devices.len()
    }

    /// True if there are no devices.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }

    /// Device `i`.
    pub fn device(&self, i: usize) -> Option<&D> {
        self.devices.get(i)
    }

    /// Device `i`, mutable.
    pub fn device_mut(&mut self, i: usize) -> Option<&mut D> {
        self.devices.get_mut(i)
    }

    /// All devices in line order.
    pub fn devices(&self) -> &[D] {
        &self.devices
    }

    /// All devices, mutable.
    pub fn devices_mut(&mut self) -> &mut [D] {
        &mut self.devices
    }

    /// Appends a device at the end of the line.
    pub fn push(&mut self, d: D) {
        let n = self.devices.len();
        self.insert(n, d);
    }

    /// Inserts a device at position `i` (cabled in, links up).
    pub fn insert(&mut self, i: usize, d: D) {
        let i = i.min(self.devices.len());
        self.devices.insert(i, d);
        self.unpowered.insert(i, false);
        self.cables.insert(i.min(self.cables.len()), true);
        self.cables.truncate(self.devices.len().saturating_sub(1));
        while self.cables.len() < self.devices.len().saturating_sub(1) {
            self.cables.push(true);
        }
        self.scratch.reserve(self.devices.len());
        self.update_links();
    }

    /// Takes device `i` out of the line; its neighbours are cabled together.
    pub fn remove(&mut self, i: usize) -> Option<D> {
        if i >= self.devices.len() {
            return None;
        }
        let d = self.devices.remove(i);
        self.unpowered.remove(i);
        if !self.cables.is_empty() {
            self.cables.remove(i.min(self.cables.len() - 1));
        }
        self.update_links();
        Some(d)
    }

    /// Connects or disconnects the cable between device `i` (port 1) and
    /// device `i + 1` (port 0).
    pub fn set_cable(&mut self, i: usize, connected: bool) {
        if let Some(c) = self.cables.get_mut(i) {
            *c = connected;
            self.update_links();
        }
    }

    /// Adds a fault of the line; it acts on every frame from now on.
    pub fn add_fault(&mut self, f: LineFault) {
        if let LineFault::Drift { slave, ppb } = f
            && let Some(d) = self.devices.get_mut(slave)
        {
            d.esc_mut().set_clock_drift(ppb);
        }
        if let LineFault::Jitter { slave, amplitude_ns, seed } = f
            && let Some(d) = self.devices.get_mut(slave)
        {
            d.esc_mut().set_clock_jitter(Some((amplitude_ns, seed)));
        }
        self.faults.push(f);
        self.update_links();
    }

    /// Ends every fault of the line (power stays as it is); a drifting
    /// clock gets its own drift back, a jittering one stamps exactly again.
    pub fn clear_faults(&mut self) {
        for f in self.faults.drain(..) {
            match f {
                LineFault::Drift { slave, .. } => {
                    if let Some(d) = self.devices.get_mut(slave) {
                        let own = d.esc().config().clock.drift_ppb;
                        d.esc_mut().set_clock_drift(own);
                    }
                }
                LineFault::Jitter { slave, .. } => {
                    if let Some(d) = self.devices.get_mut(slave) {
                        d.esc_mut().set_clock_jitter(None);
                    }
                }
                _ => {}
            }
        }
        self.update_links();
    }

    /// The faults that are on, in the order added.
    pub fn faults(&self) -> &[LineFault] {
        &self.faults
    }

    /// Seeds the generator behind the faults' probabilities.
    pub fn set_fault_seed(&mut self, seed: u64) {
        self.rng = XorShift64::new(seed);
    }

    /// Cuts device `i`'s power: it neither processes nor forwards, its
    /// neighbours lose their links to it (the line ends before it).
    pub fn power_off(&mut self, i: usize) {
        if let Some(p) = self.unpowered.get_mut(i) {
            *p = true;
            self.update_links();
        }
    }

    /// Powers device `i` on again ([`SegmentDevice::power_on`]: registers at
    /// their reset values, the EEPROM kept); its links come up.
    pub fn power_on(&mut self, i: usize) {
        if self.unpowered.get(i) == Some(&true) {
            self.unpowered[i] = false;
            self.devices[i].power_on();
            self.update_links();
        }
    }

    /// False while device `i` has its power off.
    pub fn is_powered(&self, i: usize) -> bool {
        !self.unpowered.get(i).copied().unwrap_or(false)
    }

    /// True if frames pass between device `i` and `i + 1`: cabled, no
    /// broken link, both powered.
    fn joined(&self, i: usize) -> bool {
        self.cables.get(i).copied().unwrap_or(false)
            && !self.faults.iter().any(|f| f.breaks(i))
            && !self.unpowered[i]
            && !self.unpowered[i + 1]
    }

    fn update_links(&mut self) {
        let n = self.devices.len();
        for i in 0..n {
            let (p0, p1) = if self.unpowered[i] {
                (false, false)
            } else {
                (i == 0 || self.joined(i - 1), i + 1 < n && self.joined(i))
            };
            self.devices[i].esc_mut().set_port_links([p0, p1, false, false]);
        }
    }

    /// Whether a [`LineFault::Lose`] takes this frame.
    fn lose(&mut self) -> bool {
        let rng = &mut self.rng;
        self.faults.iter_mut().any(|f| match f {
            LineFault::Lose(p) => p.fire(rng),
            _ => false,
        })
    }

    /// The slave a [`LineFault::Corrupt`] damages this frame in front of,
    /// if one fires (only on cables the frame passes).
    fn corrupt(&mut self, reached: usize) -> Option<usize> {
        let rng = &mut self.rng;
        self.faults.iter_mut().find_map(|f| match f {
            LineFault::Corrupt { at, pick } if *at < reached => pick.fire(rng).then_some(*at),
            _ => None,
        })
    }

    /// The working-counter skew of slave `i`, if any.
    fn skew(&self, i: usize) -> Option<i16> {
        self.faults.iter().find_map(|f| match f {
            LineFault::WkcSkew { slave, skew } if *slave == i => Some(*skew),
            _ => None,
        })
    }

    /// Passes an Ethernet frame through the line in place at `now` (when
    /// the master sends it), then lets every reached device's firmware run.
    /// Non-EtherCAT frames come back untouched.
    pub fn process_frame(&mut self, frame: &mut [u8], now: Instant) -> SegmentReport {
        let mut report = self.pass_frame(frame, now);
        report.next_deadline = self.run_touched();
        report
    }

    /// The frame's pass through the ESCs alone, as [`Segment::process_frame`]
    /// without the firmware: the reply is complete when this returns, so a
    /// transport sends it and then calls [`Segment::run_touched`] (as a real
    /// slave's firmware reacts to a frame after its ESC forwarded it). The
    /// report's `next_deadline` is `None` until then.
    pub fn pass_frame(&mut self, frame: &mut [u8], now: Instant) -> SegmentReport {
        self.touched.clear();
        let mut report = SegmentReport { returns_at: now, ..SegmentReport::default() };
        let Some(off) = frame::ethercat_offset(frame) else {
            report.frame.ignored = true;
            return report;
        };
        if !self.faults.is_empty() && self.lose() {
            report.lost = true;
            return report;
        }
        let (link, esc) = (self.cfg.link_delay, self.cfg.esc_delay);
        self.scratch.clear();
        let mut t = now;
        for (i, d) in self.devices.iter().enumerate() {
            if self.unpowered[i] || (i > 0 && !self.joined(i - 1)) {
                break;
            }
            t += link;
            self.scratch.push(FrameTiming { at: t, port_rx: [Some(t), None, None, None] });
            if !d.esc().port_open(1) {
                break;
            }
            t += esc;
        }
        let reached = self.scratch.len();
        if reached == 0 {
            return report;
        }
        // Way back: the last slave loops the frame, the others forward it
        // from port 1 to port 0.
        let mut back = self.scratch[reached - 1].at + esc;
        for i in (0..reached - 1).rev() {
            back += link;
            self.scratch[i].port_rx[1] = Some(back);
            back += esc;
        }
        report.returns_at = back + link;
        report.reached = reached;
        let corrupt_at = if self.faults.is_empty() { None } else { self.corrupt(reached) };
        // Faults of the line need every slave to walk the frame itself.
        let indexed = self.faults.is_empty() && self.index.build(&frame[off..]);
        self.touched.clear();
        self.touched.resize(reached, true);
        for i in 0..reached {
            if let Some(at) = corrupt_at.filter(|at| i >= *at) {
                // A bad FCS: nothing executed, the error counted.
                self.devices[i].esc_mut().count_rx_error(0, i > at);
                continue;
            }
            if corrupt_at.is_some() {
                // Before the damage: processed on the way out, the bad
                // frame forwarded from port 1 on the way back.
                self.devices[i].esc_mut().count_rx_error(1, true);
            }
            let skew = if self.faults.is_empty() { None } else { self.skew(i) };
            if skew.is_some() {
                fault::working_counters(&frame[off..], &mut self.wkcs);
            }
            let timing = self.scratch[i];
            let esc = self.devices[i].esc_mut();
            let r = if indexed {
                esc.process_indexed(&mut frame[off..], &timing, &mut self.index)
            } else {
                esc.process_ethercat(&mut frame[off..], &timing)
            };
            self.touched[i] = r.touched;
            if let Some(skew) = skew {
                fault::skew_counters(&mut frame[off..], &self.wkcs, skew);
            }
            if i == 0 {
                report.frame = r;
            }
        }
        report.lost = corrupt_at.is_some();
        if !report.frame.ignored {
            frame::mark_reply_source(frame);
        }
        report
    }

    /// Runs the firmware of the devices the last [`Segment::pass_frame`]
    /// touched, each at the instant the frame reached it; returns their
    /// earliest deadline. The others' state did not change, and their
    /// deadlines stand (a deadline is a promise). A second call does nothing.
    pub fn run_touched(&mut self) -> Option<Instant> {
        let mut next = None;
        for i in (0..self.touched.len()).filter(|&i| self.touched[i]) {
            let at = self.scratch[i].at;
            next = earliest(next, self.devices[i].poll(at));
        }
        self.touched.clear();
        next
    }

    /// Runs every device's firmware at `now`; returns the earliest deadline.
    pub fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.devices.iter_mut().fold(None, |d, dev| earliest(d, dev.poll(now)))
    }
}

#[cfg(test)]
mod tests;
