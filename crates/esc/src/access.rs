//! Reads and writes of ESC memory from either side, with the register
//! side effects of the ESC data sheet (Section II) and the sync manager
//! rules for process RAM.
//!
//! Counting (for the working counter; ESC data sheet Section I: the
//! counter is incremented if at least one byte of the datagram was
//! successfully read or written):
//!
//! * A register byte counts whenever it is implemented, even when the write
//!   only hit read-only bits. Real ESCs treat the register block as memory
//!   with per-bit write masks: writes to read-only bits are dropped, the
//!   access itself succeeds, and unused registers read 0 with the access
//!   still counted ("unused register access allowed", 0x0008 bit 1 = 0).
//!   The exceptions are accesses that the ESC *refuses*: a master write to
//!   AL control while the PDI has not read the previous one (below) and
//!   blocks this configuration does not implement (DC registers without
//!   DC, FMMUs/SMs beyond the configured count) — ethercrab relies on the
//!   latter when it counts DC slaves with `BWR 0x0900`.
//! * A RAM byte counts when it lies outside every active sync manager or
//!   the sync manager accepted it (see `sm.rs`); bytes past the end of the
//!   process RAM never count.
//!
//! AL control (0x0120) behaves like a mailbox when device emulation is off
//! (0x0141 bit 0 = 0), per the data sheet note on 0x0120: after the master
//! wrote it, further master writes are refused until the PDI has read it.
//! With device emulation on, the written state is copied to AL status.

use crate::dc::diff_register;
use crate::eeprom::SiiUnit;
use crate::esc::Esc;
use crate::events::EscEvent;
use crate::fmmu::Fmmu;
use crate::registers::{self as reg, ECAT_WRITE, PDI_WRITE, REGISTER_SPACE, sm_index};
use crate::sm::{Side, SmEffect};

#[inline]
fn touches(a: usize, end: usize, lo: usize, n: usize) -> bool {
    a < lo + n && end > lo
}

impl Esc {
    /// True if register byte `a` exists in this configuration.
    #[inline]
    pub(crate) fn implemented(&self, a: usize) -> bool {
        match a {
            0x0600..=0x06FF => (a - 0x0600) / 16 < usize::from(self.cfg.fmmus),
            0x0800..=0x087F => (a - 0x0800) / 8 < usize::from(self.cfg.sync_managers),
            0x0900..=0x09FF => self.cfg.dc,
            _ => true,
        }
    }

    /// Reads `buf.len()` bytes from `addr`; returns how many were readable.
    pub(crate) fn read(&mut self, side: Side, addr: usize, buf: &mut [u8]) -> usize {
        let end = addr + buf.len();
        let mut n = 0;
        if addr < REGISTER_SPACE {
            let e = end.min(REGISTER_SPACE);
            n += self.reg_read(side, addr, &mut buf[..e - addr]);
        }
        if end > REGISTER_SPACE {
            let s = addr.max(REGISTER_SPACE);
            n += self.ram(side, s, Buf::Read(&mut buf[s - addr..]));
        }
        n
    }

    /// Writes `data` at `addr` (only the bits in `mask` of every byte);
    /// returns how many bytes were accepted.
    pub(crate) fn write(&mut self, side: Side, addr: usize, data: &[u8]) -> usize {
        self.write_masked(side, addr, data, 0xFF)
    }

    pub(crate) fn write_masked(&mut self, side: Side, addr: usize, data: &[u8], mask: u8) -> usize {
        let end = addr + data.len();
        let mut n = 0;
        if addr < REGISTER_SPACE {
            let e = end.min(REGISTER_SPACE);
            n += self.reg_write(side, addr, &data[..e - addr], mask);
        }
        if end > REGISTER_SPACE {
            let s = addr.max(REGISTER_SPACE);
            n += self.ram(side, s, Buf::Write(&data[s - addr..], mask));
        }
        n
    }

