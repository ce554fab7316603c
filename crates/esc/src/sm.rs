//! Sync manager buffer logic (ESC data sheet Section I "SyncManager",
//! Section II 0x0800–0x087F).
//!
//! Each SM guards a window `[start, start + length)` of process RAM. The
//! *writer* side (ECAT for direction "write", 0x0804 bits 3:2 = 01; the PDI
//! for direction "read", 00) fills buffers; the *reader* side empties them.
//!
//! * **Mailbox** (mode 10): one buffer. A write is accepted only while the
//!   mailbox is empty; writing the last byte (after the first byte opened
//!   the buffer) makes it full (status bit 3). A read is accepted only while
//!   full; reading the last byte empties it.
//! * **Buffered / 3-buffer** (mode 00): three buffers at `start`,
//!   `start + length`, `start + 2·length`, all seen through the first
//!   window. The writer always writes a free buffer; writing the last byte
//!   makes it the newest complete one. The reader opens the newest complete
//!   buffer when it reads the first byte and keeps it until it opens again;
//!   with nothing new it re-reads the previous one. Accesses to the second
//!   and third buffer's addresses are ignored (they are not addressable).
//! * An SM of length 1 does not buffer (the data sheet: "only the watchdog
//!   trigger is generated"): accesses go straight to memory.
//!
//! Accesses from the wrong side (ECAT reading a write SM, the PDI writing
//! it) are ignored and do not count in the working counter. A disabled SM
//! (0x0806 bit 0 = 0) guards nothing: its area is plain memory for both
//! sides, as on the ESC. An SM the PDI deactivated (0x0807 bit 0) refuses
//! master accesses to its window (no data, no working counter).

/// Which side of the ESC accesses memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The EtherCAT master, through datagrams.
    Ecat,
    /// The slave firmware, through the process data interface.
    Pdi,
}

/// Operation mode (control bits 1:0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SmMode {
    /// 3-buffer mode (00).
    Buffered,
    /// Mailbox / single buffer (10).
    Mailbox,
}

/// A completed buffer operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SmEffect {
    /// The writer finished a buffer.
    Written(Side),
    /// The reader finished a buffer.
    Read(Side),
}

/// Outcome of resolving one access to an SM window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SmAccess {
    /// Physical address where the window offset lives (if allowed).
    pub phys: Option<usize>,
    /// Completion, if this access finished a buffer.
    pub effect: Option<SmEffect>,
}

/// Runtime state of one sync manager.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SyncManager {
    /// Enabled by ECAT (0x0806 bit 0) with a usable configuration.
    pub active: bool,
    /// Deactivated by the PDI (0x0807 bit 0).
    pub pdi_off: bool,
    pub start: u16,
    pub len: u16,
    pub control: u8,
    full: bool,
    write_buf: u8,
    read_buf: u8,
    latest: Option<u8>,
    write_open: bool,
    read_open: bool,
    irq_write: bool,
    irq_read: bool,
}

impl SyncManager {
    /// Mode, or `None` for reserved codes (the SM then stays inactive).
    pub fn mode(control: u8) -> Option<SmMode> {
        match control & 0x03 {
            0b00 => Some(SmMode::Buffered),
            0b10 => Some(SmMode::Mailbox),
            _ => None,
        }
    }

    /// True if the master writes this SM (direction 01).
    #[inline]
    pub fn ecat_writes(control: u8) -> bool {
        control & 0x0C == 0x04
    }

    /// Applies a new activation from the registers: `enabled` is 0x0806
    /// bit 0. Returns true if the SM is usable.
    pub fn configure(&mut self, enabled: bool, start: u16, len: u16, control: u8) {
        let usable = enabled
            && len > 0
            && Self::mode(control).is_some()
            && control & 0x0C != 0x0C
            && control & 0x0C != 0x08;
        *self = SyncManager { active: usable, pdi_off: self.pdi_off, start, len, control, ..Self::fresh() };
    }

    fn fresh() -> SyncManager {
        SyncManager { write_buf: 1, ..Default::default() }
    }

    /// Empties the buffers (ECAT disable or PDI deactivation).
    pub fn reset_buffers(&mut self) {
        let (active, pdi_off, start, len, control) =
            (self.active, self.pdi_off, self.start, self.len, self.control);
        *self = SyncManager { active, pdi_off, start, len, control, ..Self::fresh() };
    }

    /// Bytes of physical memory the SM occupies.
    #[inline]
    pub fn footprint(&self) -> usize {
        match Self::mode(self.control) {
            Some(SmMode::Buffered) if self.len > 1 => usize::from(self.len) * 3,
            _ => usize::from(self.len),
        }
    }

