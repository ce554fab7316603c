//! TIME (CiA 301 §7.2.6): the TIME_OF_DAY stamp, object 1012h.

use crate::{COB_ID_CONSUME, COB_ID_PRODUCE, OD_COB_ID_TIME, can_id_of, check_cob_id, le_of};
use drivebus_can::{CanId, Frame, TxSink};
use drivebus_od::{Access, DataType, Object, ObjectCode, ObjectDictionary, SdoAbort, SubObject, Value};

/// Days from 1970-01-01 (Unix epoch) to 1984-01-01 (CANopen epoch):
/// 14 years, three of them leap years (1972, 1976, 1980).
pub const UNIX_DAYS_AT_1984: u64 = 14 * 365 + 3;
const MS_PER_DAY: u32 = 86_400_000;

/// A CANopen TIME_OF_DAY (CiA 301 §7.1.6.5): milliseconds after midnight
/// (28 bits) and days since 1984-01-01.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TimeOfDay {
    /// Days since 1984-01-01.
    pub days: u16,
    /// Milliseconds after midnight (`< 86_400_000` for a real time of day).
    pub ms: u32,
}

/// A calendar date and time of day (proleptic Gregorian, UTC).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CivilTime {
    /// Year (1984..=2163 for a TIME_OF_DAY).
    pub year: u16,
    /// Month, 1..=12.
    pub month: u8,
    /// Day of the month, 1..=31.
    pub day: u8,
    /// Hour, 0..=23.
    pub hour: u8,
    /// Minute, 0..=59.
    pub minute: u8,
    /// Second, 0..=59.
    pub second: u8,
    /// Millisecond, 0..=999.
    pub millis: u16,
}

fn is_leap(y: u32) -> bool {
    y.is_multiple_of(4) && (!y.is_multiple_of(100) || y.is_multiple_of(400))
}

fn days_in_year(y: u32) -> u32 {
    if is_leap(y) { 366 } else { 365 }
}