    fn reg_read(&mut self, side: Side, a: usize, buf: &mut [u8]) -> usize {
        let end = a + buf.len();
        if self.cfg.dc && touches(a, end, 0x0910, 0x98) {
            self.refresh_dc_registers(a, end);
        }
        buf.copy_from_slice(&self.mem[a..end]);
        let mut count = buf.len();
        if touches(a, end, 0x0600, 0x400) {
            count = (a..end).filter(|&r| self.implemented(r)).count();
            for (i, b) in buf.iter_mut().enumerate() {
                if !self.implemented(a + i) {
                    *b = 0;
                }
            }
        }
        match side {
            Side::Ecat => {
                if touches(a, end, 0x0130, 2) && self.ecat_event_misc & reg::ecat_event::AL_STATUS != 0 {
                    self.ecat_event_misc &= !reg::ecat_event::AL_STATUS;
                    self.update_ecat_event();
                }
                if touches(a, end, 0x0110, 2) && self.ecat_event_misc & reg::ecat_event::DL_STATUS != 0 {
                    self.ecat_event_misc &= !reg::ecat_event::DL_STATUS;
                    self.update_ecat_event();
                }
            }
            Side::Pdi => {
                if touches(a, end, 0x0120, 2) {
                    self.al_control_full = false;
                    self.al_event_misc &= !reg::al_event::AL_CONTROL;
                    self.update_al_event();
                }
                if touches(a, end, 0x0440, 1) {
                    self.al_event_misc &= !reg::al_event::WATCHDOG;
                    self.update_al_event();
                }
                if touches(a, end, 0x0806, 0x79) && (a..end).any(|r| sm_index(r).is_some() && r % 8 == 6) {
                    self.al_event_misc &= !reg::al_event::SM_CHANGED;
                    self.update_al_event();
                }
            }
        }
        // SYNC status bits clear when read (either side).
        if self.cfg.dc {
            for r in [0x098E, 0x098F] {
                if touches(a, end, r, 1) {
                    self.mem[r] = 0;
                }
            }
        }
        count
    }

    /// Puts the live DC values into the register image before a read.
    fn refresh_dc_registers(&mut self, a: usize, end: usize) {
        let now = self.now;
        if touches(a, end, 0x0910, 8) {
            let t = self.system_time(now);
            let t = self.stamp(t);
            self.mem[0x0910..0x0918].copy_from_slice(&t.to_le_bytes());
        }
        if self.sync.active {
            if touches(a, end, 0x0990, 8)
                && let Some(t) = self.sync.sync0_next
            {
                self.mem[0x0990..0x0998].copy_from_slice(&t.to_le_bytes());
            }
            if touches(a, end, 0x0998, 8) {
                let t = self.sync.sync1_next.unwrap_or(0);
                self.mem[0x0998..0x09A0].copy_from_slice(&t.to_le_bytes());
            }
        }
    }

    fn reg_write(&mut self, side: Side, a: usize, data: &[u8], bits: u8) -> usize {
        let end = a + data.len();
        let table = match side {
            Side::Ecat => &ECAT_WRITE,
            Side::Pdi => &PDI_WRITE,
        };
        let pdi_owns = SiiUnit::pdi_owns(&self.mem);
        let sii_blocked = self.sii.busy() || pdi_owns != (side == Side::Pdi);
        let al_blocked = side == Side::Ecat && self.al_control_full && !self.device_emulation();
        let old_al_status = [self.mem[0x0130], self.mem[0x0131]];
        let mut count = 0;
        let mut al_written = false;
        for (i, &v) in data.iter().enumerate() {
            let r = a + i;
            if !self.implemented(r) {
                continue;
            }
            if side == Side::Ecat && (r == 0x0120 || r == 0x0121) {
                if al_blocked {
                    continue;
                }
                al_written = true;
            }
            count += 1;
            let mut mask = table[r] & bits;
            if (0x0502..0x0510).contains(&r) {
                mask = if sii_blocked || r < 0x0504 { 0 } else { bits };
            } else if let Some(n) = sm_index(r) {
                if r % 8 < 5 && self.mem[0x0806 + n * 8] & 1 != 0 {
                    mask = 0; // start/length/control only while disabled
                }
            } else if (0x0990..0x0998).contains(&r) && self.sync.active {
                mask = 0; // start time only while cyclic operation is off
            }
            self.mem[r] = (self.mem[r] & !mask) | (v & mask);
        }
        if count == 0 {
            return 0;
        }
        let at = |r: usize| data.get(r.wrapping_sub(a)).copied();
        match side {
            Side::Ecat => self.ecat_write_effects(a, end, &at, al_written, sii_blocked),
            Side::Pdi => {
                if touches(a, end, 0x0130, 2) && old_al_status != [self.mem[0x0130], self.mem[0x0131]] {
                    self.ecat_event_misc |= reg::ecat_event::AL_STATUS;
                    self.update_ecat_event();
                }
                if touches(a, end, 0x0502, 2) && !sii_blocked {
                    self.sii_control(at(0x0502), at(0x0503));
                }
                if touches(a, end, 0x0807, 0x79) {
                    for n in 0..usize::from(self.cfg.sync_managers) {
                        if touches(a, end, 0x0807 + n * 8, 1) {
                            self.pdi_sm_control(n);
                        }
                    }
                }
            }
        }
        count
    }

