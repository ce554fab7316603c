//! The iPOS's FoE file policy (*iPOS CoE Programming* §17.2.7, §17.3,
//! §17.4.3–§17.4.7).
//!
//! * **Setup files** (§17.4.3.1): the name starts with `FOESW_`, is at
//!   most 14 characters without the extension, the extension is `.bin` or
//!   `.efw`, the password is 0; accepted in PRE-OP, SAFE-OP and OP,
//!   refused in BOOT unless 210Ch = 1 (§17.2.7, §17.4.5, F515I+).
//! * **Firmware files** (§17.4.6): the name starts with `FOEFW_`, only in
//!   BOOT with 210Ch = 0, with the password of the firmware line: the twin
//!   is an FA00G, so 0x41303041 ("A00A"); F515x's 0x35313546 is refused.
//!   The flash is erased before the first packet is taken and programmed
//!   after the last: the master is told BUSY meanwhile and repeats.
//! * Refusals: a name or extension the rules do not allow → 8001h "not
//!   found"; a wrong password → 8002h "access denied"; a setup file in
//!   BOOT without 210Ch = 1 → 8009h "not bootstrap"; firmware outside
//!   BOOT → 8008h "bootstrap only"; firmware in BOOT with 210Ch = 1 →
//!   8004h "illegal"; a file over [`MAX_FILE`] → 8003h "disk full".
//!
//! What is kept: the manual gives the format of a `.sw` image (§17.3:
//! blocks of 16-bit words after a start address) but not of the binary
//! FoE files EasySetUp writes, nor where in the EEPROM each setup value
//! lives. A setup file is therefore stored as received — in the state
//! directory when the slave has one, so it survives a restart — and, when
//! it is a `.sw` text image, its blocks and §17.4.2 checksum are kept
//! ([`SwImage`]); its values are not applied to objects. A firmware file
//! is taken and "programmed" (its length recorded); the emulated firmware
//! stays FA00G.

use crate::ecat::DriveFiles;
use alloc::string::String;
use alloc::vec::Vec;
use drivebus_can::{Duration, Instant};
use drivebus_coe::{AlState, FileHandler, FoeEnd, FoeError, FoeProgress};
use drivebus_od::ObjectDictionary;

extern crate alloc;

/// Firmware password of the FA0xx line (§17.4.6).
pub const FA0XX_PASSWORD: u32 = 0x4130_3041;
/// Firmware password of the F515x line (§17.4.6), refused by the FA00G twin.
pub const F515X_PASSWORD: u32 = 0x3531_3546;
/// Largest file taken (a setup image is a few kB; firmware up to this).
pub const MAX_FILE: usize = 1 << 20;

/// A `.sw` EEPROM image (§17.3): blocks of 16-bit words, each after its
/// start address.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SwImage {
    /// `(start address, words)` in file order.
    pub blocks: Vec<(u16, Vec<u16>)>,
}

impl SwImage {
    /// Parses the text format of §17.3: blocks separated by empty lines,
    /// the first line of each the start address, then one hexadecimal
    /// word (at most 4 digits) per line. `None` if the file is not one.
    pub fn parse(data: &[u8]) -> Option<SwImage> {
        let text = core::str::from_utf8(data).ok()?;
        let mut blocks: Vec<(u16, Vec<u16>)> = Vec::new();
        let mut open = false;
        for line in text.lines().map(str::trim) {
            if line.is_empty() {
                open = false;
                continue;
            }
            if line.len() > 4 {
                return None;
            }
            let v = u16::from_str_radix(line, 16).ok()?;
            match blocks.last_mut() {
                Some((_, words)) if open => words.push(v),
                _ => {
                    blocks.push((v, Vec::new()));
                    open = true;
                }
            }
        }
        (!blocks.is_empty()).then_some(SwImage { blocks })
    }

    /// The 16-bit additive checksum of every word (§17.4.2, what 206Ah
    /// reports over the same range).
    pub fn checksum(&self) -> u16 {
        self.blocks.iter().flat_map(|(_, w)| w).fold(0u16, |a, w| a.wrapping_add(*w))
    }

    /// Words in all blocks.
    pub fn words(&self) -> usize {
        self.blocks.iter().map(|(_, w)| w.len()).sum()
    }
}

