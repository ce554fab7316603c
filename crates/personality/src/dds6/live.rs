//! The manufacturer values the DDS6 publishes every control period: the
//! digital inputs and outputs (§6.4.14, §6.4.15), the supply voltage
//! (§6.4.13) and the motor current (§6.4.20, §6.4.21). Handles resolved
//! once; the settings behind them cached when written (no search per step).

use super::io;
use drivebus_cia402::drive::Drive;
use drivebus_od::{EntryRef, ObjectDictionary};

/// Handles of the published values (again when objects were inserted).
#[derive(Debug, Clone, Copy)]
struct Refs {
    objects: usize,
    inputs: Option<EntryRef>,
    outputs: Option<EntryRef>,
    voltage: Option<EntryRef>,
    current: Option<EntryRef>,
}

impl Refs {
    fn resolve(od: &ObjectDictionary) -> Refs {
        Refs {
            objects: od.objects().len(),
            inputs: od.find(0x3210, 1).ok(),
            outputs: od.find(0x3230, 1).ok(),
            voltage: od.find(0x3140, 3).ok(),
            current: od.find(0x3312, 1).ok(),
        }
    }
}

/// The published values' state and settings.
#[derive(Debug, Clone, Default)]
pub(super) struct Live {
    refs: Option<Refs>,
    /// 2830h–2832h:01, the output sources.
    pub sources: [u16; 3],
    /// 3230h:01 bits of the outputs configured as General Purpose.
    pub general: u16,
    /// 2310h:08 Rated_Current_MTRDT \[10 mArms\].
    rated_current: u16,
    /// 3310h:02 / 03 Current_Min / Current_Max_MTRCNF \[0.01 %\].
    current_min: u16,
    current_max: u16,
    /// 3310h:04 Current_Idle_Delay_MTRCNF \[ms\].
    idle_delay_ms: u16,
    /// 23A0h:01 Mode_CRRG = 1: current proportional to the load.
    dynamic: bool,
    /// Time the motor has been at rest \[s\].
    rest_s: f64,
}

impl Live {
    /// Takes the settings from the dictionary (boot, a write of one of
    /// them, values restored).
    pub fn load(&mut self, od: &ObjectDictionary) {
        self.sources = [0u16, 1, 2].map(|n| od.get_u32(0x2830 + n, 1).unwrap_or(0) as u16);
        let get = |i: u16, s: u8, d: u32| od.get_u32(i, s).unwrap_or(d) as u16;
        self.rated_current = get(0x2310, 0x08, 100);
        self.current_min = get(0x3310, 2, 4000);
        self.current_max = get(0x3310, 3, 8000);
        self.idle_delay_ms = get(0x3310, 4, 500);
        self.dynamic = od.get_u32(0x23A0, 1) == Some(1);
    }

    /// The phase current \[10 mArms\] (§6.4.20): static, Current_Max while
    /// the motor turns and until Current_Idle_Delay after it stopped, then
    /// Current_Min; dynamic, between the two in proportion to the load; 0
    /// with the motor disabled.
    fn current(&mut self, drive: &Drive, enabled: bool, dt: f64) -> i16 {
        if !enabled {
            self.rest_s = 0.0;
            return 0;
        }
        let moving = drive.demand_velocity() != 0.0;
        self.rest_s = if moving { 0.0 } else { self.rest_s + dt };
        let (lo, hi) = (f64::from(self.current_min), f64::from(self.current_max));
        let percent = if self.dynamic {
            let m = &drive.model().params().motor;
            let rated = m.kt * m.rated_current;
            let load = if rated > 0.0 { (drive.model().torque().abs() / rated).min(1.0) } else { 0.0 };
            lo + (hi - lo) * load
        } else if moving || self.rest_s * 1000.0 < f64::from(self.idle_delay_ms) {
            hi
        } else {
            lo
        };
        (f64::from(self.rated_current) * percent / 10_000.0).round().clamp(0.0, 32767.0) as i16
    }

    /// Publishes 3210h:01, 3230h:01, 3140h:03 and 3312h:01 after a step
    /// (`sw` the statusword as shown, `dt` the control period).
    pub fn publish(&mut self, drive: &Drive, sw: u16, od: &mut ObjectDictionary, dt: f64) {
        let refs = match self.refs {
            Some(r) if r.objects == od.objects().len() => r,
            _ => *self.refs.insert(Refs::resolve(od)),
        };
        let di = io::inputs(drive.view().digital_inputs, 0);
        let v = drive.demand_velocity();
        let signals = io::Signals { statusword: sw, brake: false, positive: v > 0.0, negative: v < 0.0 };
        let out = io::outputs(self.sources, self.general, &signals);
        let enabled = matches!(sw & 0x6F, 0x27 | 0x07);
        let current = self.current(drive, enabled, dt);
        // §6.4.13: the power bus in 0.1 V.
        let volts = (drive.model().bus_voltage() * 10.0).round().clamp(0.0, 65535.0) as u16;
        let put = |od: &mut ObjectDictionary, r: Option<EntryRef>, b: &[u8]| {
            if let Some(r) = r {
                od.set_le(r, b);
            }
        };
        put(od, refs.inputs, &di.to_le_bytes());
        put(od, refs.outputs, &out.to_le_bytes());
        put(od, refs.voltage, &volts.to_le_bytes());
        put(od, refs.current, &current.to_le_bytes());
    }
}
