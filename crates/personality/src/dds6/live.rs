//! The manufacturer values the DDS6 publishes every control period: the
//! digital inputs and outputs (§6.4.14, §6.4.15), the analog inputs
//! (§6.4.16, §6.4.17), the supply voltage (§6.4.13), the motor current
//! (§6.4.20, §6.4.21) and the holding brake (§4.3, §6.4.22). Handles
//! resolved once; the settings behind them cached when written (no search
//! per step).
//!
//! The machine's lines: DI2..DI7 are its digital input lines 2..7 (the
//! limit and home switches besides, on DI7 / DI6 / DI5 as 2810h's defaults
//! wire them), DO0..DO2 its output lines 1..3, AI0 / AI1 its analog
//! channels 1 / 2.

use super::brake::HoldingBrakeControl;
use super::io;
use drivebus_cia402::drive::Drive;
use drivebus_cia402::drive::units::round;
use drivebus_od::{EntryRef, ObjectDictionary};

/// Handles of the published values (again when objects were inserted).
#[derive(Debug, Clone, Copy)]
struct Refs {
    objects: usize,
    inputs: Option<EntryRef>,
    outputs: Option<EntryRef>,
    voltage: Option<EntryRef>,
    current: Option<EntryRef>,
    analog: [Option<EntryRef>; 2],
    brake: Option<EntryRef>,
}

impl Refs {
    fn resolve(od: &ObjectDictionary) -> Refs {
        Refs {
            objects: od.objects().len(),
            inputs: od.find(0x3210, 1).ok(),
            outputs: od.find(0x3230, 1).ok(),
            voltage: od.find(0x3140, 3).ok(),
            current: od.find(0x3312, 1).ok(),
            analog: [od.find(0x3250, 1).ok(), od.find(0x3251, 1).ok()],
            brake: od.find(0x3360, 2).ok(),
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
    /// 2810h:02 Fault_Reset_DIA.
    fault_reset_input: u16,
    /// 3210h:01 at the last step.
    inputs_were: u16,
    /// The fault-reset input fired (taken by the behaviour).
    fault_reset: bool,
    /// The holding brake.
    pub brake: HoldingBrakeControl,
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
        self.fault_reset_input = get(0x2810, 2, 0x0502);
        let b = &mut self.brake;
        b.option = get(0x2360, 1, 0);
        b.application_ms = get(0x2360, 2, 200);
        b.release_ms = get(0x2360, 3, 200);
        b.input = get(0x2810, 0x0A, 0);
        b.control = get(0x3360, 1, 0) as u8;
    }

    /// Whether the fault-reset input (2810h:02) fired since the last call.
    pub fn take_fault_reset(&mut self) -> bool {
        core::mem::take(&mut self.fault_reset)
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
        round(f64::from(self.rated_current) * percent / 10_000.0).clamp(0.0, 32767.0) as i16
    }

    /// Publishes 3210h:01, 3230h:01, 3250h/3251h:01, 3140h:03, 3312h:01
    /// and 3360h:02 after a step and sets the output lines and the brake
    /// (`sw` the statusword as shown, `enabling` the motor enabling
    /// sequence runs, `dt` the control period).
    pub fn publish(
        &mut self,
        drive: &mut Drive,
        sw: u16,
        enabling: bool,
        od: &mut ObjectDictionary,
        dt: f64,
    ) {
        let refs = match self.refs {
            Some(r) if r.objects == od.objects().len() => r,
            _ => *self.refs.insert(Refs::resolve(od)),
        };
        // Line n (bit n − 1) is DIn (bit n).
        let di = io::inputs(drive.view().digital_inputs, drive.model().digital_inputs() << 1);
        self.fault_reset |= io::edge_fired(self.fault_reset_input, self.inputs_were, di);
        self.inputs_were = di;
        let enabled = matches!(sw & 0x6F, 0x27 | 0x07);
        let running =
            drive.state_machine().drive_function() == drivebus_cia402::state_machine::DriveFunction::Enabled;
        let control = self.brake.step(enabled || enabling, running, di, dt);
        if drive.brake_control() != control {
            drive.set_brake_control(control);
        }
        let v = drive.demand_velocity();
        let signals = io::OutputConditions {
            statusword: sw,
            brake: self.brake.output(),
            positive: v > 0.0,
            negative: v < 0.0,
        };
        let out = io::outputs(self.sources, self.general, &signals);
        if drive.output_lines() & 0b111 != out {
            drive.set_output_lines(out);
        }
        let current = self.current(drive, enabled, dt);
        // §6.4.13: the power bus in 0.1 V.
        let volts = round(drive.model().bus_voltage() * 10.0).clamp(0.0, 65535.0) as u16;
        let put = |od: &mut ObjectDictionary, r: Option<EntryRef>, b: &[u8]| {
            if let Some(r) = r {
                od.set_le(r, b);
            }
        };
        put(od, refs.inputs, &di.to_le_bytes());
        put(od, refs.outputs, &out.to_le_bytes());
        put(od, refs.voltage, &volts.to_le_bytes());
        put(od, refs.current, &current.to_le_bytes());
        for (k, r) in refs.analog.into_iter().enumerate() {
            // §6.4.16/17: mV.
            let mv = round(drive.model().analog_input(k as u8 + 1) * 1000.0).clamp(-32768.0, 32767.0) as i16;
            put(od, r, &mv.to_le_bytes());
        }
        put(od, refs.brake, &[self.brake.status()]);
    }
}