/// What kind of file is being received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A setup data file (`FOESW_`).
    Setup,
    /// A firmware file (`FOEFW_`).
    Firmware,
}

/// A file the drive took.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReceivedFile {
    /// Setup or firmware.
    pub kind: FileKind,
    /// The name the master gave.
    pub name: String,
    /// The bytes.
    pub data: Vec<u8>,
    /// A setup file that is a `.sw` image, parsed.
    pub image: Option<SwImage>,
}

/// The iPOS file handler (see the module docs).
#[derive(Debug, Clone)]
pub struct IposFiles {
    /// 210Ch "enable SW file download" (1: setup files in BOOT).
    sw_in_boot: bool,
    /// Flash erase time before the first firmware packet is taken.
    erase: Duration,
    /// Programming time after the last firmware packet.
    program: Duration,
    current: Option<(FileKind, String)>,
    programming: bool,
    busy_since: Instant,
    busy_until: Instant,
    received: Vec<u8>,
    /// Files taken, oldest first.
    pub taken: Vec<ReceivedFile>,
    /// How transfers ended, oldest first.
    pub ends: Vec<FoeEnd>,
    dir: Option<std::path::PathBuf>,
}

impl Default for IposFiles {
    fn default() -> Self {
        IposFiles::new()
    }
}

impl IposFiles {
    /// The handler of a new drive: 210Ch = 0, a 30 ms erase and a 20 ms
    /// programming time.
    pub fn new() -> Self {
        IposFiles {
            sw_in_boot: false,
            erase: Duration::from_millis(30),
            program: Duration::from_millis(20),
            current: None,
            programming: false,
            busy_since: Instant::ZERO,
            busy_until: Instant::ZERO,
            received: Vec::new(),
            taken: Vec::new(),
            ends: Vec::new(),
            dir: None,
        }
    }

    /// Setup files are also written to `dir/<name>` (the slave's state
    /// directory), so they survive a restart.
    pub fn with_dir(mut self, dir: std::path::PathBuf) -> Self {
        self.dir = Some(dir);
        self
    }

    /// 210Ch as the drive holds it.
    pub fn set_sw_in_boot(&mut self, on: bool) {
        self.sw_in_boot = on;
    }

    fn busy(&self, now: Instant) -> FoeProgress {
        let total = (self.busy_until - self.busy_since).as_micros().max(1);
        let left = (self.busy_until - now).as_micros().min(total);
        FoeProgress::Busy { done: (100 - 100 * left / total) as u16, entire: 100 }
    }

    fn start_busy(&mut self, now: Instant, d: Duration) {
        self.busy_since = now;
        self.busy_until = now + d;
    }

    fn store(&self, f: &ReceivedFile) {
        if let Some(d) = &self.dir
            && f.kind == FileKind::Setup
        {
            // A name the rules allowed has no path separator.
            let _ = std::fs::create_dir_all(d).and_then(|()| std::fs::write(d.join(&f.name), &f.data));
        }
    }
}

impl FileHandler for IposFiles {
    fn begin_write(
        &mut self,
        name: &[u8],
        password: u32,
        state: AlState,
        now: Instant,
    ) -> Result<(), FoeError> {
        let name = core::str::from_utf8(name).map_err(|_| FoeError::NOT_FOUND)?;
        let (stem, ext) = name.rsplit_once('.').unwrap_or((name, ""));
        let kind = if stem.starts_with("FOESW_") {
            let ext_ok = ext.eq_ignore_ascii_case("bin") || ext.eq_ignore_ascii_case("efw");
            if stem.len() > 14 || !ext_ok || stem.contains(['/', '\\']) {
                return Err(FoeError::NOT_FOUND);
            }
            if password != 0 {
                return Err(FoeError::ACCESS_DENIED);
            }
            if state == AlState::Boot && !self.sw_in_boot {
                return Err(FoeError::NOT_BOOTSTRAP);
            }
            FileKind::Setup
        } else if name.starts_with("FOEFW_") {
            if state != AlState::Boot {
                return Err(FoeError::BOOTSTRAP_ONLY);
            }
            if password != FA0XX_PASSWORD {
                return Err(FoeError::ACCESS_DENIED);
            }
            if self.sw_in_boot {
                return Err(FoeError::ILLEGAL);
            }
            // §17.4.6 warning: the flash is erased first.
            self.start_busy(now, self.erase);
            FileKind::Firmware
        } else {
            return Err(FoeError::NOT_FOUND);
        };
        self.current = Some((kind, String::from(name)));
        self.programming = false;
        self.received.clear();
        Ok(())
    }

