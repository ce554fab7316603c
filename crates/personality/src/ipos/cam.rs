//! The iPOS drive memory (§17.2: 2064h–206Ah) and electronic camming (§12,
//! mode −2) on the cam tables it holds (§18.4.1).
//!
//! Memory: 16-bit words in three spaces (2064h bits 3–2: program, data,
//! EEPROM) at 16-bit addresses; a 32-bit access is the low word at the
//! address and the high word after it (the word order of §18.4.1's long
//! values). 2065h writes and 2066h reads at the 2064h address and then
//! advance it by the words moved unless 2064h bit 7 is set; 2067h writes
//! one word at the address it carries; 2069h sums the EEPROM words from
//! its start address up to (not including) its end address ("the start
//! address to which you add the length", §17.2.5) into 206Ah.
//!
//! Cam tables (§18.4.1): word 0 bits 15–13 = log2 of the X step, bits
//! 12–0 = points − 1; words 1–2 the master start value X0 (low, high);
//! words 3–4 reserved; then each point's Y (low, high); last the checksum,
//! the 16-bit sum of every word before it. A 2019h write copies the table
//! at that EEPROM address to the data memory at 201Ah (§12.2.1); entering
//! the camming mode (controlword bit 4 0 → 1) takes the table found at
//! 201Ah in the data memory (§12.1). A table whose checksum or size is
//! wrong is not taken: the slave keeps its position (the manual does not
//! say what the drive does; holding is the safe reading).

use super::*;
use alloc::collections::BTreeMap;
use alloc::vec::Vec;

extern crate alloc;

/// The memory space a 2064h value selects (bits 3–2); `None` = reserved.
fn space(config: u32) -> Option<u32> {
    match (config >> 2) & 3 {
        3 => None,
        s => Some(s),
    }
}

/// Data memory (2064h bits 3–2 = 01): the RAM cam tables run from.
const DATA: u32 = 1;
/// EEPROM (2064h bits 3–2 = 10).
const EEPROM: u32 = 2;

/// The drive's memory, sparse: words never written read 0.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Memory {
    words: BTreeMap<u32, u16>,
}

impl Memory {
    fn key(space: u32, addr: u16) -> u32 {
        space << 16 | u32::from(addr)
    }

    /// The word at `addr` of `space`.
    pub fn word(&self, space: u32, addr: u16) -> u16 {
        self.words.get(&Self::key(space, addr)).copied().unwrap_or(0)
    }

    /// Writes one word.
    pub fn set(&mut self, space: u32, addr: u16, w: u16) {
        if w == 0 {
            self.words.remove(&Self::key(space, addr));
        } else {
            self.words.insert(Self::key(space, addr), w);
        }
    }

    /// `n` words from `addr` (wrapping at the end of the space).
    fn read(&self, space: u32, addr: u16, n: usize) -> Vec<u16> {
        (0..n).map(|i| self.word(space, addr.wrapping_add(i as u16))).collect()
    }
}

/// A cam table (§18.4.1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CamTable {
    /// Master start value X0 \[master increments\].
    pub x0: i32,
    /// log2 of the X step (0..=7).
    pub step_log2: u8,
    /// Y of each point \[slave increments\].
    pub y: Vec<i32>,
}

impl CamTable {
    /// Words of the table whose first word is `header`.
    pub fn words_len(header: u16) -> usize {
        2 * (usize::from(header & 0x1FFF) + 1) + 6
    }

    /// The table in `words` (its header first); `None` when the step is
    /// above 2⁷ or the checksum does not match.
    pub fn parse(words: &[u16]) -> Option<CamTable> {
        let header = *words.first()?;
        let len = Self::words_len(header);
        let words = words.get(..len)?;
        let step_log2 = (header >> 13) as u8;
        let (body, sum) = words.split_at(len - 1);
        let checksum = body.iter().fold(0u16, |a, w| a.wrapping_add(*w));
        if step_log2 > 7 || checksum != sum[0] {
            return None;
        }
        let long = |i: usize| (u32::from(words[i]) | u32::from(words[i + 1]) << 16) as i32;
        let y = (0..=usize::from(header & 0x1FFF)).map(|k| long(5 + 2 * k)).collect();
        Some(CamTable { x0: long(1), step_log2, y })
    }

    /// The words of this table, checksum included (tests, tools).
    pub fn to_words(&self) -> Vec<u16> {
        let n = self.y.len().clamp(1, 8192);
        let mut w = vec![u16::from(self.step_log2.min(7)) << 13 | (n - 1) as u16];
        let long = |v: i32, w: &mut Vec<u16>| w.extend([v as u32 as u16, (v as u32 >> 16) as u16]);
        long(self.x0, &mut w);
        w.extend([0, 0]);
        for y in self.y.iter().take(n) {
            long(*y, &mut w);
        }
        let sum = w.iter().fold(0u16, |a, x| a.wrapping_add(*x));
        w.push(sum);
        w
    }

