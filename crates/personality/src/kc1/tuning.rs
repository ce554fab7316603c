//! The loop gains, motor data and limits of the object tables (KC1 §8.1.3,
//! AKD §7.1.4) on the drive model, and the motor's I²t foldback.
//!
//! The tables give the float scale (1000:1: the object is the parameter
//! × 1000, KC1 §8.1.3 preamble) but no units; the units are the drives'
//! own (docs/personalities.md "Kollmorgen tuning parameters"):
//!
//! | object | parameter | unit | model |
//! |---|---|---|---|
//! | 3542h | PL.KP | 1/s | position loop gain |
//! | 3480h | PL.KI | Hz | position integral: PL.KP·2π·PL.KI |
//! | 3548h | VL.KP | A/(rad/s) | velocity loop gain |
//! | 354Dh | VL.KI | Hz | velocity integral: VL.KP·2π·VL.KI |
//! | 354Bh, 3407h:2 | VL.KVFF | — | share of the velocity feed-forward |
//! | 3593h | MOTOR.KT | Nm/A | torque constant |
//! | 35ABh | MOTOR.INERTIA | kg·cm² | rotor inertia |
//! | 525Fh | LOAD.INERTIA | kg·cm² (1:1) | load inertia |
//! | 3456h | MOTOR.R | Ω | winding resistance (voltage, heating) |
//! | 5260h | MOTOR.KE | V/krpm (1:1) | back-EMF constant |
//! | 3454h | MOTOR.CTF0 | mHz | foldback time constant 1/(2π·CTF0) |
//! | 356Eh/356Fh | IL.LIMITP/N | A | current limit per direction |
//! | 3622h/3623h | VL.LIMITP/N | rpm (1:1) | speed limit per direction |
//! | 3598h, 3455h | IL.KP, MOTOR.LQLL | V/A, mH | current loop time constant LQLL/IL.KP (both set) |
//! | 3423h | IL.OFFSET | A | current added to the command (gravity) |
//! | 3452h | MOTOR.VOLTMAX | V (1:1) | voltage applied to the motor |
//! | 3422h | IL.FRICTION | A | current added in the direction of motion |
//!
//! 0, the tables' default, stands for the machine's own value (as
//! MOTOR.VMAX and MOTOR.ICONT): the drive starts with the machine's tuning.
//! A changed gain keeps the machine's integral corner frequency unless
//! its KI is set too.
//!
//! The foldback (KC1 §7.1 F304/n304, AKD §6.1) runs between the motor's
//! continuous (MOTOR.ICONT) and peak (MOTOR.IPEAK) currents: IL.IFOLD
//! 3425h and IL.MIFOLD 35A4h read its current, IL.MI2T 3427h:3 the I²t
//! load in % of the continuous rating; below IL.FOLDWTHRESH 355Ah (or
//! above IL.MI2TWTRESH 3427h:2 %) warning n304, below the fault level
//! (IL.FOLDFTHRESHU 3421h, else IL.FOLDFTHRESH 3420h) fault F304. AKD
//! 60E0h/60E1h read the current limits in force in ‰ of the rated
//! current (§6.7.2.7/8).

use super::status::{Status, Warning};
use crate::build::Context;
use core::f64::consts::PI;
use drivebus_cia402::drive::Injection;
use drivebus_cia402::drive::units::round;
use drivebus_cia402::model::{DriveParams, FoldbackParams};
use drivebus_cia402::state_machine::State;
use drivebus_od::{DataType, EntryRef, ObjectDictionary, SdoAbort, le_u64};

/// The objects whose writes retune the model (IL.OFFSET and IL.FRICTION
/// are 0 = none: a current offset of 0 is no offset).
pub const TUNED: [(u16, u8); 21] = [
    (0x3542, 0),
    (0x3480, 0),
    (0x3548, 0),
    (0x354D, 0),
    (0x354B, 0),
    (0x3407, 2),
    (0x3593, 0),
    (0x35AB, 0),
    (0x525F, 0),
    (0x3456, 0),
    (0x5260, 0),
    (0x3454, 0),
    (0x356E, 0),
    (0x356F, 0),
    (0x3622, 0),
    (0x3623, 0),
    (0x3422, 0),
    (0x3423, 0),
    (0x3598, 0),
    (0x3455, 0),
    (0x3452, 0),
];

/// KC1 §7.1 / AKD §6.1: F304 motor foldback.
const FOLDBACK_FAULT: u16 = 0x8311;
const RPM: f64 = 2.0 * PI / 60.0;

/// A write in progress: its value stands in for the stored one.
type Pending<'a> = Option<(u16, u8, &'a [u8])>;