    fn ecat_write_effects(
        &mut self,
        a: usize,
        end: usize,
        at: &dyn Fn(usize) -> Option<u8>,
        al_written: bool,
        sii_blocked: bool,
    ) {
        if let Some(v) = at(0x0040) {
            self.esc_reset_byte(v);
        }
        if touches(a, end, 0x0100, 4) {
            self.update_dl_status(true);
        }
        if al_written {
            self.al_control_written();
        }
        if touches(a, end, 0x0300, 0x0C) {
            self.mem[0x0300..0x030C].fill(0);
        }
        for r in [0x030C, 0x030D, 0x0310, 0x0311, 0x0312, 0x0313] {
            if touches(a, end, r, 1) {
                self.mem[r] = 0;
            }
        }
        if touches(a, end, 0x0442, 2) {
            self.mem[0x0442] = 0;
            self.mem[0x0443] = 0;
        }
        if touches(a, end, 0x0400, 0x22) {
            if self.watchdog_time(0x0420).is_none() {
                self.wd.pd_deadline = None;
                self.mem[0x0440] |= 1;
            }
            if self.watchdog_time(0x0410).is_none() {
                self.wd.pdi_deadline = None;
            }
        }
        if at(0x0500).is_some_and(|v| v & 0x02 != 0) {
            self.mem[0x0501] &= !1; // force ECAT access
        }
        if touches(a, end, 0x0502, 2) && !sii_blocked {
            self.sii_control(at(0x0502), at(0x0503));
        }
        if touches(a, end, 0x0600, 0x100) {
            self.refresh_fmmus();
        }
        if touches(a, end, 0x0800, 0x80) {
            for n in 0..usize::from(self.cfg.sync_managers) {
                if touches(a, end, 0x0800 + n * 8, 8) {
                    self.refresh_sm(n);
                }
            }
        }
        if !self.cfg.dc || !touches(a, end, 0x0900, 0x100) {
            return;
        }
        if touches(a, end, 0x0900, 1) {
            self.latch_receive_times();
        }
        if touches(a, end, 0x0910, 8) {
            self.dc_sample(at);
        }
        if touches(a, end, 0x0930, 2) || touches(a, end, 0x0934, 2) {
            self.clock.reset_loop(self.now);
            self.dc_mean = 0;
            self.dc_last_sample = None;
            self.mem[0x092C..0x0930].fill(0);
            self.mem[0x0932..0x0934].fill(0);
        }
        if touches(a, end, 0x0981, 1) {
            self.dc_activation();
        } else if touches(a, end, 0x0990, 8) && !self.sync.active && self.mem[0x0981] & 0x08 != 0 {
            self.mem[0x0981] |= 1; // auto-activation by writing the start time
            self.dc_activation();
        }
    }

    fn sii_control(&mut self, low: Option<u8>, high: Option<u8>) {
        let now = self.now;
        let done = {
            let (head, _) = self.mem.split_at_mut(REGISTER_SPACE);
            self.sii.control_write(head, low, high, now)
        };
        if let Some(d) = done {
            self.sii_done(d);
        }
    }

    fn al_control_written(&mut self) {
        if self.device_emulation() {
            let old = self.mem[0x0130];
            self.mem[0x0130] = self.mem[0x0120] & 0x0F;
            if old != self.mem[0x0130] {
                self.ecat_event_misc |= reg::ecat_event::AL_STATUS;
                self.update_ecat_event();
            }
        } else {
            self.al_control_full = true;
            self.al_event_misc |= reg::al_event::AL_CONTROL;
            self.update_al_event();
            self.events.push(EscEvent::AlControl);
        }
    }

    fn esc_reset_byte(&mut self, v: u8) {
        let (stage, frame) = self.reset_stage;
        let next = self.frame_no == frame + 1;
        self.reset_stage = match (v, stage) {
            (b'R', _) => (1, self.frame_no),
            (b'E', 1) if next => (2, self.frame_no),
            (b'S', 2) if next => (3, self.frame_no),
            _ => (0, 0),
        };
    }

    pub(crate) fn refresh_fmmus(&mut self) {
        self.fmmu_n = 0;
        for n in 0..usize::from(self.cfg.fmmus) {
            let b = 0x0600 + n * 16;
            let mut r = [0u8; 16];
            r.copy_from_slice(&self.mem[b..b + 16]);
            self.fmmus[n] = Fmmu::from_registers(&r);
            if self.fmmus[n].enabled && self.fmmus[n].length > 0 {
                self.fmmu_active[self.fmmu_n] = n as u8;
                self.fmmu_n += 1;
            }
        }
    }

