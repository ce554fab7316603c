//! The holding brake objects (KC1 §7.2.2.15, AKD §6.2.2.19): 345Ah:1
//! bit 0 takes the brake over from the drive on its rising edge, bit 1 then
//! releases (1) or applies (0) it; a fault, a lost fieldbus or bit 0 = 0
//! give it back to the drive. 345Ah:2 reports bit 0 fieldbus control, bit
//! 1 brake released (after the brake's delay), bit 2 STO, bit 3 hardware
//! enable (the model has neither: 0). MOTOR.BRAKERLS 3450h (§8.1.3): 0
//! the drive's brake, 1 released, 2 applied; the fieldbus control comes
//! first. MOTOR.TBRAKERLS 366Fh / MOTOR.TBRAKEAPP 366Eh (ms): the
//! drive's own brake times ([`BrakeDelays`]): after the release the mode
//! waits TBRAKERLS, after the apply the power stage holds TBRAKEAPP,
//! whatever the brake does; 0 (both) = the drive waits for the brake.

use crate::build::Context;
use drivebus_cia402::drive::{BrakeControl, BrakeDelays};
use drivebus_cia402::state_machine::State;
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort};

/// The brake objects' state.
#[derive(Debug, Clone, Default)]
pub struct FieldbusBrake {
    status: Option<EntryRef>,
    objects: usize,
    /// 345Ah:1 as last written.
    command: u16,
    /// Fieldbus control taken (a rising edge of bit 0 since the last loss).
    active: bool,
    /// MOTOR.BRAKERLS: `None` the drive's, else released (`true`) / applied.
    manual: Option<bool>,
}

impl FieldbusBrake {
    /// A write of 345Ah:1.
    pub fn command(&mut self, value: u16) {
        if value & 1 == 0 {
            self.active = false;
        } else if self.command & 1 == 0 {
            self.active = true;
        }
        self.command = value;
    }

    /// A write of MOTOR.BRAKERLS.
    pub fn manual(&mut self, value: u8) -> Result<(), SdoAbort> {
        self.manual = match value {
            0 => None,
            1 => Some(true),
            2 => Some(false),
            _ => return Err(SdoAbort::INVALID_VALUE),
        };
        Ok(())
    }

    /// The fieldbus is lost (guarding, heartbeat, NMT left operational) or
    /// the drive reset: the drive takes the brake back.
    pub fn lost(&mut self) {
        self.active = false;
    }

    /// After every step: who commands the brake, and 345Ah:2.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if self.objects != od.objects().len() {
            self.objects = od.objects().len();
            self.status = od.find(0x345A, 2).ok();
        }
        // "After a fault the functionality is reset."
        if matches!(cx.drive.state_machine().state(), State::Fault | State::FaultReactionActive) {
            self.active = false;
        }
        let control = match (self.active, self.manual) {
            (true, _) if self.command & 2 != 0 => BrakeControl::Released,
            (true, _) => BrakeControl::Engaged,
            (false, Some(true)) => BrakeControl::Released,
            (false, Some(false)) => BrakeControl::Engaged,
            (false, None) => BrakeControl::Auto,
        };
        if cx.drive.brake_control() != control {
            cx.drive.set_brake_control(control);
        }
        let b = cx.drive.model().brake();
        let status = u16::from(self.active) | u16::from(b.fitted && !b.engaged) << 1;
        if let Some(r) = self.status {
            od.set_raw(r, &status.to_le_bytes());
        }
    }
}

/// The drive's brake times from MOTOR.TBRAKERLS 366Fh / MOTOR.TBRAKEAPP
/// 366Eh (ms; `pending` a write in progress); 0 in both: the drive waits
/// for the brake itself, 0 in one: the machine's delay for that one.
pub fn set_delays(
    cx: &mut Context<'_>,
    od: &ObjectDictionary,
    pending: Option<(u16, u32)>,
) -> Result<(), SdoAbort> {
    let get = |i: u16| match pending {
        Some((p, v)) if p == i => v as i32,
        _ => od.get_i64(i, 0).unwrap_or(0) as i32,
    };
    let (rls, app) = (get(0x366F), get(0x366E));
    if rls < 0 || app < 0 {
        return Err(SdoAbort::VALUE_TOO_LOW);
    }
    let machine = cx.drive.model().params().io.brake;
    let own = |v: i32, m: f64| if v > 0 { v as u32 } else { (m * 1000.0).round() as u32 };
    let d = match (rls, app, machine) {
        (0, 0, _) => None,
        (_, _, Some(b)) => {
            Some(BrakeDelays { release_ms: own(rls, b.release_delay), apply_ms: own(app, b.apply_delay) })
        }
        (_, _, None) => Some(BrakeDelays { release_ms: own(rls, 0.0), apply_ms: own(app, 0.0) }),
    };
    cx.drive.set_brake_delays(d);
    Ok(())
}