/// The value of `index:sub` (sign-extended where the object is signed).
fn value(od: &ObjectDictionary, index: u16, sub: u8, pending: Pending<'_>) -> i64 {
    let Ok(r) = od.find(index, sub) else { return 0 };
    let stored = od.bytes(r);
    let mut b = [0u8; 8];
    let src: &[u8] = match pending {
        Some((i, s, d)) if (i, s) == (index, sub) => d,
        _ => stored,
    };
    let n = src.len().min(stored.len()).min(8);
    b[..n].copy_from_slice(&src[..n]);
    let raw = le_u64(&b[..n.max(1)]);
    let signed = od.get(index, sub).is_some_and(|e| {
        matches!(e.data_type, DataType::Integer8 | DataType::Integer16 | DataType::Integer32)
    });
    if signed && n > 0 && n < 8 {
        let shift = 64 - 8 * n as u32;
        ((raw << shift) as i64) >> shift
    } else {
        raw as i64
    }
}

/// Whether `index:sub` is one of [`TUNED`].
pub fn is_tuned(index: u16, sub: u8) -> bool {
    TUNED.contains(&(index, sub))
}

/// The model's parameters from the machine's and the objects.
fn params(base: &DriveParams, od: &ObjectDictionary, pending: Pending<'_>) -> Result<DriveParams, SdoAbort> {
    let v = |i: u16| value(od, i, 0, pending);
    let milli = |i: u16| v(i) as f64 / 1000.0;
    for i in [0x354D, 0x354B] {
        if v(i) < 0 {
            return Err(SdoAbort::VALUE_TOO_LOW);
        }
    }
    let mut p = *base;
    let c = &mut p.control;
    let b = &base.control;
    let corner = |kp: f64, ki: f64| if kp > 0.0 { ki / kp } else { 0.0 };
    if v(0x3542) > 0 {
        c.position_kp = milli(0x3542);
        c.position_ki = c.position_kp * corner(b.position_kp, b.position_ki);
    }
    if v(0x3480) > 0 {
        c.position_ki = c.position_kp * 2.0 * PI * milli(0x3480);
    }
    if v(0x3548) > 0 {
        c.velocity_kp = milli(0x3548);
        c.velocity_ki = c.velocity_kp * corner(b.velocity_kp, b.velocity_ki);
    }
    if v(0x354D) > 0 {
        c.velocity_ki = c.velocity_kp * 2.0 * PI * milli(0x354D);
    }
    // VL.KVFF twice in the table (354Bh, 3407h:2): the later write wins,
    // the other object is made to match.
    let kvff = match pending {
        Some((0x3407, 2, _)) => value(od, 0x3407, 2, pending),
        _ => v(0x354B),
    };
    if kvff > 0 {
        c.velocity_feedforward = kvff as f64 / 1000.0;
    }
    let m = &mut p.motor;
    if v(0x3593) > 0 {
        m.kt = milli(0x3593);
    }
    if v(0x35AB) > 0 {
        m.rotor_inertia = milli(0x35AB) * 1e-4;
    }
    if v(0x3456) > 0 {
        m.resistance = milli(0x3456);
    }
    if v(0x5260) > 0 {
        m.ke = v(0x5260) as f64 / (1000.0 * RPM);
    }
    if v(0x525F) > 0 {
        p.axis.load_inertia = v(0x525F) as f64 * 1e-4;
    }
    // IL.KP (V/A) on the winding's inductance MOTOR.LQLL (mH): the
    // current loop's time constant L / IL.KP, when both are set.
    if v(0x3598) < 0 {
        return Err(SdoAbort::VALUE_TOO_LOW);
    }
    if v(0x3598) > 0 && v(0x3455) > 0 {
        p.motor.current_time_constant = milli(0x3455) * 1e-3 / milli(0x3598);
    }
    p.validate().map_err(|_| SdoAbort::VALUE_TOO_HIGH)?;
    Ok(p)
}

/// A limit object (A × 1000 or rpm): its magnitude, `None` for 0.
fn limit(od: &ObjectDictionary, index: u16, pending: Pending<'_>, scale: f64) -> f64 {
    match value(od, index, 0, pending).unsigned_abs() {
        0 => f64::INFINITY,
        x => x as f64 * scale,
    }
}

/// Sets the model from the objects (`pending`: a write being checked, its
/// value in place of the stored one). Refused values leave the drive as it
/// was.
pub fn apply(cx: &mut Context<'_>, od: &mut ObjectDictionary, pending: Pending<'_>) -> Result<(), SdoAbort> {
    let base = cx.drive.config().params;
    let p = params(&base, od, pending)?;
    cx.drive.set_model_params(p).map_err(|_| SdoAbort::VALUE_TOO_HIGH)?;
    let ip = limit(od, 0x356E, pending, 1e-3);
    let in_ = limit(od, 0x356F, pending, 1e-3);
    cx.drive.set_current_limits(ip, in_).map_err(|_| SdoAbort::INVALID_VALUE)?;
    let vp = limit(od, 0x3622, pending, RPM);
    let vn = limit(od, 0x3623, pending, RPM);
    cx.drive.set_velocity_limits(vp, vn).map_err(|_| SdoAbort::INVALID_VALUE)?;
    cx.drive.set_voltage_limit(limit(od, 0x3452, pending, 1.0)).map_err(|_| SdoAbort::INVALID_VALUE)?;
    cx.drive.set_foldback(Some(foldback(cx, od, pending))).map_err(|_| SdoAbort::INVALID_VALUE)?;
    // IL.OFFSET (A × 1000, signed) and IL.FRICTION (A × 1000).
    let offset = value(od, 0x3423, 0, pending) as f64 / 1000.0;
    let friction = value(od, 0x3422, 0, pending) as f64 / 1000.0;
    cx.drive.set_current_feedforward(offset, friction).map_err(|_| SdoAbort::VALUE_TOO_HIGH)?;
    if let Some((i @ (0x354B | 0x3407), s, d)) = pending {
        // Keep both VL.KVFF objects equal.
        let other = if (i, s) == (0x354B, 0) { (0x3407, 2) } else { (0x354B, 0) };
        if let Ok(r) = od.find(other.0, other.1) {
            let mut b = [0u8; 4];
            b[..d.len().min(4)].copy_from_slice(&d[..d.len().min(4)]);
            od.set_raw(r, &b);
        }
    }
    Ok(())
}