    /// Applies the SM `n` registers after a master write: enabling takes a
    /// snapshot of start, length and control (they are locked while
    /// enabled); any change of the activate register is an AL event.
    fn refresh_sm(&mut self, n: usize) {
        let b = 0x0800 + n * 8;
        let act = self.mem[b + 6];
        let old = self.sm_activate[n];
        if (act ^ old) & 1 != 0 {
            let start = u16::from_le_bytes([self.mem[b], self.mem[b + 1]]);
            let len = u16::from_le_bytes([self.mem[b + 2], self.mem[b + 3]]);
            self.sms[n].configure(act & 1 != 0, start, len, self.mem[b + 4]);
        }
        if act != old {
            self.al_event_misc |= reg::al_event::SM_CHANGED;
            self.events.push(EscEvent::SmChanged);
        }
        self.sm_activate[n] = act;
        self.sm_registers_changed(n);
    }

    /// The PDI wrote SM `n`'s PDI control register.
    fn pdi_sm_control(&mut self, n: usize) {
        let off = self.mem[0x0807 + n * 8] & 1 != 0;
        if off != self.sms[n].pdi_off {
            self.sms[n].pdi_off = off;
            self.sms[n].reset_buffers();
            self.sm_registers_changed(n);
        }
    }

    pub(crate) fn sm_registers_changed(&mut self, n: usize) {
        if self.sms[n].guards() {
            self.sm_guard |= 1 << n;
        } else {
            self.sm_guard &= !(1 << n);
        }
        self.mem[0x0805 + n * 8] = if self.sms[n].guards() { self.sms[n].status() } else { 0 };
        self.update_al_event();
        self.update_ecat_event();
    }

    fn sm_effect(&mut self, n: usize, effect: Option<SmEffect>) {
        match effect {
            Some(SmEffect::Written(Side::Ecat)) => {
                self.events.push(EscEvent::SmWritten(n as u8));
                if self.sms[n].control & 0x40 != 0 {
                    self.trigger_pd_watchdog();
                }
            }
            Some(SmEffect::Read(Side::Ecat)) => self.events.push(EscEvent::SmRead(n as u8)),
            _ => {}
        }
        self.mem[0x0805 + n * 8] = self.sms[n].status();
        self.sm_irq_bits(n);
    }

    /// Mirrors SM `n`'s interrupt state into the AL and ECAT event request
    /// registers (the frame-path version of a full recompute).
    fn sm_irq_bits(&mut self, n: usize) {
        let (pdi, ecat) = (self.sms[n].pdi_irq(), self.sms[n].ecat_irq());
        let byte = 0x0221 + n / 8;
        let bit = 1u8 << (n % 8);
        self.mem[byte] = if pdi { self.mem[byte] | bit } else { self.mem[byte] & !bit };
        if n < 8 {
            let (byte, bit) = (0x0210 + (n + 4) / 8, 1u8 << ((n + 4) % 8));
            self.mem[byte] = if ecat { self.mem[byte] | bit } else { self.mem[byte] & !bit };
        }
    }

    pub(crate) fn trigger_pd_watchdog(&mut self) {
        if let Some(t) = self.watchdog_time(0x0420) {
            self.wd.pd_deadline = Some(self.now + t);
        }
        self.mem[0x0440] |= 1;
    }

    fn latch_receive_times(&mut self) {
        let t = self.timing;
        for (p, rx) in t.port_rx.iter().enumerate() {
            if let Some(i) = rx {
                let l = self.clock.local(*i);
                let l = self.stamp(l) as u32;
                self.mem[0x0900 + 4 * p..0x0904 + 4 * p].copy_from_slice(&l.to_le_bytes());
            }
        }
        let l = self.clock.local(t.at);
        let l = self.stamp(l);
        self.mem[0x0918..0x0920].copy_from_slice(&l.to_le_bytes());
    }

