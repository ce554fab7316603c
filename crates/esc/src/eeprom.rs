//! The SII EEPROM interface, registers 0x0500–0x050F (ESC data sheet
//! Section I "SII EEPROM", Section II 0x0500).
//!
//! * 0x0500/0x0501: the interface belongs to the PDI only when the master
//!   offers it (0x0500 bit 0) *and* the PDI takes it (0x0501 bit 0); bit 1
//!   of 0x0500 ("force ECAT") clears the PDI's claim. While the PDI owns
//!   it, master writes to 0x0502–0x050F are ignored.
//! * 0x0502 control/status: bit 0 write enable (self-clearing at the start
//!   of every frame), bit 6 read size (1: 8-byte reads, read-only), bit 7
//!   address algorithm (read-only), bits 10:8 command (1 read, 2 write,
//!   4 reload; reads back while busy), bit 11 checksum error, bit 12 device
//!   information not loaded, bit 13 command error, bit 14 write-enable
//!   error, bit 15 busy. Writing command 0 clears bits 13 and 14; any other
//!   code than 0, 1, 2, 4 sets bit 13. While busy, writes to 0x0502–0x050F
//!   are ignored.
//! * 0x0504: word address, taken when the command executes, so an address
//!   written in the same datagram as the command is used (ethercrab writes
//!   control + address as one 6-byte datagram).
//! * 0x0508: 4 or 8 data bytes after a read; the word to store for a write.
//!
//! Commands take the configured time (zero: they complete inside the
//! datagram that issued them). A read past the end of the image wraps
//! around, as a real I²C EEPROM's address counter does. Writes go to the
//! image and mark it dirty so the caller can persist it.

use crate::sii::SiiImage;
use drivebus_base::{Duration, Instant};

/// Durations of EEPROM commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiTiming {
    /// Time a read command keeps the interface busy.
    pub read: Duration,
    /// Time a write command keeps the interface busy.
    pub write: Duration,
    /// Time a reload keeps the interface busy.
    pub reload: Duration,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    Read,
    Write,
    Reload,
}

/// A command that finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SiiDone {
    Read,
    Written,
    Reloaded,
}

const CTRL: usize = 0x0502;
const ADDR: usize = 0x0504;
const DATA: usize = 0x0508;
const ERR_CHECKSUM: u16 = 1 << 11;
const ERR_DEVICE_INFO: u16 = 1 << 12;
const ERR_COMMAND: u16 = 1 << 13;
const ERR_WRITE_ENABLE: u16 = 1 << 14;
const BUSY: u16 = 1 << 15;

/// State of the EEPROM interface.
#[derive(Debug, Clone)]
pub(crate) struct SiiUnit {
    pub image: SiiImage,
    pub dirty: bool,
    busy: Option<(Instant, Op)>,
    read_8: bool,
    timing: SiiTiming,
    errors: u16,
    write_enable: bool,
}

impl SiiUnit {
    pub fn new(image: SiiImage, read_8: bool, timing: SiiTiming) -> Self {
        SiiUnit { image, dirty: false, busy: None, read_8, timing, errors: 0, write_enable: false }
    }

    /// True while a command runs.
    pub fn busy(&self) -> bool {
        self.busy.is_some()
    }

    /// When the running command finishes.
    pub fn deadline(&self) -> Option<Instant> {
        self.busy.map(|(t, _)| t)
    }

    /// True if the PDI owns the interface (0x0500.0 and 0x0501.0).
    pub fn pdi_owns(regs: &[u8]) -> bool {
        regs[0x0500] & 1 != 0 && regs[0x0501] & 1 != 0
    }

    /// Rebuilds the control/status register.
    pub fn sync(&self, regs: &mut [u8]) {
        let mut v = u16::from(self.write_enable) | (u16::from(self.read_8) << 6) | self.errors;
        // Images above 16 Kbit need two address bytes.
        if self.image.bytes().len() > 2048 {
            v |= 1 << 7;
        }
        if let Some((_, op)) = self.busy {
            v |= BUSY
                | match op {
                    Op::Read => 0x0100,
                    Op::Write => 0x0200,
                    Op::Reload => 0x0400,
                };
        }
        regs[CTRL..CTRL + 2].copy_from_slice(&v.to_le_bytes());
    }

    /// Start of a frame: the write-enable bit clears itself.
    pub fn start_of_frame(&mut self, regs: &mut [u8]) {
        if self.write_enable {
            self.write_enable = false;
            self.sync(regs);
        }
    }

    /// Result of a configuration-area reload check (0x0502 bits 11/12).
    pub fn set_load_status(&mut self, ok: bool, regs: &mut [u8]) {
        self.errors &= !(ERR_CHECKSUM | ERR_DEVICE_INFO);
        if !ok {
            self.errors |= ERR_CHECKSUM | ERR_DEVICE_INFO;
        }
        self.sync(regs);
    }

