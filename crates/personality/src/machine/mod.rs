//! The machine around a drive: the axis it moves and what is mounted on
//! it — travel, limit switches, home switch, hard stops, the encoder's
//! index pulse, load and gear — its signals (digital and analog inputs,
//! a master encoder, a holding brake, the motor temperature: [`mod@io`])
//! and faults and input changes a test schedules on it.
//!
//! A drive on its own has no switches (`drivebus_cia402::model::AxisParams`
//! defaults to a bare shaft), so a master that starts a limit-switch
//! homing waits while the axis runs away. Every profile therefore has a
//! default machine ([`Machine::default_for`]) under which every homing
//! method it lists in 60E3h completes from any start position
//! (`tests/machine_homing.rs`); a machine file ([`MachineFile`], TOML,
//! `docs/machine.md`) changes it per node without recompiling.
//!
//! Positions are in *machine units*: [`Machine::feed`] of them per
//! revolution of the output shaft, which turns once per
//! [`Machine::gear_ratio`] motor revolutions. They are the plant's, not the
//! drive's: the drive still counts in its own position units (6064h).
//!
//! This module is the one place of the format: the types, the per-profile
//! defaults, the TOML file ([`mod@file`]) and the run-time fault schedule
//! ([`faults`]).

pub mod faults;
pub mod file;
pub mod io;

pub use faults::{Change, Fault, FaultKind, FaultSchedule, InForce, InputBase, Switch};
pub use file::{MachineFile, MachineFileError};
pub use io::{Brake, Input, InputChange, Io, MasterEncoder, Temperature};

use crate::Profile;
use core::f64::consts::PI;
use drivebus_cia402::drive::DriveConfig;
use drivebus_cia402::model::LoadTorque;

/// How a switch is wired. The drive shows the switch's logical state in
/// 60FDh either way; the wiring decides what a broken wire reads
/// ([`FaultKind::WireBreak`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Polarity {
    /// Normally open: the contact closes when the switch is actuated; a
    /// broken wire reads "not actuated".
    NormallyOpen,
    /// Normally closed (fail-safe, the usual wiring of limit switches): a
    /// broken wire reads "actuated".
    #[default]
    NormallyClosed,
}

/// The two limit switches: active at or beyond their positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimitSwitches {
    /// Negative limit switch, active at or below \[machine units\].
    pub negative: f64,
    /// Positive limit switch, active at or above \[machine units\].
    pub positive: f64,
    /// Wiring of both.
    pub polarity: Polarity,
    /// Differential travel \[machine units\]: an active switch releases
    /// only this far back inside its position.
    pub hysteresis: f64,
}

/// The home (reference) switch: active inside `[from, to]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomeSwitch {
    /// Lower edge \[machine units\].
    pub from: f64,
    /// Upper edge \[machine units\].
    pub to: f64,
    /// Wiring.
    pub polarity: Polarity,
}

/// Mechanical end stops: the axis cannot pass them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardStops {
    /// Negative stop \[machine units\].
    pub negative: f64,
    /// Positive stop \[machine units\].
    pub positive: f64,
}

/// What the motor moves besides its rotor, at the output shaft (reflected
/// to the motor by the gear ratio: inertia / i², friction / i, torque / i).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// Inertia at the output shaft \[kg·m²\] (a linear mass m on a feed of
    /// s metres per output revolution: m·(s/2π)²).
    pub inertia: f64,
    /// Viscous friction at the output shaft \[N·m·s/rad\].
    pub viscous_friction: f64,
    /// Coulomb (sliding) friction at the output shaft \[N·m\].
    pub coulomb_friction: f64,
    /// Constant torque at the output shaft \[N·m\] (gravity on a vertical
    /// axis; positive pushes towards positive positions).
    pub torque: f64,
}

