//! The ESC: configuration, state, time and the PDI-side API.
//!
//! Register and memory access with their side effects live in
//! `access.rs`, datagram execution in `datagram.rs`.

use crate::dc::{ClockConfig, LocalClock, SyncUnit};
use crate::eeprom::{SiiDone, SiiTiming, SiiUnit};
use crate::events::{EscEvent, EventQueue};
use crate::fmmu::Fmmu;
use crate::registers as reg;
use crate::sii::SiiImage;
use crate::sm::{Side, SyncManager};
use alloc::vec;
use alloc::vec::Vec;
use drivebus_base::{Duration, Instant, earliest};

/// Static properties of an ESC.
#[derive(Debug, Clone)]
pub struct EscConfig {
    /// ESC type (0x0000). 0x04 is the Beckhoff IP core family.
    pub esc_type: u8,
    /// Revision (0x0001).
    pub revision: u8,
    /// Build (0x0002).
    pub build: u16,
    /// FMMUs implemented (1–16).
    pub fmmus: u8,
    /// Sync managers implemented (1–16).
    pub sync_managers: u8,
    /// Process RAM in KiB from 0x1000 (1–60).
    pub ram_kib: u8,
    /// Ports implemented (1–4), all reported as MII in 0x0007.
    pub ports: u8,
    /// Distributed clocks implemented (64-bit, enhanced SYNC activation).
    /// Without DC, 0x0900–0x09FF are not implemented: accesses to them
    /// do not count in the working counter (masters count DC slaves so).
    pub dc: bool,
    /// Local clock offset and drift.
    pub clock: ClockConfig,
    /// The SII EEPROM content.
    pub sii: SiiImage,
    /// SII reads return 8 bytes (0x0502 bit 6) instead of 4.
    pub sii_8_byte_reads: bool,
    /// Durations of SII commands (zero: done within the datagram).
    pub sii_timing: SiiTiming,
}

impl Default for EscConfig {
    fn default() -> Self {
        EscConfig {
            esc_type: 0x04,
            revision: 0x03,
            build: 0x0301,
            fmmus: 16,
            sync_managers: 16,
            ram_kib: 8,
            ports: 2,
            dc: true,
            clock: ClockConfig::default(),
            sii: SiiImage::default(),
            sii_8_byte_reads: true,
            sii_timing: SiiTiming::default(),
        }
    }
}

/// Largest jitter amplitude of the time stamps (1 ms).
pub const MAX_JITTER_NS: u32 = 1_000_000;

impl EscConfig {
    /// Default hardware with the given SII image.
    pub fn with_sii(sii: SiiImage) -> Self {
        EscConfig { sii, ..EscConfig::default() }
    }
}

/// When a frame passes an ESC.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameTiming {
    /// When the frame reaches the processing unit (its port 0 arrival).
    pub at: Instant,
    /// When the frame's first bit arrived at each port (latched into
    /// 0x0900–0x090F on a write to 0x0900); `None` if it did not.
    pub port_rx: [Option<Instant>; 4],
}

impl FrameTiming {
    /// A frame that arrives on port 0 at `at` and is looped back inside.
    pub fn at(at: Instant) -> Self {
        FrameTiming { at, port_rx: [Some(at), None, None, None] }
    }
}

/// What processing a frame did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameReport {
    /// Datagrams executed.
    pub datagrams: u16,
    /// The frame was inconsistent; processing stopped at the first bad
    /// datagram and left it and everything after it untouched.
    pub malformed: bool,
    /// Not an EtherCAT DL PDU frame (other EtherType or header type):
    /// passed on untouched.
    pub ignored: bool,
    /// Some datagram was executed against this ESC (its firmware may have
    /// something to do); false when every datagram was for others.
    pub touched: bool,
}

/// What an ESC has processed since it was powered up (a status page's
/// counters; [`Esc::traffic`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EscTraffic {
    /// EtherCAT frames that reached it.
    pub frames: u64,
    /// Datagrams it executed (whether addressed to it or not).
    pub datagrams: u64,
    /// Working counter increments it made: datagrams that read or wrote
    /// its memory (read-writes count 1 + 2, as in the frame).
    pub wkc: u64,
}