    /// A write to the control register: `low`/`high` are the bytes written
    /// (`None` if that byte was not part of the access).
    pub fn control_write(
        &mut self,
        regs: &mut [u8],
        low: Option<u8>,
        high: Option<u8>,
        now: Instant,
    ) -> Option<SiiDone> {
        if self.busy() {
            return None;
        }
        if let Some(l) = low {
            self.write_enable = l & 1 != 0;
        }
        let mut done = None;
        if let Some(h) = high {
            let op = match h & 0x07 {
                0 => {
                    self.errors &= !(ERR_COMMAND | ERR_WRITE_ENABLE);
                    None
                }
                1 => Some(Op::Read),
                2 if self.write_enable => Some(Op::Write),
                2 => {
                    self.errors |= ERR_WRITE_ENABLE;
                    None
                }
                4 => Some(Op::Reload),
                _ => {
                    self.errors |= ERR_COMMAND;
                    None
                }
            };
            if let Some(op) = op {
                self.errors &= !(ERR_COMMAND | ERR_WRITE_ENABLE);
                let d = match op {
                    Op::Read => self.timing.read,
                    Op::Write => self.timing.write,
                    Op::Reload => self.timing.reload,
                };
                self.busy = Some((now + d, op));
                if d.is_zero() {
                    done = self.advance(regs, now);
                }
            }
        }
        self.sync(regs);
        done
    }

    /// Finishes a command that is due.
    pub fn advance(&mut self, regs: &mut [u8], now: Instant) -> Option<SiiDone> {
        let (at, op) = self.busy?;
        if now < at {
            return None;
        }
        self.busy = None;
        let addr = u32::from_le_bytes([regs[ADDR], regs[ADDR + 1], regs[ADDR + 2], regs[ADDR + 3]]) as usize;
        let words = self.image.words().max(1);
        let done = match op {
            Op::Read => {
                let n = if self.read_8 { 4 } else { 2 };
                for i in 0..n {
                    let w = self.image.word((addr + i) % words);
                    regs[DATA + 2 * i..DATA + 2 * i + 2].copy_from_slice(&w.to_le_bytes());
                }
                SiiDone::Read
            }
            Op::Write => {
                let a = addr % words;
                let (lo, hi) = (regs[DATA], regs[DATA + 1]);
                let b = self.image.bytes_mut();
                b[a * 2] = lo;
                b[a * 2 + 1] = hi;
                self.dirty = true;
                SiiDone::Written
            }
            Op::Reload => SiiDone::Reloaded,
        };
        self.sync(regs);
        Some(done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sii::SiiImage;

    fn unit(t: SiiTiming) -> (SiiUnit, [u8; 0x1000]) {
        let img = SiiImage::from_bytes((0..256u16).map(|i| i as u8).collect());
        let mut regs = [0u8; 0x1000];
        let u = SiiUnit::new(img, true, t);
        u.sync(&mut regs);
        (u, regs)
    }

    #[test]
    fn read_fills_eight_bytes_from_the_word_address() {
        let (mut u, mut regs) = unit(SiiTiming::default());
        assert_eq!(regs[CTRL], 0x40, "8-byte read size is advertised");
        regs[ADDR] = 0x10;
        assert_eq!(u.control_write(&mut regs, Some(0), Some(1), Instant::ZERO), Some(SiiDone::Read));
        assert_eq!(&regs[DATA..DATA + 8], &[0x20, 0x21, 0x22, 0x23, 0x24, 0x25, 0x26, 0x27]);
        assert_eq!(regs[CTRL + 1] & 0x87, 0, "idle, command cleared");
    }

    #[test]
    fn busy_until_the_read_time_and_writes_ignored_meanwhile() {
        let (mut u, mut regs) = unit(SiiTiming { read: Duration::from_micros(50), ..Default::default() });
        regs[ADDR] = 1;
        assert_eq!(u.control_write(&mut regs, None, Some(1), Instant::ZERO), None);
        assert_eq!(regs[CTRL + 1], 0x81, "busy + read command");
        assert_eq!(u.deadline(), Some(Instant::from_micros(50)));
        assert_eq!(u.control_write(&mut regs, None, Some(4), Instant::from_micros(1)), None);
        assert_eq!(u.advance(&mut regs, Instant::from_micros(49)), None);
        assert_eq!(u.advance(&mut regs, Instant::from_micros(50)), Some(SiiDone::Read));
        assert_eq!(regs[DATA], 2);
        assert!(!u.busy());
    }

    #[test]
    fn write_needs_write_enable_and_stores_the_word() {
        let (mut u, mut regs) = unit(SiiTiming::default());
        regs[ADDR] = 4;
        regs[DATA] = 0xCD;
        regs[DATA + 1] = 0xAB;
        assert_eq!(u.control_write(&mut regs, Some(0), Some(2), Instant::ZERO), None);
        assert_eq!(regs[CTRL + 1] & 0x40, 0x40, "write-enable error");
        // Command 0 clears it.
        u.control_write(&mut regs, Some(0), Some(0), Instant::ZERO);
        assert_eq!(regs[CTRL + 1] & 0x60, 0);
        assert_eq!(u.control_write(&mut regs, Some(1), Some(2), Instant::ZERO), Some(SiiDone::Written));
        assert_eq!(u.image.word(4), 0xABCD);
        assert!(u.dirty);
        // Write enable clears at the next frame.
        u.start_of_frame(&mut regs);
        assert_eq!(regs[CTRL] & 1, 0);
    }

    #[test]
    fn invalid_command_sets_command_error_and_reads_wrap() {
        let (mut u, mut regs) = unit(SiiTiming::default());
        u.control_write(&mut regs, None, Some(3), Instant::ZERO);
        assert_eq!(regs[CTRL + 1] & 0x20, 0x20);
        regs[ADDR..ADDR + 2].copy_from_slice(&(128u16 + 127).to_le_bytes());
        u.control_write(&mut regs, None, Some(1), Instant::ZERO);
        assert_eq!(regs[CTRL + 1] & 0x20, 0, "a valid command clears it");
        assert_eq!(&regs[DATA..DATA + 4], &[254, 255, 0, 1], "address wraps past the end");
    }
}
