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
//! Slaves can be inserted, removed and disconnected at run time; DL status
//! and the lost-link counters follow.

use crate::esc::{Esc, FrameReport, FrameTiming};
use crate::frame;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{Duration, Instant, earliest};

/// Something on the segment: an ESC, with or without firmware on its PDI.
pub trait Device {
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
}

impl Device for Esc {
    fn esc(&self) -> &Esc {
        self
    }
    fn esc_mut(&mut self) -> &mut Esc {
        self
    }
}

impl<D: Device + ?Sized> Device for Box<D> {
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
}

/// A line of devices.
#[derive(Debug)]
pub struct Segment<D> {
    devices: Vec<D>,
    cables: Vec<bool>,
    cfg: SegmentConfig,
    scratch: Vec<FrameTiming>,
}

impl<D: Device> Segment<D> {
    /// An empty segment.
    pub fn new(cfg: SegmentConfig) -> Self {
        Segment { devices: Vec::new(), cables: Vec::new(), cfg, scratch: Vec::new() }
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

    fn update_links(&mut self) {
        let n = self.devices.len();
        for i in 0..n {
            let p0 = i == 0 || self.cables[i - 1];
            let p1 = i + 1 < n && self.cables[i];
            self.devices[i].esc_mut().set_port_links([p0, p1, false, false]);
        }
    }

    /// Passes an Ethernet frame through the line in place at `now` (when
    /// the master sends it), then lets every reached device's firmware run.
    /// Non-EtherCAT frames come back untouched.
    pub fn process_frame(&mut self, frame: &mut [u8], now: Instant) -> SegmentReport {
        let mut report = SegmentReport { returns_at: now, ..SegmentReport::default() };
        let Some(off) = frame::ethercat_offset(frame) else {
            report.frame.ignored = true;
            return report;
        };
        let (link, esc) = (self.cfg.link_delay, self.cfg.esc_delay);
        self.scratch.clear();
        let mut t = now;
        for (i, d) in self.devices.iter().enumerate() {
            if i > 0 && !self.cables[i - 1] {
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
        for i in 0..reached {
            let timing = self.scratch[i];
            let r = self.devices[i].esc_mut().process_ethercat(&mut frame[off..], &timing);
            if i == 0 {
                report.frame = r;
            }
        }
        if !report.frame.ignored {
            frame::mark_reply_source(frame);
        }
        for i in 0..reached {
            let at = self.scratch[i].at;
            self.devices[i].poll(at);
        }
        report
    }

    /// Runs every device's firmware at `now`; returns the earliest deadline.
    pub fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.devices.iter_mut().fold(None, |d, dev| earliest(d, dev.poll(now)))
    }
}

#[cfg(test)]
mod tests;