fn days_in_month(y: u32, m: u8) -> u8 {
    match m {
        2 if is_leap(y) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

impl TimeOfDay {
    /// The 6-byte wire form: 28-bit milliseconds little-endian with the 4
    /// reserved bits 0, then the days little-endian.
    pub fn to_bytes(self) -> [u8; 6] {
        let m = (self.ms & 0x0FFF_FFFF).to_le_bytes();
        let d = self.days.to_le_bytes();
        [m[0], m[1], m[2], m[3], d[0], d[1]]
    }

    /// Parse the 6-byte wire form (other lengths: `None`); the reserved bits are ignored.
    pub fn from_bytes(b: &[u8]) -> Option<TimeOfDay> {
        let b: &[u8; 6] = b.try_into().ok()?;
        Some(TimeOfDay {
            ms: u32::from_le_bytes([b[0], b[1], b[2], b[3]]) & 0x0FFF_FFFF,
            days: u16::from_le_bytes([b[4], b[5]]),
        })
    }

    /// From milliseconds since the Unix epoch; `None` before 1984-01-01 or
    /// after the last day 16 bits can count (2163-06-06).
    pub fn from_unix_ms(unix_ms: u64) -> Option<TimeOfDay> {
        let days = (unix_ms / MS_PER_DAY as u64).checked_sub(UNIX_DAYS_AT_1984)?;
        Some(TimeOfDay { days: u16::try_from(days).ok()?, ms: (unix_ms % MS_PER_DAY as u64) as u32 })
    }

    /// Milliseconds since the Unix epoch.
    pub fn to_unix_ms(self) -> u64 {
        (self.days as u64 + UNIX_DAYS_AT_1984) * MS_PER_DAY as u64 + self.ms as u64
    }

    /// From a calendar date and time, `None` if a field is out of range or
    /// the date is outside 1984-01-01..=2163-06-06.
    pub fn from_civil(t: &CivilTime) -> Option<TimeOfDay> {
        let y = t.year as u32;
        if y < 1984
            || !(1..=12).contains(&t.month)
            || t.day == 0
            || t.day > days_in_month(y, t.month)
            || t.hour > 23
            || t.minute > 59
            || t.second > 59
            || t.millis > 999
        {
            return None;
        }
        let mut days: u32 = (1984..y).map(days_in_year).sum();
        days += (1..t.month).map(|m| days_in_month(y, m) as u32).sum::<u32>();
        days += t.day as u32 - 1;
        let ms = ((t.hour as u32 * 60 + t.minute as u32) * 60 + t.second as u32) * 1000 + t.millis as u32;
        Some(TimeOfDay { days: u16::try_from(days).ok()?, ms })
    }

    /// The calendar date and time (milliseconds past a day's end carry into
    /// the hour field, which then exceeds 23: the stamp was not a time of day).
    pub fn to_civil(self) -> CivilTime {
        let mut days = self.days as u32;
        let mut year = 1984u32;
        while days >= days_in_year(year) {
            days -= days_in_year(year);
            year += 1;
        }
        let mut month = 1u8;
        while days >= days_in_month(year, month) as u32 {
            days -= days_in_month(year, month) as u32;
            month += 1;
        }
        let s = self.ms / 1000;
        CivilTime {
            year: year as u16,
            month,
            day: days as u8 + 1,
            hour: (s / 3600) as u8,
            minute: (s / 60 % 60) as u8,
            second: (s % 60) as u8,
            millis: (self.ms % 1000) as u16,
        }
    }
}

/// TIME producer and consumer of one node (object 1012h).
#[derive(Clone, Debug)]
pub struct TimeService {
    cob_id: u32,
    can_id: Option<CanId>,
}

impl TimeService {
    /// Insert 1012h with the CiA 301 default 100h (neither consumer nor
    /// producer) and return the service.
    pub fn install(od: &mut ObjectDictionary) -> TimeService {
        let name = "COB-ID time stamp object";
        od.insert(
            Object::with_code(OD_COB_ID_TIME, ObjectCode::Var, name).with_sub(
                SubObject::new(0, name, DataType::Unsigned32, Access::Rw, Value::U32(0x100)).hooked(),
            ),
        );
        TimeService { cob_id: 0x100, can_id: can_id_of(0x100) }
    }

    /// 1012h bit 31: this node consumes TIME.
    pub fn is_consumer(&self) -> bool {
        self.cob_id & COB_ID_CONSUME != 0
    }
    /// 1012h bit 30: this node produces TIME.
    pub fn is_producer(&self) -> bool {
        self.cob_id & COB_ID_PRODUCE != 0
    }

    /// Send a TIME stamp (6 bytes) if this node is a TIME producer.
    /// Returns whether a frame was sent. `ms_after_midnight` is cut to 28 bits.
    pub fn transmit_time(&self, ms_after_midnight: u32, days_since_1984: u16, out: &mut impl TxSink) -> bool {
        self.transmit(TimeOfDay { ms: ms_after_midnight, days: days_since_1984 }, out)
    }

    /// [`TimeService::transmit_time`] with a [`TimeOfDay`].
    pub fn transmit(&self, t: TimeOfDay, out: &mut impl TxSink) -> bool {
        let Some(id) = self.can_id.filter(|_| self.is_producer()) else { return false };
        match Frame::try_new(id, &t.to_bytes()) {
            Ok(f) => {
                out.send(f);
                true
            }
            Err(_) => false,
        }
    }

    /// A frame from the bus: the stamp, if this node consumes TIME and the
    /// frame is a 6-byte data frame on the 1012h identifier.
    pub fn handle_frame(&self, frame: &Frame) -> Option<TimeOfDay> {
        if !self.is_consumer() || Some(frame.id()) != self.can_id || frame.is_rtr() {
            return None;
        }
        TimeOfDay::from_bytes(frame.data())
    }

    /// The abort for a refused 1012h write: bad or restricted CAN-ID, or
    /// bits 0..29 changed while the consumer or producer bit is set →
    /// `0609 0030` (CiA 301 §7.5.2 (1012h), same rule as the other COB-IDs).
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        if (index, sub) != (OD_COB_ID_TIME, 0) {
            return Ok(());
        }
        let new = le_of(DataType::Unsigned32, data)?;
        let old = od.get_u32(OD_COB_ID_TIME, 0).unwrap_or(self.cob_id);
        check_cob_id(old, new, COB_ID_CONSUME | COB_ID_PRODUCE)
    }

    /// Re-read 1012h after a write was stored.
    pub fn reconfigure(&mut self, od: &ObjectDictionary, index: u16, sub: u8) {
        if (index, sub) == (OD_COB_ID_TIME, 0)
            && let Some(v) = od.get_u32(OD_COB_ID_TIME, 0)
        {
            self.cob_id = v;
            self.can_id = can_id_of(v);
        }
    }
}
