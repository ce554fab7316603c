//! Manufacturer parameters that set a CiA 402 parameter of the drive (KC1
//! §8.1.3, AKD §7.1.4 object tables): DRV.DIR 352Ah (polarity 607Eh),
//! MOTOR.VMAX 35A3h (rpm, the drive's maximum speed 6080h), MT.TPOSWND
//! 35C6h (position window 6067h), MT.TVELWND 3856h (velocity window
//! 606Dh), DRV.ACC 3501h / DRV.DEC 3522h / HOME.ACC 3502h (the drive's
//! own ramps 6083h/6084h/609Ah = 0 select), MOTOR.ICONT 358Eh (rated current and torque, 6075h/6076h), and
//! the pv scaling factor 204Ch (KC1 §7.5.2.1 / AKD §6.5.2.1,
//! the velocity factor 6096h, active with FBUS.PARAM05 bit 4; a negative
//! factor reverses the velocity direction).
//!
//! 607Eh, 6067h, 6075h, 6076h, 6080h and 6096h are not in the manuals' dictionaries:
//! the drive keeps them as its own parameters, reached only from here.

use super::{Kollmorgen, UNITS_PER_REV};
use crate::build::Context;
use drivebus_cia402::drive::ZeroRamp;
use drivebus_od::{ObjectDictionary, SdoAbort, le_u64};

/// The indices whose writes this module turns into drive parameters.
pub const FORWARDED: [u16; 10] =
    [0x352A, 0x35A3, 0x35C6, 0x3856, 0x204C, 0x36E9, 0x358E, 0x3501, 0x3522, 0x3502];

/// FBUS.PARAM05 bit 4: scaling by the DS402 objects (204Ch active).
const DS402_SCALING: u64 = 1 << 4;

fn i32_of(od: &ObjectDictionary, index: u16, sub: u8) -> i64 {
    od.get_i64(index, sub).unwrap_or(0)
}

impl Kollmorgen {
    /// Checks a write of one of [`FORWARDED`] (with the value it would
    /// store) and sets the drive's parameters from the dictionary with it.
    pub(crate) fn forward(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        let v = le_u64(data);
        match index {
            // §7.5.2.1: "the value of 0 shall not be used", ±32767.
            0x204C if sub >= 1 => {
                let x = v as u32 as i32;
                if x == 0 || x.unsigned_abs() > 32_767 {
                    return Err(SdoAbort::INVALID_VALUE);
                }
            }
            0x3856 if v as u32 as i32 > i32::from(u16::MAX) || (v as u32 as i32) < 0 => {
                return Err(SdoAbort::INVALID_VALUE);
            }
            _ => {}
        }
        let get = |i: u16, s: u8| {
            if (i, s) == (index, sub) { i64::from(v as u32 as i32) } else { i32_of(od, i, s) }
        };
        let get_u = |i: u16, s: u8| if (i, s) == (index, sub) { v } else { od.get_u64(i, s).unwrap_or(0) };
        match index {
            // 607Eh: DRV.DIR inverts position and velocity; a negative pv
            // scaling factor inverts the velocity once more.
            0x352A | 0x204C | 0x36E9 => {
                let scaling = get_u(0x36E9, 0) & DS402_SCALING != 0;
                let (num, den) = if scaling { (get(0x204C, 1), get(0x204C, 2)) } else { (1, 1) };
                let (num, den) = (if num == 0 { 1 } else { num }, if den == 0 { 1 } else { den });
                let dir = if get(0x352A, 0) != 0 { 0xC0u8 } else { 0 };
                let polarity = dir ^ if (num < 0) != (den < 0) { 0x40 } else { 0 };
                cx.drive.on_write(od, 0x607E, 0, &[polarity])?;
                cx.drive.on_write(od, 0x6096, 1, &(num.unsigned_abs() as u32).to_le_bytes())?;
                cx.drive.on_write(od, 0x6096, 2, &(den.unsigned_abs() as u32).to_le_bytes())?;
            }
            // MOTOR.VMAX in rpm; 0: the drive's own maximum.
            0x35A3 => {
                let rpm = v as u32;
                let own = cx.drive.config().profile.max_profile_velocity;
                let vmax = if rpm == 0 { own } else { rpm.saturating_mul(UNITS_PER_REV / 60) };
                cx.drive.on_write(od, 0x6080, 0, &vmax.to_le_bytes())?;
            }
            0x35C6 => {
                let w = (v as u32 as i32).max(0) as u32;
                cx.drive.on_write(od, 0x6067, 0, &w.to_le_bytes())?;
            }
            0x3856 => self.local_write(cx, od, 0x606D, 0, &(v as u16).to_le_bytes())?,
            // DRV.ACC, DRV.DEC, HOME.ACC: the drive's own ramps, which 6083h,
            // 6084h, 609Ah = 0 select (KC1 §7.11.2.4/5, §7.10.2.4).
            0x3501 | 0x3522 | 0x3502 => {
                let x = v as u32 as i32;
                if x <= 0 {
                    return Err(SdoAbort::VALUE_TOO_LOW);
                }
                let ZeroRamp::DriveRamp { mut acceleration, mut deceleration, mut homing } =
                    cx.drive.config().zero_ramp
                else {
                    return Ok(());
                };
                let (slot, object) = match index {
                    0x3501 => (&mut acceleration, 0x6083),
                    0x3522 => (&mut deceleration, 0x6084),
                    _ => (&mut homing, 0x609A),
                };
                *slot = x as u32;
                cx.drive.set_zero_ramp(ZeroRamp::DriveRamp { acceleration, deceleration, homing });
                if od.get_u32(object, 0) == Some(0) {
                    cx.drive.on_write(od, object, 0, &0u32.to_le_bytes())?;
                }
            }
            // MOTOR.ICONT (mA): the rated current, and with the motor's
            // torque constant the rated torque 6071h/6077h count in.
            0x358E => {
                let m = &cx.drive.config().params.motor;
                let ma = if v == 0 { (m.rated_current * 1000.0).round() } else { v as u32 as f64 };
                let mnm = (ma * m.kt).round().clamp(1.0, f64::from(u32::MAX)) as u32;
                let ma = ma.clamp(1.0, f64::from(u32::MAX)) as u32;
                cx.drive.on_write(od, 0x6075, 0, &ma.to_le_bytes())?;
                cx.drive.on_write(od, 0x6076, 0, &mnm.to_le_bytes())?;
            }
            _ => {}
        }
        Ok(())
    }

    /// The forwarded parameters again from the dictionary (after the node
    /// restored stored values and the drive reloaded its own).
    pub(crate) fn forward_all(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        for index in [0x352A, 0x35A3, 0x35C6, 0x358E, 0x3501, 0x3522, 0x3502] {
            if let Some(v) = od.get_u64(index, 0)
                && (v != 0 || index == 0x352A)
            {
                let _ = self.forward(cx, od, index, 0, &v.to_le_bytes()[..4]);
            }
        }
    }
}