/// The machine around one drive (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Machine units per output shaft revolution (360: degrees of a
    /// rotary axis; a screw's lead in mm for a linear one).
    pub feed: f64,
    /// Motor revolutions per output shaft revolution.
    pub gear_ratio: f64,
    /// Position at power-on \[machine units\].
    pub start: f64,
    /// Limit switches (`None`: none fitted).
    pub limits: Option<LimitSwitches>,
    /// Home switch (`None`: none fitted).
    pub home_switch: Option<HomeSwitch>,
    /// Hard stops (`None`: endless travel).
    pub hard_stops: Option<HardStops>,
    /// Angle of the encoder's index pulse on the motor shaft \[degrees\];
    /// one pulse per motor revolution.
    pub index_offset: f64,
    /// The load.
    pub load: Load,
    /// Digital and analog inputs, outputs wired back.
    pub io: Io,
    /// The master encoder input.
    pub master_encoder: MasterEncoder,
    /// The holding brake (`None`: none fitted).
    pub brake: Option<Brake>,
    /// Ambient and motor temperature.
    pub temperature: Temperature,
    /// Faults applied at run time.
    pub faults: Vec<Fault>,
    /// Input changes at run time (on the faults' schedule).
    pub inputs: Vec<InputChange>,
}

/// A machine that does not make sense: the key (as in the file) and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MachineError {
    /// Dotted key, e.g. `limits.positive`.
    pub key: String,
    /// What is wrong.
    pub reason: String,
    /// The other key of a pair in the wrong order (where a file that
    /// names only that one places the error).
    pub other: Option<String>,
}

impl core::fmt::Display for MachineError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.key, self.reason)
    }
}

impl std::error::Error for MachineError {}

fn err(key: &str, reason: impl Into<String>) -> MachineError {
    MachineError { key: key.into(), reason: reason.into(), other: None }
}

fn err2(key: &str, other: &str, reason: impl Into<String>) -> MachineError {
    MachineError { other: Some(other.into()), ..err(key, reason) }
}

/// Largest position, feed or ratio taken: far inside what the model
/// integrates without losing precision.
const MAX_ABS: f64 = 1e9;

fn finite(key: &str, v: f64) -> Result<(), MachineError> {
    if v.is_finite() && v.abs() <= MAX_ABS {
        Ok(())
    } else {
        Err(err(key, format!("{v} is not a number within ±1e9")))
    }
}

fn positive(key: &str, v: f64) -> Result<(), MachineError> {
    finite(key, v)?;
    if v > 0.0 { Ok(()) } else { Err(err(key, format!("{v} must be above 0"))) }
}

fn not_negative(key: &str, v: f64) -> Result<(), MachineError> {
    finite(key, v)?;
    if v >= 0.0 { Ok(()) } else { Err(err(key, format!("{v} must not be negative"))) }
}

/// One profile's machine, in motor revolutions `r` of its axis: the
/// negative limit switch `neg` r below the power-on position, the positive
/// one `pos` r above, the home switch over 0.5…1.5 r (its edges half a
/// revolution from the index pulses at whole revolutions, so no edge and
/// pulse coincide), hard stops 1.5 r beyond the limit switches.
fn layout(feed: f64, gear_ratio: f64, (neg, pos): (f64, f64), inertia: f64, coulomb: f64) -> Machine {
    let r = feed / gear_ratio;
    Machine {
        feed,
        gear_ratio,
        start: 0.0,
        limits: Some(LimitSwitches {
            negative: -neg * r,
            positive: pos * r,
            polarity: Polarity::NormallyClosed,
            hysteresis: 0.01 * r,
        }),
        home_switch: Some(HomeSwitch { from: 0.5 * r, to: 1.5 * r, polarity: Polarity::NormallyOpen }),
        hard_stops: Some(HardStops { negative: -(neg + 1.5) * r, positive: (pos + 1.5) * r }),
        index_offset: 0.0,
        load: Load { inertia, viscous_friction: 0.0, coulomb_friction: coulomb, torque: 0.0 },
        io: Io::default(),
        master_encoder: MasterEncoder::default(),
        brake: None,
        temperature: Temperature::default(),
        faults: Vec::new(),
        inputs: Vec::new(),
    }
}