    fn write(&mut self, offset: u32, data: &[u8], now: Instant) -> Result<FoeProgress, FoeError> {
        if now < self.busy_until {
            return Ok(self.busy(now));
        }
        if offset as usize != self.received.len() {
            return Err(FoeError::PROGRAM_ERROR);
        }
        if self.received.len() + data.len() > MAX_FILE {
            return Err(FoeError::DISK_FULL);
        }
        self.received.extend_from_slice(data);
        Ok(FoeProgress::Ready)
    }

    fn finish_write(&mut self, now: Instant) -> Result<FoeProgress, FoeError> {
        let Some((kind, name)) = self.current.clone() else { return Err(FoeError::PROGRAM_ERROR) };
        if kind == FileKind::Firmware && !self.programming {
            self.programming = true;
            self.start_busy(now, self.program);
        }
        if now < self.busy_until {
            return Ok(self.busy(now));
        }
        let data = core::mem::take(&mut self.received);
        let image = (kind == FileKind::Setup).then(|| SwImage::parse(&data)).flatten();
        let f = ReceivedFile { kind, name, data, image };
        self.store(&f);
        self.taken.push(f);
        self.current = None;
        self.programming = false;
        Ok(FoeProgress::Ready)
    }

    fn end(&mut self, how: FoeEnd) {
        self.current = None;
        self.programming = false;
        self.ends.push(how);
    }
}

impl DriveFiles for IposFiles {
    fn refresh(&mut self, od: &ObjectDictionary) {
        self.sw_in_boot = od.get_i64(0x210C, 0) == Some(1);
    }

    fn as_any_mut(&mut self) -> &mut dyn core::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sw_image_and_checksum() {
        let f = b"5638\nC400\n0\n92\n\n5700\nFFFF\n1\n";
        let i = SwImage::parse(f).unwrap();
        assert_eq!(i.blocks, [(0x5638, vec![0xC400, 0, 0x92]), (0x5700, vec![0xFFFF, 1])]);
        assert_eq!(i.words(), 5);
        assert_eq!(i.checksum(), 0xC400u16.wrapping_add(0x92).wrapping_add(0xFFFF).wrapping_add(1));
        assert_eq!(SwImage::parse(&[0x00, 0xFF, 0x13]), None, "binary");
        assert_eq!(SwImage::parse(b"12345\n"), None, "more than 4 digits");
    }

    #[test]
    fn names_passwords_and_states() {
        let mut f = IposFiles::new();
        let t = Instant::ZERO;
        let e = |f: &mut IposFiles, n: &str, pw: u32, s: AlState| f.begin_write(n.as_bytes(), pw, s, t).err();
        assert_eq!(e(&mut f, "FOESW_12345678.efw", 0, AlState::Op), None, "14 characters");
        assert_eq!(e(&mut f, "FOESW_123456789.bin", 0, AlState::Op), Some(FoeError::NOT_FOUND));
        assert_eq!(e(&mut f, "FOESW_A.sw", 0, AlState::Op), Some(FoeError::NOT_FOUND));
        assert_eq!(e(&mut f, "FOESW_A.bin", 7, AlState::Op), Some(FoeError::ACCESS_DENIED));
        assert_eq!(e(&mut f, "FOESW_A.bin", 0, AlState::Boot), Some(FoeError::NOT_BOOTSTRAP));
        assert_eq!(e(&mut f, "FOEFW_FA00H", FA0XX_PASSWORD, AlState::PreOp), Some(FoeError::BOOTSTRAP_ONLY));
        assert_eq!(e(&mut f, "FOEFW_FA00H", F515X_PASSWORD, AlState::Boot), Some(FoeError::ACCESS_DENIED));
        f.set_sw_in_boot(true);
        assert_eq!(e(&mut f, "FOESW_A.bin", 0, AlState::Boot), None);
        assert_eq!(e(&mut f, "FOEFW_FA00H", FA0XX_PASSWORD, AlState::Boot), Some(FoeError::ILLEGAL));
    }
}