    /// The output at master input `x`: linear between the points, the end
    /// points' Y outside the table.
    pub fn output(&self, x: f64) -> f64 {
        let last = self.y.len() - 1;
        let pos = (x - f64::from(self.x0)) / f64::from(1u32 << self.step_log2);
        if pos <= 0.0 {
            return f64::from(self.y[0]);
        }
        if pos >= last as f64 {
            return f64::from(self.y[last]);
        }
        let k = pos.floor() as usize;
        let f = pos - k as f64;
        f64::from(self.y[k]) + f * (f64::from(self.y[k + 1]) - f64::from(self.y[k]))
    }

    /// Y at the first and the last point (the rollover compensation of
    /// the relative mode, §12.1).
    fn ends(&self) -> (f64, f64) {
        (f64::from(self.y[0]), f64::from(self.y[self.y.len() - 1]))
    }
}

/// Electronic camming state (§12.1).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Camming {
    /// The table taken when camming started.
    table: Option<CamTable>,
    /// The cam input X of the last update (relative mode's rollover).
    x_old: f64,
    /// The cam output of the last update \[slave increments\].
    y_old: f64,
    /// Absolute mode (controlword bit 6 = 1 at the start).
    absolute: bool,
    /// Speed limitation (controlword bit 5, absolute mode only).
    limited: bool,
}

/// FIXED32 (16.16) → float.
fn fixed(v: u32) -> f64 {
    f64::from(v as i32) / 65536.0
}

impl Ipos {
    /// 2064h as it stands.
    fn mem_config(od: &ObjectDictionary) -> u32 {
        od.get_u32(0x2064, 0).unwrap_or(0x84)
    }

    /// Advances the 2064h address by `n` words unless bit 7 says not to.
    fn mem_advance(od: &mut ObjectDictionary, config: u32, n: u16) {
        if config & 0x80 != 0 {
            return;
        }
        let addr = ((config >> 16) as u16).wrapping_add(n);
        if let Ok(r) = od.find(0x2064, 0) {
            od.set_le(r, &(u32::from(addr) << 16 | config & 0xFFFF).to_le_bytes());
        }
    }