impl Machine {
    /// The machine `profile` is served on unless a file says otherwise
    /// (`docs/machine.md` gives the figures and the reasons):
    ///
    /// * `kc1`, `akd`: a servo on a linear axis, ball screw of 10 mm lead
    ///   driven directly, 6 kg carriage (units mm);
    /// * `ipos`: a servo swivel axis through a 5:1 gearbox (units degrees
    ///   of the output);
    /// * `ssd630`: a servo rotary table through a 3:1 gearbox (degrees);
    /// * `dds6`: the stepper on a linear stage, 5 mm lead screw (mm);
    /// * `generic`: a servo turning a disc directly (degrees).
    ///
    /// Each has the limit switches some motor revolutions either side of
    /// the power-on position, a home switch between them (0.5…1.5
    /// revolutions), hard stops 1.5 revolutions beyond the switches and
    /// the index pulse once per motor revolution.
    pub fn default_for(profile: Profile) -> Machine {
        match profile {
            // 6 kg · (0.01 m / 2π)² ≈ 1.5e-5 kg·m²: matched to the rotor.
            // −45…+165 mm: room for the demo's ten-turn move and sine.
            Profile::Kc1 | Profile::Akd => layout(10.0, 1.0, (4.5, 16.5), 1.5e-5, 0.02),
            // 4e-4 kg·m² / 5² = 1.6e-5 at the motor; ±252° of the output.
            Profile::Ipos => layout(360.0, 5.0, (3.5, 3.5), 4.0e-4, 0.05),
            // 1.4e-4 kg·m² / 3² ≈ 1.6e-5 at the motor; ±420° of the table.
            Profile::Ssd630 => layout(360.0, 3.0, (3.5, 3.5), 1.4e-4, 0.03),
            // Screw and carriage as one inertia, the stepper's own figure;
            // −22.5…+42.5 mm.
            Profile::Dds6 => layout(5.0, 1.0, (4.5, 8.5), 3.0e-5, 0.01),
            // ±3.5 turns of the disc.
            Profile::Generic => layout(360.0, 1.0, (3.5, 3.5), 1.6e-5, 0.0),
        }
    }

    /// One motor revolution in machine units.
    pub fn units_per_motor_rev(&self) -> f64 {
        self.feed / self.gear_ratio
    }

