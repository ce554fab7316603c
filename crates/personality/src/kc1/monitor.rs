//! The parameter mirrors of the drive's measurements and their limits
//! (KC1 §8.1.3, AKD §7.1.4 object tables): PL.ERR 35C5h, VL.FB 3618h,
//! VBUS.VALUE 361Ah, MOTOR.TEMP 3612h, IL.FB 3558h, FB1.MECHPOS 35D2h,
//! AIN.VALUE 3509h/3470h:4 (analog input 1, through the AIN.CUTOFF 5000h
//! low-pass), AOUT.VALUE 3470h:2 (the
//! analog output AOUT.VALUEU 3470h:3 sets), VL.FBFILTER 3407h:1 (the
//! speed through a 10 Hz low-pass), DRV.HANDWHEEL 2050h and AKD
//! 60E4h:1 (the master encoder as secondary feedback), DRV.TEMPERATURES
//! 3610h (the ambient), REGEN.POWER 3416h (the braking resistor's power)
//! read
//! what the model measures; VL.THRESH 3627h (overspeed, F302),
//! MOTOR.TEMPWARN 3453h (n301) and MOTOR.TEMPFAULT 3586h (F301) act on
//! them, VBUS.UVFTHRESH 361Dh (F502) on the DC bus (0 = off).

use super::status::{Status, Warning};
use crate::build::Context;
use drivebus_cia402::drive::Injection;
use drivebus_cia402::drive::units::round;
use drivebus_cia402::state_machine::State;
use drivebus_od::{EntryRef, ObjectDictionary};

/// KC1 §7.1 / AKD §6.1: F302 over speed.
const OVERSPEED: u16 = 0x8480;
/// KC1 §7.1 / AKD §6.1: F301 motor overheat.
const MOTOR_OVERHEAT: u16 = 0x7180;
/// KC1 §7.1 / AKD §6.1: F502 DC bus under-voltage.
const UNDER_VOLTAGE: u16 = 0x3220;

#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    pl_err: Option<EntryRef>,
    vl_fb: Option<EntryRef>,
    vbus: Option<EntryRef>,
    temp: Option<EntryRef>,
    il_fb: Option<EntryRef>,
    mechpos: Option<EntryRef>,
    overspeed: Option<EntryRef>,
    temp_warn: Option<EntryRef>,
    temp_fault: Option<EntryRef>,
    uv_fault: Option<EntryRef>,
    ain: [Option<EntryRef>; 2],
    handwheel: Option<EntryRef>,
    ambient: Option<EntryRef>,
    /// 60E4h:1, and its factors 60E8h:1, 60EDh:1, 60E9h:1, 60EEh:1, FB2.ENCRES.
    additional: Option<EntryRef>,
    factors: [Option<EntryRef>; 5],
    current: Option<EntryRef>,
    velocity: Option<EntryRef>,
    fb_filter: Option<EntryRef>,
    aout: Option<EntryRef>,
    ain_cutoff: Option<EntryRef>,
    regen: Option<EntryRef>,
}

/// The measurement mirrors and their limits.
#[derive(Debug, Clone, Default)]
pub struct Monitor {
    refs: Refs,
    /// VL.FBFILTER's state \[rpm\] and the time of the last update \[ns\].
    fb_filter: (f64, u64),
    /// The analog input 1 through AIN.CUTOFF \[V\].
    ain: f64,
}

fn word(od: &ObjectDictionary, r: Option<EntryRef>) -> u64 {
    r.map_or(0, |r| od.word(r))
}

/// Stores `v` as an INTEGER32 cut to the entry's size (at most 4 bytes).
#[inline(always)]
fn put(od: &mut ObjectDictionary, r: Option<EntryRef>, v: i64) {
    if let Some(r) = r
        && !od.set_low(r, u64::from(v as i32 as u32), 4)
    {
        let n = od.bytes(r).len().min(4);
        od.set_raw(r, &(v as i32).to_le_bytes()[..n]);
    }
}

impl Monitor {
    fn resolve(od: &ObjectDictionary) -> Refs {
        let f = |i: u16| od.find(i, 0).ok();
        Refs {
            objects: od.objects().len(),
            pl_err: f(0x35C5),
            vl_fb: f(0x3618),
            vbus: f(0x361A),
            temp: f(0x3612),
            il_fb: f(0x3558),
            mechpos: f(0x35D2),
            overspeed: f(0x3627),
            temp_warn: f(0x3453),
            temp_fault: f(0x3586),
            uv_fault: f(0x361D),
            ain: [f(0x3509), od.find(0x3470, 4).ok()],
            handwheel: f(0x2050),
            ambient: f(0x3610),
            additional: od.find(0x60E4, 1).ok(),
            factors: [
                od.find(0x60E8, 1).ok(),
                od.find(0x60ED, 1).ok(),
                od.find(0x60E9, 1).ok(),
                od.find(0x60EE, 1).ok(),
                f(0x51EC),
            ],
            current: f(0x2077),
            velocity: f(0x606C),
            fb_filter: od.find(0x3407, 1).ok(),
            aout: od.find(0x3470, 2).ok(),
            ain_cutoff: f(0x5000),
            regen: f(0x3416),
        }
    }

