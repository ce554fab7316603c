//! 1C32h/1C33h (ETG.1020 synchronisation parameters) as the slave runs
//! them: the type and cycle the master set up, taken at PRE-OP → SAFE-OP
//! from the ESC's DC registers; 60C2h made consistent with the SYNC0
//! cycle (iPOS §3.2: "60C2h must equal the master cycle / SYNC time");
//! the sync error counters masters read.

use drivebus_can::{Frame, Instant};
use drivebus_esc::slave::{AlStatusCode, SyncConfig, SyncMode};
use drivebus_od::ObjectDictionary;
use drivebus_personality::PersonalityDevice;
use drivebus_personality::ecat::sync_sub as sub;

/// The slave's side of 1C32h/1C33h.
#[derive(Debug, Clone, Default)]
pub struct SyncParams {
    dc: bool,
    /// Outputs received since the last SYNC0 pulse (DC).
    received: u32,
    /// The last SM2 event (SM-synchronous).
    last_event: Option<Instant>,
}

fn set_u16(od: &mut ObjectDictionary, index: u16, s: u8, v: u16) {
    if let Ok(r) = od.find(index, s) {
        od.set_le(r, &v.to_le_bytes());
    }
}

fn set_u32(od: &mut ObjectDictionary, index: u16, s: u8, v: u32) {
    if let Ok(r) = od.find(index, s) {
        od.set_le(r, &v.to_le_bytes());
    }
}

fn bump(od: &mut ObjectDictionary, s: u8) {
    for index in [0x1C32u16, 0x1C33] {
        let v = od.get_u32(index, s).unwrap_or(0) as u16;
        set_u16(od, index, s, v.saturating_add(1));
        if let Ok(r) = od.find(index, sub::SYNC_ERROR) {
            od.set_le(r, &[1]);
        }
    }
}

/// A cycle in ns as 60C2h writes it: `value × 10^index` s, the value in
/// 1..=255 with the largest index that keeps it whole.
pub fn interpolation_period(cycle_ns: u32) -> Option<(u8, i8)> {
    (-9i8..=-3).rev().find_map(|e| {
        let unit = 10u64.pow((9 + i32::from(e)) as u32);
        let ns = u64::from(cycle_ns);
        (ns % unit == 0 && (1..=255).contains(&(ns / unit))).then(|| ((ns / unit) as u8, e))
    })
}

impl SyncParams {
    /// PRE-OP → SAFE-OP: the type the master wrote must fit the DC set-up
    /// (1C32h:01 = 2 without DC activated in 0x0981 → 0030h).
    pub fn check(&self, od: &ObjectDictionary, cfg: &SyncConfig) -> Result<(), AlStatusCode> {
        let wanted = od.get_u32(0x1C32, sub::SYNC_TYPE).unwrap_or(0);
        if wanted == 2 && cfg.mode == SyncMode::FreeRun {
            return Err(AlStatusCode::INVALID_DC_SYNC_CONFIG);
        }
        Ok(())
    }

    /// Entered SAFE-OP with `cfg` (or OP with a DC set-up made in
    /// SAFE-OP): 1C32h/1C33h show it, the counters start at 0, and in DC
    /// mode 60C2h is the SYNC0 cycle (written through the write path, so
    /// the drive's cyclic modes take it).
    pub fn enter_safe_op(
        &mut self,
        dev: &mut PersonalityDevice,
        cfg: &SyncConfig,
        now: Instant,
        frames: &mut Vec<Frame>,
    ) {
        self.dc = cfg.mode != SyncMode::FreeRun;
        self.received = 0;
        self.last_event = None;
        let od = dev.node.od_mut();
        for index in [0x1C32u16, 0x1C33] {
            for s in [sub::SM_EVENT_MISSED, sub::CYCLE_TOO_SMALL] {
                set_u16(od, index, s, 0);
            }
            if let Ok(r) = od.find(index, sub::SYNC_ERROR) {
                od.set_le(r, &[0]);
            }
            if self.dc {
                set_u16(od, index, sub::SYNC_TYPE, 2);
                set_u32(od, index, sub::CYCLE_TIME, cfg.sync0_cycle);
                set_u32(od, index, sub::SYNC0_CYCLE, cfg.sync0_cycle);
            } else {
                let t = od.get_u32(0x1C32, sub::SYNC_TYPE).unwrap_or(1);
                let v = if index == 0x1C32 {
                    t
                } else if t == 1 {
                    0x22
                } else {
                    0
                };
                set_u16(od, index, sub::SYNC_TYPE, v as u16);
                set_u32(od, index, sub::SYNC0_CYCLE, 0);
            }
        }
        if self.dc
            && let Some((value, exp)) = interpolation_period(cfg.sync0_cycle)
            && od.object(0x60C2).is_some()
            && (od.get_u32(0x60C2, 1), od.get_i64(0x60C2, 2))
                != (Some(u32::from(value)), Some(i64::from(exp)))
        {
            let _ = dev.write_object(0x60C2, 2, &[exp as u8], now, frames);
            let _ = dev.write_object(0x60C2, 1, &[value], now, frames);
        }
    }

    /// The master wrote the outputs (every mode).
    pub fn received(&mut self) {
        self.received = self.received.saturating_add(1);
    }

    /// SM-synchronous: an SM2 event; with 1C32h:08 = 1 the time since the
    /// previous one is the measured cycle time (1C32h:02).
    pub fn sm_event(&mut self, dev: &mut PersonalityDevice, now: Instant) {
        let od = dev.node.od_mut();
        if let Some(t) = self.last_event
            && od.get_u32(0x1C32, sub::GET_CYCLE) == Some(1)
        {
            let ns = (now - t).as_nanos().min(u128::from(u32::MAX)) as u32;
            set_u32(od, 0x1C32, sub::CYCLE_TIME, ns);
        }
        self.last_event = Some(now);
        self.received = 0;
    }

    /// DC in OP: a SYNC0 pulse. No outputs since the last one: an SM event
    /// was missed; more than one: the cycle is shorter than SYNC0.
    pub fn pulse(&mut self, dev: &mut PersonalityDevice) {
        let od = dev.node.od_mut();
        match self.received {
            0 => bump(od, sub::SM_EVENT_MISSED),
            1 => {
                for index in [0x1C32u16, 0x1C33] {
                    if let Ok(r) = od.find(index, sub::SYNC_ERROR) {
                        od.set_le(r, &[0]);
                    }
                }
            }
            _ => bump(od, sub::CYCLE_TOO_SMALL),
        }
        self.received = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periods() {
        assert_eq!(interpolation_period(1_000_000), Some((1, -3)));
        assert_eq!(interpolation_period(2_000_000), Some((2, -3)));
        assert_eq!(interpolation_period(500_000), Some((5, -4)));
        assert_eq!(interpolation_period(125_000), Some((125, -6)));
        assert_eq!(interpolation_period(1_234_567), None);
    }
}