    /// True if accesses to `[start, start + footprint)` are governed by
    /// this SM.
    #[inline]
    pub fn guards(&self) -> bool {
        self.active
    }

    /// Mailbox full flag (status bit 3).
    #[cfg(test)]
    pub fn is_full(&self) -> bool {
        self.full
    }

    /// Status register value (0x0805 + 8·n).
    pub fn status(&self) -> u8 {
        let mut s = u8::from(self.irq_write) | (u8::from(self.irq_read) << 1);
        match Self::mode(self.control) {
            Some(SmMode::Mailbox) => s |= u8::from(self.full) << 3,
            _ => s |= self.latest.unwrap_or(3) << 4,
        }
        s | (u8::from(self.read_open) << 6) | (u8::from(self.write_open) << 7)
    }

    /// The pending interrupt the PDI sees (AL event bit 8 + n, if control
    /// bit 5): "written" for SMs the master writes, "read" otherwise.
    pub fn pdi_irq(&self) -> bool {
        self.active
            && self.control & 0x20 != 0
            && if Self::ecat_writes(self.control) { self.irq_write } else { self.irq_read }
    }

    /// The pending interrupt the master sees (ECAT event bit 4 + n, if
    /// control bit 4).
    pub fn ecat_irq(&self) -> bool {
        self.active
            && self.control & 0x10 != 0
            && if Self::ecat_writes(self.control) { self.irq_read } else { self.irq_write }
    }

    /// Resolves an access of `len` bytes at window offset `off` (which the
    /// caller has checked lies in `[0, footprint)`).
    pub fn access(&mut self, side: Side, write: bool, off: usize, len: usize) -> SmAccess {
        let denied = SmAccess { phys: None, effect: None };
        if self.pdi_off && side == Side::Ecat {
            return denied;
        }
        let l = usize::from(self.len);
        if off >= l {
            // Second and third buffer of a 3-buffer SM: not addressable.
            return denied;
        }
        let ecat_writes = Self::ecat_writes(self.control);
        let writer = if ecat_writes { Side::Ecat } else { Side::Pdi };
        let is_writer = side == writer;
        if write != is_writer {
            return denied;
        }
        let start = usize::from(self.start);
        if l == 1 {
            // Nothing to buffer: every access is a complete one.
            let effect = if write { SmEffect::Written(side) } else { SmEffect::Read(side) };
            return SmAccess { phys: Some(start), effect: Some(effect) };
        }
        let first = off == 0;
        let last = off + len >= l;
        let mode = Self::mode(self.control).unwrap_or(SmMode::Buffered);
        let mut effect = None;
        let phys = if write {
            if mode == SmMode::Mailbox && self.full {
                return denied;
            }
            if first {
                self.write_open = true;
                self.irq_read = false;
            }
            let buf = if mode == SmMode::Mailbox { 0 } else { usize::from(self.write_buf) };
            if last && self.write_open {
                self.write_open = false;
                self.irq_write = true;
                effect = Some(SmEffect::Written(side));
                if mode == SmMode::Mailbox {
                    self.full = true;
                } else {
                    self.latest = Some(self.write_buf);
                    self.write_buf =
                        (0..3).find(|b| Some(*b) != self.latest && *b != self.read_buf).unwrap_or(0);
                }
            }
            start + buf * l + off
        } else {
            if mode == SmMode::Mailbox && !self.full {
                return denied;
            }
            if first {
                self.read_open = true;
                self.irq_write = false;
                if let Some(newest) = self.latest {
                    self.read_buf = newest;
                }
            }
            let buf = if mode == SmMode::Mailbox { 0 } else { usize::from(self.read_buf) };
            if last && self.read_open {
                self.read_open = false;
                self.irq_read = true;
                effect = Some(SmEffect::Read(side));
                if mode == SmMode::Mailbox {
                    self.full = false;
                }
            }
            start + buf * l + off
        };
        SmAccess { phys: Some(phys), effect }
    }

    /// Index of the buffer the reader would open now (3-buffer mode), for
    /// invariant checks.
    #[cfg(test)]
    pub fn newest(&self) -> Option<u8> {
        self.latest
    }