    /// After every step (after [`Status::update`], whose 2077h IL.FB
    /// mirrors): the mirrors, then the limits.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, status: &mut Status) {
        if self.refs.objects != od.objects().len() {
            self.refs = Self::resolve(od);
        }
        let r = &self.refs;
        let drive = &*cx.drive;
        let model = drive.model();
        let velocity = i64::from(word(od, r.velocity) as u32 as i32);
        let temp = model.temperature();
        let bus_mv = model.bus_voltage() * 1000.0;
        put(od, r.pl_err, round(drive.demand_position() - drive.position() as f64) as i64);
        put(od, r.vl_fb, velocity);
        // VL.FBFILTER 3407h:1 (rpm × 1000): the speed through a 10 Hz
        // first-order low-pass.
        let now = cx.now.as_nanos();
        let dt = now.saturating_sub(self.fb_filter.1) as f64 * 1e-9;
        self.fb_filter.1 = now;
        let rpm = model.velocity_measured() * 30.0 / core::f64::consts::PI;
        let k = -(-2.0 * core::f64::consts::PI * 10.0 * dt.min(1.0)).exp_m1();
        self.fb_filter.0 += (rpm - self.fb_filter.0) * k;
        put(od, r.fb_filter, round(self.fb_filter.0 * 1000.0).clamp(-2e9, 2e9) as i64);
        put(od, r.vbus, round(model.bus_voltage()) as i64);
        put(od, r.temp, round(temp) as i64);
        put(od, r.il_fb, i64::from(word(od, r.current) as u32 as i32));
        let per_rev = i64::from(drive.config().params.encoder.counts_per_rev).max(1);
        put(od, r.mechpos, drive.position_increments().rem_euclid(per_rev));
        // AIN.VALUE (mV, float scale 1000:1): the machine's analog input 1,
        // through a first-order low-pass at AIN.CUTOFF 5000h (Hz; 0: none).
        let cutoff = word(od, r.ain_cutoff) as u32;
        let raw = model.analog_input(1);
        self.ain = if cutoff == 0 {
            raw
        } else {
            let k = -(-2.0 * core::f64::consts::PI * f64::from(cutoff) * dt.min(1.0)).exp_m1();
            self.ain + (raw - self.ain) * k
        };
        let mv = round(self.ain * 1000.0).clamp(-32768.0, 32767.0) as i64;
        for a in r.ain {
            put(od, a, mv);
        }
        // AOUT.VALUE (mV): the analog output the machine sees.
        put(od, r.aout, round(model.analog_output() * 1000.0).clamp(-32768.0, 32767.0) as i64);
        // DRV.HANDWHEEL: the secondary feedback, the machine's master
        // encoder (counts); AKD 60E4h:1 its position in user units, as
        // 6064h through the factors 60E8h/60EDh (gear) and 60E9h/60EEh
        // (feed) (§6.5.4), one revolution = FB2.ENCRES counts (0: the
        // primary feedback's resolution).
        let master = model.master_position();
        put(od, r.handwheel, master);
        if r.additional.is_some() {
            let w = |k: usize| (word(od, r.factors[k]) as u32).max(1) as f64;
            let res = if word(od, r.factors[4]) == 0 { per_rev as f64 } else { w(4) };
            let pos = master as f64 / res * w(1) / w(0) * w(2) / w(3);
            put(od, r.additional, round(pos).clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i64);
        }
        put(od, r.ambient, round(model.params().motor.ambient_temperature) as i64);
        // REGEN.POWER (W): what the braking resistor dissipates.
        put(od, r.regen, round(model.regen_power()).clamp(0.0, 2e9) as i64);
        let state = drive.state_machine().state();
        let faulted = matches!(state, State::Fault | State::FaultReactionActive);
        let over = word(od, r.overspeed) as u32 as i32;
        if over > 0 && velocity.abs() > i64::from(over) && state == State::OperationEnabled {
            cx.drive.inject(Injection::Fault(OVERSPEED));
        }
        let warn = word(od, r.temp_warn) as u32;
        status.set(cx, od, Warning::MotorTemperature, warn > 0 && temp > f64::from(warn));
        let fault = word(od, r.temp_fault) as u32;
        if fault > 0 && temp > f64::from(fault) && !faulted {
            cx.drive.inject(Injection::Fault(MOTOR_OVERHEAT));
        }
        // VBUS.UVFTHRESH (mV, float scale 1000:1): below it with the power
        // stage on, F502.
        let uv = word(od, r.uv_fault) as u32;
        let powered = matches!(state, State::OperationEnabled | State::QuickStopActive);
        if uv > 0 && powered && bus_mv < f64::from(uv) {
            cx.drive.inject(Injection::Fault(UNDER_VOLTAGE));
        }
    }
}
