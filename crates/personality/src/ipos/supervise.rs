//! The iPOS rules that run beside the drive: the objects whose writes
//! reach the drive changed or do something of their own (TML, memory,
//! save, reset, outputs, time factor), and what is kept in step after
//! every drive step (6061h, pv entry, the speed control error) or write
//! (the factor group, the times, the homing and positioning options).

use super::*;
use drivebus_cia402::drive::DriveView;

impl Ipos {
    /// The writes §3–§18 give an effect of the iPOS's own; `None` for the
    /// others (the caller's rules, then the drive).
    pub(super) fn object_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        value: u64,
    ) -> Option<Result<Verdict, SdoAbort>> {
        let r = match (index, sub) {
            // §4.4.11: −1 "no action" (for the non-fatal errors): stored;
            // the fault actions (status.rs) carry it out.
            (0x605E, 0) if value as u16 as i16 == -1 => Ok(Verdict::Store),
            (0x6066 | 0x6068, 0) if factor::time_factor(od) != (1, 1) => {
                // §5.1.13: the time in time units; the drive takes ms.
                let ms = factor::time_iu(od, value, u64::from(u16::MAX)) as u16;
                cx.drive.on_write(od, index, 0, &ms.to_le_bytes()).map(|_| Verdict::Store)
            }
            // §18.2.2.1 / §18.3.1: the twin holds no TML functions or
            // program (it runs no TML): 1..10 or any program start is
            // "not defined" (0800 0020h), other function numbers 0609 0030h.
            (0x2006, 0) if !(1..=10).contains(&value) => Err(SdoAbort::INVALID_VALUE),
            (0x2006 | 0x2077, 0) => Err(SdoAbort::CANNOT_STORE),
            (0x60FE, 2) => {
                // §4.5.3: an output the drive does not have selected in the
                // mask: EMCY FF05h; it does not reach the machine.
                let mask = Self::available_outputs(cx, value as u32);
                cx.drive.on_write(od, 0x60FE, 2, &mask.to_le_bytes()).map(|_| Verdict::Store)
            }
            (0x2065 | 0x2067, 0) => {
                // §17.2.2 / §17.2.4: write-only commands on the memory.
                self.memory_write(od, index, value as u32).map(|()| Verdict::Handled)
            }
            (0x2076, 0) => {
                // §4.9.6: any value saves the operating parameters to the
                // EEPROM (the node's parameter storage, as 1010h:01 does);
                // they come back at the next power-on or reset.
                cx.request(Request::StoreParameters);
                Ok(Verdict::Handled)
            }
            (0x2080, 0) => {
                // §4.9.8: a non-zero value resets the drive, as a power
                // cycle: parameters from the EEPROM, Switch on disabled,
                // the position counter restarts (the CAN node's reset;
                // on EtherCAT the ESM stays, ecat/behaviour.rs).
                if value != 0 {
                    cx.request(Request::Nmt(drivebus_nmt::NmtCommand::ResetNode));
                }
                Ok(Verdict::Handled)
            }
            _ => return None,
        };
        Some(r)
    }

    /// §4.2.4: "if the drive is in an inferior state than Operation enabled
    /// and 6060h is changed, 6061h will take the value of 6060h only after
    /// the drive reached Operation enabled".
    pub(super) fn show_mode(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        refs: Refs,
        view: DriveView,
    ) {
        let Some(r) = refs.mode_display else { return };
        if view.state == State::OperationEnabled {
            self.mode_shown = cx.drive.manufacturer_mode().unwrap_or(cx.drive.mode());
        }
        if od.bytes(r).first() != Some(&(self.mode_shown as u8)) {
            od.set_le(r, &[self.mode_shown as u8]);
        }
    }

    /// §10.1 remark 2: "if the velocity is already set when entering
    /// velocity mode, the motion will not start until a value (even if it
    /// is the same) will be set again in Target Velocity 60FFh": on entry
    /// the drive's target is 0 until the next 60FFh write.
    pub(super) fn enter_pv(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, view: DriveView) {
        let pv = view.mode == 3 && view.state == State::OperationEnabled;
        if pv && !self.in_pv {
            let _ = cx.drive.on_write(od, 0x60FF, 0, &0i32.to_le_bytes());
        }
        self.in_pv = pv;
    }

    /// §10.2.8 / §10.2.9: the speed control error. With 60F8h > 0 (0, the
    /// working default, is the set-up's "disabled"), a speed error
    /// |606Bh − 606Ch| beyond 60F8h for longer than 2005h (time units)
    /// sets statusword bit 13 "max slippage error" and faults with a
    /// control error (8611h, 2000h bit 3), in pv and csv.
    pub(super) fn watch_slippage(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        refs: Refs,
        view: DriveView,
    ) {
        let max = i64_at(od, refs.max_slippage).unwrap_or(0);
        if max <= 0 || !matches!(view.mode, 3 | 9) || view.state != State::OperationEnabled {
            self.slipping_since = None;
            return;
        }
        let demand = i64_at(od, refs.velocity_demand).unwrap_or(0);
        let actual = i64_at(od, refs.velocity_actual).unwrap_or(0);
        if (demand - actual).abs() <= max {
            self.slipping_since = None;
            return;
        }
        let now = cx.now.as_nanos();
        let since = *self.slipping_since.get_or_insert(now);
        if let Some(r) = refs.statusword {
            let sw = u32_at(od, Some(r)).unwrap_or(0) as u16 | 1 << 13;
            od.set_le(r, &sw.to_le_bytes());
        }
        let limit_ms =
            factor::time_iu(od, u32_at(od, refs.slippage_time).unwrap_or(0).into(), u64::from(u32::MAX));
        if now.saturating_sub(since) > limit_ms * 1_000_000 {
            self.slipping_since = None;
            cx.drive.inject(drivebus_cia402::drive::Injection::Fault(0x8611));
        }
    }

    /// 2023h jerk time (ms, §7.2.5: the S-curve's time to reach the
    /// profile acceleration) → the drive's jerk = 6083h / t.
    pub(super) fn sync_jerk(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let ms =
            factor::time_iu(od, u64::from(od.get_u32(0x2023, 0).unwrap_or(0)), u64::from(u32::MAX)) as u32;
        cx.drive.set_profile_jerk(od, ProfileJerk::Time(f64::from(ms) * 1e-3));
    }

    /// §4.9.12: 210Bh bit 12 = 1, "after finishing a homing procedure, do
    /// not reset the actual position. Homing ends keeping position on home
    /// switch".
    pub(super) fn sync_asr2(cx: &mut Context<'_>, od: &ObjectDictionary) {
        cx.drive.set_homing_keeps_position(od.get_u32(0x210B, 0).unwrap_or(0) & 1 << 12 != 0);
        // §7.2.15: 60F2h rado, how pp reaches a target in the 607Bh range.
        cx.drive.set_positioning_option(od.get_u32(0x60F2, 0).unwrap_or(0) as u16);
    }

    /// The time objects in time units → the drive's ms (2071h, §5.1.13).
    pub(super) fn sync_times(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        for index in factor::TIMES {
            let t = od.get_u32(index, 0).unwrap_or(0);
            let ms = factor::time_iu(od, u64::from(t), u64::from(u16::MAX)) as u16;
            let _ = cx.drive.on_write(od, index, 0, &ms.to_le_bytes());
        }
        Self::sync_jerk(cx, od);
    }

    /// The scaling objects in force (§5, factor.rs) → the drive's units.
    pub(super) fn sync_scaling(&mut self, cx: &mut Context<'_>, od: &ObjectDictionary) {
        if let Some(s) = factor::scaling(od)
            && cx.drive.set_scaling(Some(s))
        {
            self.velocity_iu = s.velocity;
        }
    }

    /// kₜ × 6075h: the torque the drive's ‰ refer to (§8.2.1: 6071h, 6072h,
    /// 6074h, 6077h are ‰ of the motor rated current 6075h; the drive
    /// computes with at least 1 mA). The iPOS has no 6076h: the drive keeps
    /// its rated torque as a withdrawn parameter (build/conform.rs).
    pub(super) fn sync_torque_reference(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let ma = od.get_u32(0x6075, 0).unwrap_or(0).max(1);
        let kt = cx.drive.config().params.motor.kt;
        let mnm = (kt * f64::from(ma)).round().clamp(1.0, f64::from(u32::MAX)) as u32;
        let _ = cx.drive.on_write(od, 0x6076, 0, &mnm.to_le_bytes());
    }
}