    /// 2065h / 2067h / 2069h / 2019h writes (§17.2, §12.2.1).
    pub(super) fn memory_write(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        value: u32,
    ) -> Result<(), SdoAbort> {
        let config = Self::mem_config(od);
        match index {
            0x2065 => {
                let s = space(config).ok_or(SdoAbort::INVALID_VALUE)?;
                let addr = (config >> 16) as u16;
                self.memory.set(s, addr, value as u16);
                if config & 1 != 0 {
                    self.memory.set(s, addr.wrapping_add(1), (value >> 16) as u16);
                }
                Self::mem_advance(od, config, if config & 1 != 0 { 2 } else { 1 });
            }
            0x2067 => {
                let s = space(config).ok_or(SdoAbort::INVALID_VALUE)?;
                self.memory.set(s, (value >> 16) as u16, value as u16);
            }
            0x2069 => {
                let (start, end) = (value as u16, (value >> 16) as u16);
                let n = usize::from(end.wrapping_sub(start));
                let sum = self.memory.read(EEPROM, start, n).iter().fold(0u16, |a, w| a.wrapping_add(*w));
                if let Ok(r) = od.find(0x206A, 0) {
                    od.set_le(r, &sum.to_le_bytes());
                }
            }
            0x2019 => {
                // §12.2.1: each write copies the table at the load address
                // from the EEPROM to the RAM at the run address (201Ah).
                let load = value as u16;
                let run = od.get_u32(0x201A, 0).unwrap_or(0x9E00) as u16;
                let n = CamTable::words_len(self.memory.word(EEPROM, load));
                for (i, w) in self.memory.read(EEPROM, load, n).into_iter().enumerate() {
                    self.memory.set(DATA, run.wrapping_add(i as u16), w);
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// 2066h read (§17.2.3): the data at the 2064h address, then the
    /// address advances.
    pub(super) fn memory_read(&mut self, od: &mut ObjectDictionary) -> Result<(), SdoAbort> {
        let config = Self::mem_config(od);
        let s = space(config).ok_or(SdoAbort::INVALID_VALUE)?;
        let addr = (config >> 16) as u16;
        let lo = u32::from(self.memory.word(s, addr));
        let wide = config & 1 != 0;
        let v = if wide { lo | u32::from(self.memory.word(s, addr.wrapping_add(1))) << 16 } else { lo };
        if let Ok(r) = od.find(0x2066, 0) {
            od.set_le(r, &v.to_le_bytes());
        }
        Self::mem_advance(od, config, if wide { 2 } else { 1 });
        Ok(())
    }

    /// The cam input of master position `m` (§12.2.3): (m − 201Bh) modulo
    /// the master resolution 2012h, scaled by 206Bh.
    fn cam_input(od: &ObjectDictionary, m: i64) -> f64 {
        let offset = i64::from(od.get_u32(0x201B, 0).unwrap_or(0));
        let res = od.get_u32(0x2012, 0).unwrap_or(MASTER_FULL_RANGE);
        let x = if res == MASTER_FULL_RANGE || res == 0 || res > i32::MAX as u32 {
            i64::from((m as i32).wrapping_sub(offset as i32))
        } else {
            (m - offset).rem_euclid(i64::from(res))
        };
        x as f64 * fixed(od.get_u32(0x206B, 0).unwrap_or(0x1_0000))
    }

    /// The cam output for input `x`, scaled by 206Ch \[slave increments\].
    fn cam_output(od: &ObjectDictionary, t: &CamTable, x: f64) -> f64 {
        t.output(x) * fixed(od.get_u32(0x206C, 0).unwrap_or(0x1_0000))
    }

    /// Camming starts (controlword bit 4 0 → 1, §12.1.1): the table at
    /// 201Ah; relative: Y_old = f(X); absolute: the slave goes to f(X).
    pub(super) fn cam_engage(&mut self, od: &ObjectDictionary, cw: u16) {
        let run = od.get_u32(0x201A, 0).unwrap_or(0x9E00) as u16;
        let n = CamTable::words_len(self.memory.word(DATA, run));
        let table = CamTable::parse(&self.memory.read(DATA, run, n));
        let x = Self::cam_input(od, self.gear.master);
        self.cam = Camming {
            y_old: table.as_ref().map_or(0.0, |t| Self::cam_output(od, t, x)),
            x_old: x,
            absolute: cw & 0x40 != 0,
            limited: cw & 0x20 != 0,
            table,
        };
    }

    /// A master position update in camming (§12.1): relative mode adds dY
    /// (compensated by Ymax − Ymin when the master rolls over); absolute
    /// mode makes Y the demand, at most 6081h fast with bit 5. Returns the
    /// new slave reference, `None` without a table.
    pub(super) fn cam_update(&mut self, od: &ObjectDictionary, increment: i64, dt: f64) -> Option<f64> {
        let t = self.cam.table.as_ref()?;
        let x = Self::cam_input(od, self.gear.master);
        let y = Self::cam_output(od, t, x);
        let reference = if self.cam.absolute {
            let mut r = y;
            if self.cam.limited {
                // 6081h: internal velocity units, 1/65536 increment per 1 ms.
                let v = f64::from(od.get_u32(0x6081, 0).unwrap_or(0)) / 65536.0 * 1000.0;
                let step = v * dt;
                r = self.gear.reference + (y - self.gear.reference).clamp(-step, step);
            }
            r
        } else {
            let mut dy = y - self.cam.y_old;
            let dx = x - self.cam.x_old;
            // A forward master move whose X went down rolled over (and
            // the other way round).
            let (y_min, y_max) = t.ends();
            let span = (y_max - y_min) * fixed(od.get_u32(0x206C, 0).unwrap_or(0x1_0000));
            if increment > 0 && dx < 0.0 {
                dy += span;
            } else if increment < 0 && dx > 0.0 {
                dy -= span;
            }
            self.gear.reference + dy
        };
        self.cam.x_old = x;
        self.cam.y_old = y;
        Some(reference)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_round_trip_and_interpolation() {
        let t = CamTable { x0: 0, step_log2: 6, y: (0..=10).map(|i| i * i * 40).collect() };
        let w = t.to_words();
        assert_eq!(w[0], 0xC00A);
        assert_eq!(w.len(), CamTable::words_len(w[0]));
        assert_eq!(CamTable::parse(&w), Some(t.clone()));
        assert_eq!(t.output(640.0), 4000.0);
        assert_eq!(t.output(320.0), 1000.0);
        assert_eq!(t.output(352.0), 1220.0);
        assert_eq!(t.output(-5.0), 0.0);
        assert_eq!(t.output(1e9), 4000.0);
        let mut bad = w.clone();
        bad[6] ^= 1;
        assert_eq!(CamTable::parse(&bad), None, "checksum");
        assert_eq!(CamTable::parse(&w[..5]), None, "short");
    }
}