    #[cfg(test)]
    pub fn buffers(&self) -> (u8, u8) {
        (self.write_buf, self.read_buf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sm(control: u8, len: u16) -> SyncManager {
        let mut s = SyncManager::default();
        s.configure(true, 0x1000, len, control);
        s
    }

    #[test]
    fn mailbox_write_fills_on_last_byte_and_pdi_read_empties() {
        let mut s = sm(0x26, 8);
        assert!(s.access(Side::Ecat, false, 0, 8).phys.is_none(), "master cannot read a write mailbox");
        let a = s.access(Side::Ecat, true, 0, 4);
        assert_eq!((a.phys, a.effect), (Some(0x1000), None));
        assert_eq!(s.status() & 0x80, 0x80, "write buffer open");
        let a = s.access(Side::Ecat, true, 4, 4);
        assert_eq!(a.effect, Some(SmEffect::Written(Side::Ecat)));
        assert!(s.is_full());
        assert_eq!(s.status(), 0x09, "full + interrupt write");
        assert!(s.pdi_irq());
        // Full: the next master write is refused.
        assert!(s.access(Side::Ecat, true, 0, 8).phys.is_none());
        // PDI reads first byte (clears the interrupt) then the last (empties).
        s.access(Side::Pdi, false, 0, 1);
        assert!(!s.pdi_irq());
        let a = s.access(Side::Pdi, false, 7, 1);
        assert_eq!(a.effect, Some(SmEffect::Read(Side::Pdi)));
        assert!(!s.is_full());
        assert_eq!(s.status(), 0x02);
    }

    #[test]
    fn mailbox_read_needs_full_and_master_read_of_last_byte_empties() {
        let mut s = sm(0x22, 4);
        assert!(s.access(Side::Ecat, false, 0, 4).phys.is_none(), "empty mailbox is not readable");
        assert_eq!(s.access(Side::Pdi, true, 0, 4).effect, Some(SmEffect::Written(Side::Pdi)));
        assert!(s.is_full());
        // A read that does not reach the last byte leaves it full.
        assert_eq!(s.access(Side::Ecat, false, 0, 2).effect, None);
        assert!(s.is_full());
        assert_eq!(s.access(Side::Ecat, false, 2, 2).effect, Some(SmEffect::Read(Side::Ecat)));
        assert!(!s.is_full());
    }

    #[test]
    fn last_byte_without_first_does_not_complete() {
        let mut s = sm(0x26, 4);
        assert_eq!(s.access(Side::Ecat, true, 3, 1).effect, None);
        assert!(!s.is_full());
    }

    #[test]
    fn three_buffer_reader_gets_newest_complete_buffer() {
        let mut s = sm(0x64, 2); // buffered, master writes, watchdog
        assert_eq!(s.status() >> 4 & 3, 3, "no buffer written yet");
        let w1 = s.access(Side::Ecat, true, 0, 2);
        assert_eq!(w1.effect, Some(SmEffect::Written(Side::Ecat)));
        let w2 = s.access(Side::Ecat, true, 0, 2);
        assert_ne!(w1.phys, w2.phys, "second write goes to another buffer");
        // Incomplete third write does not switch.
        let w3 = s.access(Side::Ecat, true, 0, 1);
        assert_eq!(w3.effect, None);
        let r = s.access(Side::Pdi, false, 0, 2);
        assert_eq!(r.phys, w2.phys, "PDI opens the newest complete buffer");
        // No new data: the PDI re-reads the same buffer.
        assert_eq!(s.access(Side::Pdi, false, 0, 2).phys, w2.phys);
        // Shadow buffers are not addressable.
        assert!(s.access(Side::Ecat, true, 2, 2).phys.is_none());
    }

    proptest! {
        /// 3-buffer invariants under any interleaving of complete/partial
        /// writer and reader accesses: the writer never touches the buffer
        /// being read or the newest complete one, and a reader opening
        /// after a completed write sees that write.
        #[test]
        fn three_buffer_invariants(ops in proptest::collection::vec((any::<bool>(), 0usize..3, 1usize..4), 1..200)) {
            let len = 3usize;
            let mut s = sm(0x04, len as u16);
            let mut last_complete: Option<usize> = None;
            for (is_write, off, n) in ops {
                let off = off.min(len - 1);
                let n = n.min(len - off);
                if is_write {
                    let (wb, rb) = s.buffers();
                    prop_assert!(Some(wb) != s.newest());
                    prop_assert!(wb != rb);
                    let a = s.access(Side::Ecat, true, off, n);
                    let phys = a.phys.unwrap();
                    prop_assert_eq!(phys, 0x1000 + usize::from(wb) * len + off);
                    if a.effect.is_some() {
                        last_complete = Some(usize::from(wb));
                    }
                } else {
                    let a = s.access(Side::Pdi, false, off, n);
                    if off == 0 && let Some(b) = last_complete {
                        prop_assert_eq!(a.phys.unwrap(), 0x1000 + b * len);
                    }
                }
            }
        }
    }
}
