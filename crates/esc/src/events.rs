//! Events the ESC raises towards the slave firmware (the PDI side).
//!
//! Like the interrupt lines of a real ESC, events are *pending flags*: the
//! same event raised twice before the firmware takes it is delivered once.
//! SYNC events carry the exact time of the latest pulse and how many pulses
//! were folded into it. Storage is fixed: raising an event never
//! allocates and never fails.

use drivebus_base::Instant;

/// Something the firmware should react to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EscEvent {
    /// The ESC was reset through 0x0040 (or by [`crate::Esc::reset`]).
    EscReset,
    /// The master wrote the AL control register (0x0120).
    AlControl,
    /// The DL status (links, loops) changed.
    DlStatusChanged,
    /// A SII reload command finished (configuration area re-applied).
    SiiReloaded,
    /// A SII write command stored a word in the image.
    SiiWritten,
    /// The process-data (SM) watchdog expired.
    ProcessDataWatchdog,
    /// The PDI watchdog expired.
    PdiWatchdog,
    /// A SYNC0 pulse.
    Sync0 {
        /// System time of the pulse.
        system_time: u64,
        /// Caller time of the pulse.
        at: Instant,
        /// Earlier pulses folded into this one (late polling).
        missed: u32,
    },
    /// A SYNC1 pulse.
    Sync1 {
        /// System time of the pulse.
        system_time: u64,
        /// Caller time of the pulse.
        at: Instant,
        /// Earlier pulses folded into this one.
        missed: u32,
    },
    /// A sync manager activation register changed (enable or repeat
    /// request, 0x0806 + 8·n).
    SmChanged,
    /// The master finished writing the buffer of SM n (mailbox full, new
    /// 3-buffer data).
    SmWritten(u8),
    /// The master finished reading the buffer of SM n (mailbox emptied).
    SmRead(u8),
}

const ESC_RESET: u16 = 1 << 0;
const AL_CONTROL: u16 = 1 << 1;
const DL_STATUS: u16 = 1 << 2;
const SII_RELOADED: u16 = 1 << 3;
const SII_WRITTEN: u16 = 1 << 4;
const PD_WATCHDOG: u16 = 1 << 5;
const PDI_WATCHDOG: u16 = 1 << 6;
const SYNC0: u16 = 1 << 7;
const SYNC1: u16 = 1 << 8;
const SM_CHANGED: u16 = 1 << 9;

#[derive(Debug, Clone, Copy, Default)]
struct SyncInfo {
    system_time: u64,
    at: Instant,
    missed: u32,
}

/// Pending-event flags in fixed storage.
#[derive(Debug, Clone, Default)]
pub(crate) struct EventQueue {
    flags: u16,
    sm_written: u16,
    sm_read: u16,
    sync0: SyncInfo,
    sync1: SyncInfo,
}

impl EventQueue {
    /// Raises an event.
    pub fn push(&mut self, e: EscEvent) {
        match e {
            EscEvent::EscReset => self.flags |= ESC_RESET,
            EscEvent::AlControl => self.flags |= AL_CONTROL,
            EscEvent::DlStatusChanged => self.flags |= DL_STATUS,
            EscEvent::SiiReloaded => self.flags |= SII_RELOADED,
            EscEvent::SiiWritten => self.flags |= SII_WRITTEN,
            EscEvent::ProcessDataWatchdog => self.flags |= PD_WATCHDOG,
            EscEvent::PdiWatchdog => self.flags |= PDI_WATCHDOG,
            EscEvent::Sync0 { system_time, at, missed } => {
                let folded = if self.flags & SYNC0 != 0 { self.sync0.missed.saturating_add(1) } else { 0 };
                self.sync0 = SyncInfo { system_time, at, missed: missed.saturating_add(folded) };
                self.flags |= SYNC0;
            }
            EscEvent::Sync1 { system_time, at, missed } => {
                let folded = if self.flags & SYNC1 != 0 { self.sync1.missed.saturating_add(1) } else { 0 };
                self.sync1 = SyncInfo { system_time, at, missed: missed.saturating_add(folded) };
                self.flags |= SYNC1;
            }
            EscEvent::SmChanged => self.flags |= SM_CHANGED,
            EscEvent::SmWritten(n) => self.sm_written |= 1 << (n & 15),
            EscEvent::SmRead(n) => self.sm_read |= 1 << (n & 15),
        }
    }

    /// True if nothing is pending.
    pub fn is_empty(&self) -> bool {
        self.flags == 0 && self.sm_written == 0 && self.sm_read == 0
    }

    /// Takes the most urgent pending event: reset, AL control, link and SII
    /// changes, watchdogs, SYNC pulses, then sync manager events by index.
    pub fn pop(&mut self) -> Option<EscEvent> {
        if self.flags != 0 {
            let bit = self.flags & self.flags.wrapping_neg();
            self.flags &= !bit;
            return Some(match bit {
                ESC_RESET => EscEvent::EscReset,
                AL_CONTROL => EscEvent::AlControl,
                DL_STATUS => EscEvent::DlStatusChanged,
                SII_RELOADED => EscEvent::SiiReloaded,
                SII_WRITTEN => EscEvent::SiiWritten,
                PD_WATCHDOG => EscEvent::ProcessDataWatchdog,
                PDI_WATCHDOG => EscEvent::PdiWatchdog,
                SYNC0 => EscEvent::Sync0 {
                    system_time: self.sync0.system_time,
                    at: self.sync0.at,
                    missed: self.sync0.missed,
                },
                SYNC1 => EscEvent::Sync1 {
                    system_time: self.sync1.system_time,
                    at: self.sync1.at,
                    missed: self.sync1.missed,
                },
                _ => EscEvent::SmChanged,
            });
        }
        if self.sm_written != 0 {
            let n = self.sm_written.trailing_zeros() as u8;
            self.sm_written &= !(1 << n);
            return Some(EscEvent::SmWritten(n));
        }
        if self.sm_read != 0 {
            let n = self.sm_read.trailing_zeros() as u8;
            self.sm_read &= !(1 << n);
            return Some(EscEvent::SmRead(n));
        }
        None
    }

    /// Drops everything (ESC reset).
    pub fn clear(&mut self) {
        *self = EventQueue::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_coalesce_and_come_out_by_priority() {
        let mut q = EventQueue::default();
        q.push(EscEvent::SmWritten(2));
        q.push(EscEvent::SmWritten(0));
        q.push(EscEvent::SmWritten(2));
        q.push(EscEvent::AlControl);
        q.push(EscEvent::Sync0 { system_time: 5, at: Instant::from_nanos(1), missed: 0 });
        q.push(EscEvent::Sync0 { system_time: 9, at: Instant::from_nanos(2), missed: 1 });
        assert_eq!(q.pop(), Some(EscEvent::AlControl));
        assert_eq!(q.pop(), Some(EscEvent::Sync0 { system_time: 9, at: Instant::from_nanos(2), missed: 2 }));
        assert_eq!(q.pop(), Some(EscEvent::SmWritten(0)));
        assert_eq!(q.pop(), Some(EscEvent::SmWritten(2)));
        assert_eq!(q.pop(), None);
        assert!(q.is_empty());
    }
}