/// Process-data and PDI watchdogs (ESC data sheet Section I "Watchdogs").
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Watchdogs {
    pub pd_deadline: Option<Instant>,
    pub pdi_deadline: Option<Instant>,
    pub pdi_ok: bool,
}

/// A software EtherCAT slave controller.
///
/// The master side is [`Esc::process_frame`] / [`Esc::process_ethercat`];
/// the firmware side is [`Esc::pdi_read`], [`Esc::pdi_write`] and
/// [`Esc::pop_event`]; time moves only through `now` arguments and
/// [`Esc::poll`].
#[derive(Debug, Clone)]
pub struct Esc {
    pub(crate) mem: Vec<u8>,
    pub(crate) cfg: EscConfig,
    pub(crate) fmmus: [Fmmu; 16],
    pub(crate) fmmu_active: [u8; 16],
    pub(crate) fmmu_n: usize,
    pub(crate) sms: [SyncManager; 16],
    pub(crate) sm_guard: u16,
    pub(crate) sm_activate: [u8; 16],
    pub(crate) sii: SiiUnit,
    pub(crate) clock: LocalClock,
    pub(crate) sync: SyncUnit,
    pub(crate) dc_last_sample: Option<Instant>,
    pub(crate) dc_mean: i64,
    /// Jitter of the time stamps (a fault): amplitude (ns) and generator.
    pub(crate) jitter: Option<(u32, drivebus_base::XorShift64)>,
    pub(crate) wd: Watchdogs,
    pub(crate) events: EventQueue,
    pub(crate) now: Instant,
    pub(crate) timing: FrameTiming,
    pub(crate) al_control_full: bool,
    pub(crate) al_event_misc: u32,
    pub(crate) ecat_event_misc: u16,
    pub(crate) links: [bool; 4],
    pub(crate) eeprom_loaded: bool,
    pub(crate) frame_no: u64,
    /// Datagrams executed and working counter increments made, since power-up
    /// (diagnostics of the host, not registers: a reset keeps them).
    pub(crate) traffic: EscTraffic,
    pub(crate) reset_stage: (u8, u64),
    /// Scratch for read-write datagrams (allocated once, never on the frame path).
    pub(crate) scratch: Vec<u8>,
    /// The last SYNC pulse instant `next_deadline` computed, with what it
    /// depends on (local target time, clock state): a firmware polls many
    /// times between two clock corrections, and the conversion through
    /// the local clock is most of a poll's cost.
    pub(crate) sync_instant: core::cell::Cell<Option<(u64, LocalClock, Instant)>>,
}

impl Esc {
    /// Powers an ESC up: registers at their reset values, then the SII
    /// configuration area loaded (alias, PDI control, SYNC pulse length).
    /// Port 0 has a link; call [`Esc::set_port_links`] for others.
    pub fn new(mut cfg: EscConfig) -> Esc {
        cfg.fmmus = cfg.fmmus.clamp(1, 16);
        cfg.sync_managers = cfg.sync_managers.clamp(1, 16);
        cfg.ram_kib = cfg.ram_kib.clamp(1, 60);
        cfg.ports = cfg.ports.clamp(1, 4);
        let sii = SiiUnit::new(core::mem::take(&mut cfg.sii), cfg.sii_8_byte_reads, cfg.sii_timing);
        let mem = vec![0u8; reg::REGISTER_SPACE + usize::from(cfg.ram_kib) * 1024];
        let mut esc = Esc {
            mem,
            clock: LocalClock::new(cfg.clock),
            cfg,
            fmmus: [Fmmu::default(); 16],
            fmmu_active: [0; 16],
            fmmu_n: 0,
            sms: [SyncManager::default(); 16],
            sm_guard: 0,
            sm_activate: [0; 16],
            sii,
            sync: SyncUnit::default(),
            dc_last_sample: None,
            dc_mean: 0,
            jitter: None,
            wd: Watchdogs::default(),
            events: EventQueue::default(),
            now: Instant::ZERO,
            sync_instant: core::cell::Cell::new(None),
            timing: FrameTiming::at(Instant::ZERO),
            al_control_full: false,
            al_event_misc: 0,
            ecat_event_misc: 0,
            links: [true, false, false, false],
            eeprom_loaded: false,
            frame_no: 0,
            traffic: EscTraffic::default(),
            reset_stage: (0, 0),
            scratch: vec![0; crate::frame::MAX_DATA_LEN + 1],
        };
        esc.power_on();
        esc
    }