    /// A master write to the system time: one sample for the control loop.
    fn dc_sample(&mut self, at: &dyn Fn(usize) -> Option<u8>) {
        let now = self.now;
        let sys = self.system_time(now);
        let sys = self.stamp(sys);
        let mut rb = sys.to_le_bytes();
        let mut hi = false;
        for (i, b) in rb.iter_mut().enumerate() {
            if let Some(v) = at(0x0910 + i) {
                *b = v;
                hi |= i >= 4;
            }
        }
        let delay = u64::from(u32::from_le_bytes(self.mem[0x0928..0x092C].try_into().unwrap_or([0; 4])));
        let target = u64::from_le_bytes(rb).wrapping_add(delay);
        let e = if hi {
            target.wrapping_sub(sys) as i64
        } else {
            i64::from((target as u32).wrapping_sub(sys as u32) as i32)
        };
        let interval = self.dc_last_sample.map_or(1_000_000, |l| (now - l).as_nanos() as u64);
        self.clock.sample(now, e, interval);
        self.dc_last_sample = Some(now);
        let depth = u32::from(self.mem[0x0934] & 0x0F);
        self.dc_mean = self.dc_mean.saturating_add(e.saturating_sub(self.dc_mean) / (1i64 << depth));
        self.mem[0x092C..0x0930].copy_from_slice(&diff_register(self.dc_mean).to_le_bytes());
        let speed =
            (self.clock.correction_ppb() / 100).clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16;
        self.mem[0x0932..0x0934].copy_from_slice(&speed.to_le_bytes());
    }

    fn dc_activation(&mut self) {
        let act = self.mem[0x0981];
        if act & 1 != 0 && !self.sync.active {
            let start = u64::from_le_bytes(self.mem[0x0990..0x0998].try_into().unwrap_or([0; 8]));
            let c0 = u32::from_le_bytes(self.mem[0x09A0..0x09A4].try_into().unwrap_or([0; 4]));
            let c1 = u32::from_le_bytes(self.mem[0x09A4..0x09A8].try_into().unwrap_or([0; 4]));
            let sys = self.system_time(self.now);
            self.sync.activate(act, start, c0, c1, sys);
            self.mem[0x0984] = 1;
        } else if act & 1 == 0 && self.sync.active {
            self.sync.deactivate();
            self.mem[0x0984] = 0;
        } else if self.sync.active {
            self.sync.sync0_on = act & 0x02 != 0;
            self.sync.sync1_on = act & 0x04 != 0;
        }
    }

    /// Process RAM access through the sync managers.
    fn ram(&mut self, side: Side, addr: usize, mut buf: Buf<'_>) -> usize {
        let total = buf.len();
        let end = (addr + total).min(self.mem.len());
        let mut p = addr;
        let mut n = 0;
        while p < end {
            let mut seg_end = end;
            let mut hit = None;
            let mut g = self.sm_guard;
            while g != 0 {
                let i = g.trailing_zeros() as usize;
                g &= g - 1;
                let s = usize::from(self.sms[i].start);
                let f = s + self.sms[i].footprint();
                if p >= s && p < f {
                    hit = Some(i);
                    seg_end = seg_end.min(f);
                    break;
                }
                if s > p {
                    seg_end = seg_end.min(s);
                }
            }
            let Some(i) = hit else {
                n += buf.copy(&mut self.mem, p - addr, p, seg_end - p);
                p = seg_end;
                continue;
            };
            let off = p - usize::from(self.sms[i].start);
            let l = usize::from(self.sms[i].len);
            if off >= l {
                p = seg_end; // shadow buffers: not addressable
                continue;
            }
            let len = (seg_end - p).min(l - off);
            let acc = self.sms[i].access(side, buf.is_write(), off, len);
            if let Some(phys) = acc.phys
                && phys + len <= self.mem.len()
            {
                n += buf.copy(&mut self.mem, p - addr, phys, len);
            }
            self.sm_effect(i, acc.effect);
            p += len;
        }
        n
    }
}

/// Direction and data of a RAM access.
enum Buf<'a> {
    Read(&'a mut [u8]),
    Write(&'a [u8], u8),
}

impl Buf<'_> {
    fn len(&self) -> usize {
        match self {
            Buf::Read(b) => b.len(),
            Buf::Write(b, _) => b.len(),
        }
    }

    fn is_write(&self) -> bool {
        matches!(self, Buf::Write(..))
    }

    /// Copies `len` bytes between buffer offset `off` and memory `phys`.
    fn copy(&mut self, mem: &mut [u8], off: usize, phys: usize, len: usize) -> usize {
        match self {
            Buf::Read(b) => b[off..off + len].copy_from_slice(&mem[phys..phys + len]),
            Buf::Write(b, 0xFF) => mem[phys..phys + len].copy_from_slice(&b[off..off + len]),
            Buf::Write(b, m) => {
                for (d, s) in mem[phys..phys + len].iter_mut().zip(&b[off..off + len]) {
                    *d = (*d & !*m) | (*s & *m);
                }
            }
        }
        len
    }
}