    /// Checks every value and their order (limit switches inside the hard
    /// stops, the start between the hard stops, …).
    pub fn check(&self) -> Result<(), MachineError> {
        positive("feed", self.feed)?;
        positive("gear_ratio", self.gear_ratio)?;
        let r = self.units_per_motor_rev();
        if !(r.is_finite() && r > 1e-9) {
            return Err(err("gear_ratio", "feed / gear_ratio is not a usable revolution"));
        }
        finite("start", self.start)?;
        if let Some(l) = &self.limits {
            finite("limits.negative", l.negative)?;
            finite("limits.positive", l.positive)?;
            not_negative("limits.hysteresis", l.hysteresis)?;
            if l.negative >= l.positive {
                return Err(err2(
                    "limits.negative",
                    "limits.positive",
                    format!("{} must be below limits.positive ({})", l.negative, l.positive),
                ));
            }
            if 2.0 * l.hysteresis >= l.positive - l.negative {
                return Err(err(
                    "limits.hysteresis",
                    "must be less than half the travel between the switches",
                ));
            }
        }
        if let Some(h) = &self.home_switch {
            finite("home_switch.from", h.from)?;
            finite("home_switch.to", h.to)?;
            if h.from >= h.to {
                return Err(err(
                    "home_switch.from",
                    format!("{} must be below home_switch.to ({})", h.from, h.to),
                ));
            }
        }
        if let Some(s) = &self.hard_stops {
            finite("hard_stops.negative", s.negative)?;
            finite("hard_stops.positive", s.positive)?;
            if s.negative >= s.positive {
                return Err(err2(
                    "hard_stops.negative",
                    "hard_stops.positive",
                    format!("{} must be below hard_stops.positive ({})", s.negative, s.positive),
                ));
            }
            if !(s.negative..=s.positive).contains(&self.start) {
                let stop =
                    if self.start < s.negative { "hard_stops.negative" } else { "hard_stops.positive" };
                return Err(err2("start", stop, format!("{} is beyond a hard stop", self.start)));
            }
            if let Some(l) = &self.limits {
                // A switch behind its stop could never be reached.
                if l.negative <= s.negative {
                    return Err(err2(
                        "limits.negative",
                        "hard_stops.negative",
                        "must be inside hard_stops.negative",
                    ));
                }
                if l.positive >= s.positive {
                    return Err(err2(
                        "limits.positive",
                        "hard_stops.positive",
                        "must be inside hard_stops.positive",
                    ));
                }
            }
        }
        finite("index.offset", self.index_offset)?;
        not_negative("load.inertia", self.load.inertia)?;
        not_negative("load.viscous_friction", self.load.viscous_friction)?;
        not_negative("load.coulomb_friction", self.load.coulomb_friction)?;
        finite("load.torque", self.load.torque)?;
        for (i, f) in self.faults.iter().enumerate() {
            f.check().map_err(|e| err(&format!("faults[{i}].{}", e.key), e.reason))?;
        }
        self.check_io()
    }

    /// Puts the machine into a drive configuration (after the personality
    /// chose its motor and units): axis, switches, stops, index angle,
    /// load reflected to the motor shaft, inputs, brake, temperatures.
    pub fn apply(&self, cfg: &mut DriveConfig) {
        let i = self.gear_ratio;
        let p = &mut cfg.params;
        let a = &mut p.axis;
        a.feed_constant = self.feed;
        a.gear_ratio = i;
        a.initial_position = self.start;
        a.negative_limit = self.limits.map(|l| l.negative);
        a.positive_limit = self.limits.map(|l| l.positive);
        a.limit_hysteresis = self.limits.map_or(0.0, |l| l.hysteresis);
        a.home_switch = self.home_switch.map(|h| (h.from, h.to));
        a.negative_stop = self.hard_stops.map(|s| s.negative);
        a.positive_stop = self.hard_stops.map(|s| s.positive);
        a.load_inertia = self.load.inertia / (i * i);
        a.load = if self.load.torque == 0.0 {
            LoadTorque::None
        } else {
            LoadTorque::Constant(self.load.torque / i)
        };
        p.encoder.index_angle = (self.index_offset * PI / 180.0).rem_euclid(2.0 * PI);
        let m = &mut p.motor;
        m.viscous_friction += self.load.viscous_friction / (i * i);
        m.coulomb_friction += self.load.coulomb_friction / i;
        // Break-away at least the sliding friction (the model requires it).
        m.static_friction += self.load.coulomb_friction / i;
        self.apply_io(cfg);
    }

    /// The run-time schedule of [`Machine::faults`] and [`Machine::inputs`].
    pub fn fault_schedule(&self) -> FaultSchedule {
        FaultSchedule::with_inputs(
            self.faults.clone(),
            self.inputs.clone(),
            InputBase {
                digital_inputs: self.io.digital_inputs,
                analog_inputs: self.io.analog_inputs,
                master_velocity: self.master_encoder.velocity,
            },
            self.limits.map_or(Polarity::default(), |l| l.polarity),
            self.home_switch.map_or(Polarity::NormallyOpen, |h| h.polarity),
        )
    }
}

impl Default for Machine {
    /// The `generic` profile's machine ([`Machine::default_for`]).
    fn default() -> Self {
        Machine::default_for(Profile::Generic)
    }
}