    /// Hardware reset: every register back to its reset value and the SII
    /// configuration area reloaded. The EEPROM keeps what was written to it;
    /// the local clock keeps running.
    pub fn reset(&mut self) {
        self.power_on();
        self.events.push(EscEvent::EscReset);
    }

    fn power_on(&mut self) {
        self.mem.fill(0);
        self.fmmus = [Fmmu::default(); 16];
        self.fmmu_n = 0;
        self.sms = [SyncManager::default(); 16];
        self.sm_guard = 0;
        self.sm_activate = [0; 16];
        self.sync = SyncUnit::default();
        self.dc_last_sample = None;
        self.dc_mean = 0;
        self.wd = Watchdogs { pdi_ok: true, ..Watchdogs::default() };
        self.events.clear();
        self.al_control_full = false;
        self.al_event_misc = 0;
        self.ecat_event_misc = 0;
        let c = &self.cfg;
        let m = &mut self.mem;
        m[0x0000] = c.esc_type;
        m[0x0001] = c.revision;
        m[0x0002..0x0004].copy_from_slice(&c.build.to_le_bytes());
        m[0x0004] = c.fmmus;
        m[0x0005] = c.sync_managers;
        m[0x0006] = c.ram_kib;
        m[0x0007] = (0..c.ports).fold(0u8, |d, p| d | (0b11 << (2 * p)));
        // Bit 2 DC, bit 3 64-bit DC, bit 8 enhanced DC SYNC activation.
        let features: u16 = if c.dc { 0x010C } else { 0 };
        m[0x0008..0x000A].copy_from_slice(&features.to_le_bytes());
        // DL control reset value: forwarding rule 1, RX FIFO size 7.
        m[0x0100] = 0x01;
        m[0x0102] = 0x07;
        m[0x0120] = 0x01;
        m[0x0130] = 0x01;
        m[0x0400..0x0402].copy_from_slice(&2498u16.to_le_bytes());
        m[0x0410..0x0412].copy_from_slice(&1000u16.to_le_bytes());
        m[0x0420..0x0422].copy_from_slice(&1000u16.to_le_bytes());
        m[0x0440] = 0x01;
        if c.dc {
            m[0x0930..0x0932].copy_from_slice(&0x1000u16.to_le_bytes());
            m[0x0934] = 0x04;
            m[0x0935] = 0x0C;
        }
        self.load_config_area();
        self.update_dl_status(false);
    }

    /// Applies SII words 0–4 to the registers if the CRC is right
    /// (otherwise: 0x0502 bits 11/12 set, DL status "PDI operational" 0).
    pub(crate) fn load_config_area(&mut self) {
        let img = &self.sii.image;
        let ok = img.checksum_ok();
        if ok {
            let w0 = img.word(0);
            self.mem[0x0140..0x0142].copy_from_slice(&w0.to_le_bytes());
            self.mem[0x0150..0x0152].copy_from_slice(&img.word(1).to_le_bytes());
            self.mem[0x0982..0x0984].copy_from_slice(&img.word(2).to_le_bytes());
            self.mem[0x0152..0x0154].copy_from_slice(&img.word(3).to_le_bytes());
            self.mem[0x0012..0x0014].copy_from_slice(&img.word(4).to_le_bytes());
        }
        self.eeprom_loaded = ok;
        let (head, _) = self.mem.split_at_mut(reg::REGISTER_SPACE);
        self.sii.set_load_status(ok, head);
    }

    /// True if the ESC emulates the AL status itself (0x0141 bit 0): a
    /// device without firmware, like an EK1100 coupler.
    pub fn device_emulation(&self) -> bool {
        self.mem[0x0141] & 1 != 0
    }

    /// The configuration this ESC was built with (its SII image lives in
    /// [`Esc::sii_image`]).
    pub fn config(&self) -> &EscConfig {
        &self.cfg
    }