/// The foldback's ratings: MOTOR.ICONT / MOTOR.IPEAK where set (mA), the
/// time constant from MOTOR.CTF0 (mHz × 1000), else the machine's winding
/// thermal time constant.
fn foldback(cx: &Context<'_>, od: &ObjectDictionary, pending: Pending<'_>) -> FoldbackParams {
    let m = &cx.drive.config().params.motor;
    let ma = |i: u16| match value(od, i, 0, pending) {
        x if x > 0 => Some(x as f64 / 1000.0),
        _ => None,
    };
    let peak = ma(0x358F).unwrap_or(m.max_current).min(m.max_current);
    let continuous = ma(0x358E).unwrap_or(m.rated_current).min(peak);
    let ctf0 = value(od, 0x3454, 0, pending);
    let time_constant = if ctf0 > 0 {
        1.0 / (2.0 * PI * ctf0 as f64 / 1e6)
    } else {
        m.thermal_resistance * m.thermal_capacity
    };
    FoldbackParams { continuous, peak, time_constant: time_constant.clamp(1e-3, 1e6) }
}

/// Handles of the foldback and limit objects.
#[derive(Debug, Clone, Default)]
pub struct Foldback {
    objects: usize,
    ifold: Option<EntryRef>,
    mifold: Option<EntryRef>,
    mi2t: Option<EntryRef>,
    mi2t_warn: Option<EntryRef>,
    warn: Option<EntryRef>,
    fault: Option<EntryRef>,
    fault_user: Option<EntryRef>,
    torque_limits: [Option<EntryRef>; 2],
}

fn word(od: &ObjectDictionary, r: Option<EntryRef>) -> u64 {
    r.map_or(0, |r| od.word(r))
}

#[inline(always)]
fn put(od: &mut ObjectDictionary, r: Option<EntryRef>, v: u32) {
    if let Some(r) = r
        && !od.set_low(r, u64::from(v), 4)
    {
        let n = od.bytes(r).len().min(4);
        od.set_raw(r, &v.to_le_bytes()[..n]);
    }
}

impl Foldback {
    /// After every step: the foldback readings, warning n304, fault F304,
    /// AKD 60E0h/60E1h.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, status: &mut Status) {
        if self.objects != od.objects().len() {
            let f = |i: u16, s: u8| od.find(i, s).ok();
            *self = Foldback {
                objects: od.objects().len(),
                ifold: f(0x3425, 0),
                mifold: f(0x35A4, 0),
                mi2t: f(0x3427, 3),
                mi2t_warn: f(0x3427, 2),
                warn: f(0x355A, 0),
                fault: f(0x3420, 0),
                fault_user: f(0x3421, 0),
                torque_limits: [f(0x60E0, 0), f(0x60E1, 0)],
            };
        }
        let model = cx.drive.model();
        let Some(ifold) = model.foldback_current() else { return };
        let continuous = cx.drive.config().params.motor.rated_current;
        let i2t = model.foldback_i2t().unwrap_or(0.0);
        let load = round(i2t / (continuous * continuous) * 100.0).clamp(0.0, 1e9) as u32;
        let ma = round(ifold * 1000.0) as u32;
        put(od, self.ifold, ma);
        put(od, self.mifold, ma);
        put(od, self.mi2t, load);
        let rated = cx.drive.config().params.motor.rated_current;
        let (ip, in_) = model.current_limits();
        for (r, i) in self.torque_limits.into_iter().zip([ip, in_]) {
            put(od, r, round(i / rated * 1000.0).clamp(0.0, 65535.0) as u32);
        }
        let warn_ma = word(od, self.warn) as u32 as i32;
        let warn_pct = word(od, self.mi2t_warn) as u32;
        let warning =
            (warn_ma > 0 && i64::from(ma) < i64::from(warn_ma)) || (warn_pct > 0 && load >= warn_pct);
        status.set(cx, od, Warning::MotorFoldback, warning);
        let fault = match word(od, self.fault_user) as u32 {
            0 => word(od, self.fault) as u32,
            u => u,
        };
        let state = cx.drive.state_machine().state();
        if fault > 0 && ma < fault && !matches!(state, State::Fault | State::FaultReactionActive) {
            cx.drive.inject(Injection::Fault(FOLDBACK_FAULT));
        }
    }
}