    /// The latest `now` seen.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// Moves time forward and does what became due: SII commands, watchdog
    /// expiries, SYNC pulses. Returns the next deadline.
    pub fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.advance(now);
        self.next_deadline()
    }

    /// Earliest instant at which [`Esc::poll`] has work.
    pub fn next_deadline(&self) -> Option<Instant> {
        let mut d = earliest(self.sii.deadline(), self.wd.pd_deadline);
        d = earliest(d, self.wd.pdi_deadline);
        if let Some(sys) = self.sync.next_due() {
            let local = sys.wrapping_sub(self.system_time_offset());
            let at = match self.sync_instant.get() {
                Some((l, c, at)) if l == local && c == self.clock => at,
                _ => {
                    let at = self.clock.instant_of(local);
                    self.sync_instant.set(Some((local, self.clock, at)));
                    at
                }
            };
            d = earliest(d, Some(at.max(self.now)));
        }
        d
    }

    pub(crate) fn advance(&mut self, now: Instant) {
        if now > self.now {
            self.now = now;
        }
        let now = self.now;
        if let Some(done) = {
            let (head, _) = self.mem.split_at_mut(reg::REGISTER_SPACE);
            self.sii.advance(head, now)
        } {
            self.sii_done(done);
        }
        if self.wd.pd_deadline.is_some_and(|d| d <= now) {
            self.wd.pd_deadline = None;
            self.mem[0x0440] &= !1;
            self.mem[0x0442] = self.mem[0x0442].saturating_add(1);
            self.al_event_misc |= reg::al_event::WATCHDOG;
            self.update_al_event();
            self.events.push(EscEvent::ProcessDataWatchdog);
        }
        if self.wd.pdi_deadline.is_some_and(|d| d <= now) {
            self.wd.pdi_deadline = None;
            self.wd.pdi_ok = false;
            self.mem[0x0443] = self.mem[0x0443].saturating_add(1);
            self.update_dl_status(true);
            self.events.push(EscEvent::PdiWatchdog);
        }
        if self.sync.active {
            let sys = self.system_time(now);
            while let Some(p) = self.sync.take_sync0(sys) {
                self.mem[0x098E] |= 1;
                let at = self.instant_of_system(p.system_time);
                self.events.push(EscEvent::Sync0 { system_time: p.system_time, at, missed: p.missed });
            }
            while let Some(p) = self.sync.take_sync1(sys) {
                self.mem[0x098F] |= 1;
                let at = self.instant_of_system(p.system_time);
                self.events.push(EscEvent::Sync1 { system_time: p.system_time, at, missed: p.missed });
            }
            // Bit 0/1 of 0x0984: the first pulse is still pending.
            self.mem[0x0984] = u8::from(self.sync.sync0_pulses == 0);
        }
    }

    pub(crate) fn sii_done(&mut self, done: SiiDone) {
        match done {
            SiiDone::Read => {}
            SiiDone::Written => self.events.push(EscEvent::SiiWritten),
            SiiDone::Reloaded => {
                self.load_config_area();
                self.update_dl_status(true);
                self.events.push(EscEvent::SiiReloaded);
            }
        }
    }

    /// Takes the next pending event for the firmware.
    pub fn pop_event(&mut self) -> Option<EscEvent> {
        self.events.pop()
    }

    /// True if events are pending.
    pub fn has_events(&self) -> bool {
        !self.events.is_empty()
    }

    // ---- time ----------------------------------------------------------

    /// Local time (ns) at `now`.
    pub fn local_time(&self, now: Instant) -> u64 {
        self.clock.local(now)
    }

    pub(crate) fn system_time_offset(&self) -> u64 {
        u64::from_le_bytes(self.mem[0x0920..0x0928].try_into().unwrap_or([0; 8]))
    }

    /// System time (local time + 0x0920) at `now`.
    pub fn system_time(&self, now: Instant) -> u64 {
        self.clock.local(now).wrapping_add(self.system_time_offset())
    }

    /// Caller instant at which this ESC's system time reaches `sys`.
    pub fn instant_of_system(&self, sys: u64) -> Instant {
        self.clock.instant_of(sys.wrapping_sub(self.system_time_offset()))
    }

    /// Sets the local oscillator's frequency error (ppb, positive: fast)
    /// from the latest `now` on, as a drifting clock would; the local time
    /// stays continuous. [`EscConfig::clock`] keeps the one it was built with.
    pub fn set_clock_drift(&mut self, drift_ppb: i32) {
        self.clock.set_drift(self.now, drift_ppb);
    }

    /// Gives the clock's time stamps bounded random jitter (a fault), or
    /// ends it (`None`): from now on every stamp the ESC takes (the receive
    /// times 0x0900–0x091F, a read of the system time 0x0910, the compare
    /// of a master's 0x0910 write that steers the control loop) is off by
    /// a value in ±`amplitude_ns` (at most [`MAX_JITTER_NS`]) drawn from a
    /// generator seeded with `seed`, so a run replays.
    pub fn set_clock_jitter(&mut self, jitter: Option<(u32, u64)>) {
        self.jitter = jitter.map(|(a, seed)| (a.min(MAX_JITTER_NS), drivebus_base::XorShift64::new(seed)));
    }

    /// A time `t` as the ESC stamps it: plus the jitter, if on.
    pub(crate) fn stamp(&mut self, t: u64) -> u64 {
        match &mut self.jitter {
            Some((a, rng)) => {
                let a = u64::from(*a);
                t.wrapping_add(rng.below(2 * a + 1)).wrapping_sub(a)
            }
            None => t,
        }
    }

    /// Frequency correction of the time control loop, in ppb.
    pub fn clock_correction_ppb(&self) -> i64 {
        self.clock.correction_ppb()
    }

    // ---- topology ------------------------------------------------------

    /// Sets which ports have a physical link (the segment does this).
    pub fn set_port_links(&mut self, links: [bool; 4]) {
        let mut l = links;
        for (p, v) in l.iter_mut().enumerate() {
            if p >= usize::from(self.cfg.ports) {
                *v = false;
            }
        }
        if l != self.links {
            for (p, up) in l.iter().enumerate() {
                if self.links[p] && !up {
                    let c = &mut self.mem[0x0310 + p];
                    *c = c.saturating_add(1);
                }
            }
            self.links = l;
            self.update_dl_status(true);
        }
    }

    /// Counts a frame with a bad FCS received on port `p` (0..=3): the
    /// invalid frame counter (0x0300 + 2p), or the forwarded RX error
    /// counter (0x0308 + p) when an earlier ESC had marked it already.
    /// Both stop at 0xFF (ESC data sheet Section II, 0x0300–0x030B).
    pub fn count_rx_error(&mut self, p: usize, forwarded: bool) {
        let at = if forwarded { 0x0308 + p.min(3) } else { 0x0300 + 2 * p.min(3) };
        self.mem[at] = self.mem[at].saturating_add(1);
    }

    /// True if frames leave through port `p` (link up and the loop not
    /// closed by DL control 0x0101: 00/01 auto, 10 open, 11 closed).
    pub fn port_open(&self, p: usize) -> bool {
        if p >= usize::from(self.cfg.ports) {
            return false;
        }
        match (self.mem[0x0101] >> (2 * p)) & 3 {
            0 | 1 => self.links[p],
            2 => true,
            _ => false,
        }
    }

    pub(crate) fn update_dl_status(&mut self, raise: bool) {
        let mut v = u16::from(self.eeprom_loaded) | (u16::from(self.wd.pdi_ok) << 1);
        for p in 0..4 {
            if self.links[p] {
                v |= 1 << (4 + p) | 1 << (9 + 2 * p);
            }
            if !self.port_open(p) {
                v |= 1 << (8 + 2 * p);
            }
        }
        let old = u16::from_le_bytes([self.mem[0x0110], self.mem[0x0111]]);
        if old != v {
            self.mem[0x0110..0x0112].copy_from_slice(&v.to_le_bytes());
            if raise {
                self.ecat_event_misc |= reg::ecat_event::DL_STATUS;
                self.update_ecat_event();
                self.events.push(EscEvent::DlStatusChanged);
            }
        }
    }

    // ---- event registers ------------------------------------------------

    pub(crate) fn update_al_event(&mut self) {
        let mut v = self.al_event_misc;
        for (n, sm) in self.sms.iter().enumerate() {
            if sm.pdi_irq() {
                v |= reg::al_event::SM0 << n;
            }
        }
        self.mem[0x0220..0x0224].copy_from_slice(&v.to_le_bytes());
    }

    pub(crate) fn update_ecat_event(&mut self) {
        let mut v = self.ecat_event_misc;
        for (n, sm) in self.sms.iter().take(8).enumerate() {
            if sm.ecat_irq() {
                v |= reg::ecat_event::SM0 << n;
            }
        }
        self.mem[0x0210..0x0212].copy_from_slice(&v.to_le_bytes());
    }

    // ---- PDI side -------------------------------------------------------

    /// The firmware reads ESC memory with PDI access rights and side
    /// effects (reading 0x0120 acknowledges AL control, SM buffers follow
    /// the sync manager rules, …). Returns false if any byte was refused
    /// (e.g. an empty mailbox); refused bytes are left as they were.
    pub fn pdi_read(&mut self, addr: u16, buf: &mut [u8]) -> bool {
        self.pdi_touch();
        self.read(Side::Pdi, usize::from(addr), buf) == buf.len()
    }

    /// The firmware writes ESC memory with PDI access rights. Returns false
    /// if any byte was refused (e.g. a full mailbox).
    pub fn pdi_write(&mut self, addr: u16, data: &[u8]) -> bool {
        self.pdi_touch();
        self.write(Side::Pdi, usize::from(addr), data) == data.len()
    }

    fn pdi_touch(&mut self) {
        let t = self.watchdog_time(0x0410);
        self.wd.pdi_deadline = t.map(|t| self.now + t);
        if !self.wd.pdi_ok {
            self.wd.pdi_ok = true;
            self.update_dl_status(true);
        }
    }

    /// A watchdog time register (0x0410 or 0x0420) in real time, `None` if 0.
    pub(crate) fn watchdog_time(&self, at: usize) -> Option<Duration> {
        let div = u64::from(u16::from_le_bytes([self.mem[0x0400], self.mem[0x0401]]));
        let n = u64::from(u16::from_le_bytes([self.mem[at], self.mem[at + 1]]));
        (n != 0).then(|| Duration::from_nanos(n * (div + 2) * 40))
    }

    /// Reads memory without side effects (live DC registers excluded:
    /// they show their last value).
    pub fn peek(&self, addr: u16, buf: &mut [u8]) {
        let a = usize::from(addr);
        for (i, b) in buf.iter_mut().enumerate() {
            *b = self.mem.get(a + i).copied().unwrap_or(0);
        }
    }

    /// A 16-bit register, without side effects.
    pub fn peek_u16(&self, addr: u16) -> u16 {
        let mut b = [0u8; 2];
        self.peek(addr, &mut b);
        u16::from_le_bytes(b)
    }

    /// Configured station address (0x0010).
    pub fn station_address(&self) -> u16 {
        self.peek_u16(reg::STATION_ADDRESS)
    }

    /// AL status register (0x0130).
    pub fn al_status(&self) -> u16 {
        self.peek_u16(reg::AL_STATUS)
    }

    /// Sync manager `n` as the master configured it.
    pub fn sync_manager(&self, n: usize) -> Option<SmInfo> {
        let b = usize::from(reg::SM_BASE) + n * 8;
        (n < usize::from(self.cfg.sync_managers)).then(|| SmInfo {
            start: u16::from_le_bytes([self.mem[b], self.mem[b + 1]]),
            length: u16::from_le_bytes([self.mem[b + 2], self.mem[b + 3]]),
            control: self.mem[b + 4],
            status: self.mem[b + 5],
            enabled: self.mem[b + 6] & 1 != 0,
            activate: self.mem[b + 6],
            pdi_control: self.mem[b + 7],
        })
    }

    /// FMMU `n` as the master configured it.
    pub fn fmmu(&self, n: usize) -> Option<Fmmu> {
        (n < usize::from(self.cfg.fmmus)).then(|| self.fmmus[n])
    }

    /// The SII image, including words the master wrote.
    pub fn sii_image(&self) -> &SiiImage {
        &self.sii.image
    }

    /// True (once) if the master wrote the SII since the last call, so the
    /// caller can persist [`Esc::sii_image`].
    pub fn take_sii_dirty(&mut self) -> bool {
        core::mem::take(&mut self.sii.dirty)
    }
}

/// A sync manager's registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SmInfo {
    /// Physical start address.
    pub start: u16,
    /// Length.
    pub length: u16,
    /// Control register.
    pub control: u8,
    /// Status register.
    pub status: u8,
    /// Activate bit 0.
    pub enabled: bool,
    /// Whole activate register (bit 1 repeat request).
    pub activate: u8,
    /// PDI control register (bit 0 deactivate, bit 1 repeat acknowledge).
    pub pdi_control: u8,
}
