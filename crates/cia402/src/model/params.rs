//! Parameters of the motor, power stage, encoder, axis and internal control
//! loops, with per-drive-type defaults and validation.
//!
//! Units are SI on the motor shaft (rad, rad/s, A, Nm, V, Ω, kg·m², °C);
//! axis positions (switches, stops) are in user *position units* and are
//! converted with the feed constant and gear ratio (CiA 402 6091h/6092h).

use core::f64::consts::PI;
use core::fmt;

/// Which physics the motor follows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotorKind {
    /// Brushless servo with an inner current loop (equivalent DC motor model).
    Servo,
    /// Hybrid stepper driven by a micro-stepping chopper.
    Stepper(StepperParams),
}

/// Hybrid stepper specifics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepperParams {
    /// Full steps per revolution (200 for a 1.8° motor); a multiple of 4
    /// (one electrical period = 4 full steps in two-phase drives).
    pub full_steps: u32,
    /// Micro-steps per full step.
    pub microsteps: u32,
    /// Holding torque at rated current \[Nm\] (peak of the torque–angle curve).
    pub holding_torque: f64,
    /// Phase inductance \[H\] (limits the current and torque at speed).
    pub inductance: f64,
    /// Closed loop: commutate from the encoder with at most 90° electrical
    /// load angle, so the motor cannot lose steps.
    pub closed_loop: bool,
}

/// Motor parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorParams {
    /// Servo or stepper physics.
    pub kind: MotorKind,
    /// Torque constant \[Nm/A\] (servo).
    pub kt: f64,
    /// Back-EMF constant \[V·s/rad\], referred to the DC bus (servo).
    pub ke: f64,
    /// Winding resistance \[Ω\] (terminal-equivalent; stepper: per phase).
    pub resistance: f64,
    /// Time constant of the closed current (torque) loop \[s\] (servo).
    pub current_time_constant: f64,
    /// Current limit \[A\] (servo: peak; stepper: rated phase current).
    pub max_current: f64,
    /// Continuous (rated) current \[A\].
    pub rated_current: f64,
    /// Over-current trip threshold \[A\] (2310h); above `max_current`.
    pub overcurrent_trip: f64,
    /// Rotor inertia \[kg·m²\].
    pub rotor_inertia: f64,
    /// Viscous friction \[Nm·s/rad\].
    pub viscous_friction: f64,
    /// Coulomb (sliding) friction \[Nm\].
    pub coulomb_friction: f64,
    /// Static friction (break-away torque) \[Nm\], ≥ Coulomb friction.
    pub static_friction: f64,
    /// Maximum motor speed \[rad/s\] (velocity command limit).
    pub max_speed: f64,
    /// Winding-to-ambient thermal resistance \[K/W\].
    pub thermal_resistance: f64,
    /// Winding thermal capacity \[J/K\].
    pub thermal_capacity: f64,
    /// Ambient temperature \[°C\].
    pub ambient_temperature: f64,
    /// Over-temperature threshold of the winding \[°C\] (4310h).
    pub max_temperature: f64,
}

/// DC link (bus) parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusParams {
    /// Nominal (rectified supply) voltage \[V\].
    pub nominal_voltage: f64,
    /// DC link capacitance \[F\]; 0 = stiff bus (no regen rise).
    pub capacitance: f64,
    /// Braking chopper switch-on voltage \[V\]; `None` = no braking resistor.
    pub brake_on_voltage: Option<f64>,
    /// Braking resistor \[Ω\].
    pub brake_resistance: f64,
    /// Over-voltage trip \[V\] (3210h).
    pub over_voltage: f64,
    /// Under-voltage trip \[V\] (3220h).
    pub under_voltage: f64,
}

/// Incremental encoder on the motor shaft.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderParams {
    /// Counts per motor revolution (e.g. 2^20 servo, 4000 stepper).
    pub counts_per_rev: u32,
    /// Angle of the index (zero) pulse within a revolution \[rad, 0..2π\].
    pub index_angle: f64,
}

/// Rotary or linear axis (affects only how positions are read).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisKind {
    /// Rotary output (position units e.g. degrees).
    Rotary,
    /// Linear output through a screw/belt (position units e.g. mm).
    Linear,
}

/// External load torque on the motor shaft (positive = positive direction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadTorque {
    /// No load.
    None,
    /// Constant torque \[Nm\], e.g. gravity on a vertical linear axis.
    Constant(f64),
    /// Unbalanced arm: `−peak · sin(θ_out − zero)`, θ_out the output angle
    /// \[rad\] (motor angle / gear ratio); hangs at `zero`.
    Pendulum {
        /// Peak torque at the motor \[Nm\].
        peak: f64,
        /// Output angle of the stable rest position \[rad\].
        zero: f64,
    },
    /// Spring towards `rest` (motor angle \[rad\]) with `stiffness` \[Nm/rad\].
    /// Integrated explicitly, so validation requires `√(k/J)·dt ≤ 0.5`.
    Spring {
        /// Stiffness at the motor shaft \[Nm/rad\].
        stiffness: f64,
        /// Rest position, motor angle \[rad\].
        rest: f64,
    },
}

/// Axis mechanics and switches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisParams {
    /// Rotary or linear.
    pub kind: AxisKind,
    /// Feed constant: position units per output (driving) shaft revolution.
    pub feed_constant: f64,
    /// Gear ratio: motor revolutions per output shaft revolution.
    pub gear_ratio: f64,
    /// Load inertia reflected to the motor shaft \[kg·m²\].
    pub load_inertia: f64,
    /// External load torque.
    pub load: LoadTorque,
    /// Negative limit switch, active at or below this position \[units\].
    pub negative_limit: Option<f64>,
    /// Positive limit switch, active at or above this position \[units\].
    pub positive_limit: Option<f64>,
    /// Hysteresis of both limit switches \[units\]: an active switch is
    /// released only this far back inside its edge (a real switch's
    /// differential travel), so an axis held at the edge does not make the
    /// input chatter. 0 = an ideal switch.
    pub limit_hysteresis: f64,
    /// Home switch, active inside `[a, b]` \[units\].
    pub home_switch: Option<(f64, f64)>,
    /// Negative mechanical end stop \[units\].
    pub negative_stop: Option<f64>,
    /// Positive mechanical end stop \[units\].
    pub positive_stop: Option<f64>,
    /// Position at power-on \[units\].
    pub initial_position: f64,
}

/// The drive's internal cascaded loops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlParams {
    /// Position loop proportional gain \[1/s\].
    pub position_kp: f64,
    /// Position loop integral gain \[1/s²\] (0 = P only).
    pub position_ki: f64,
    /// Velocity loop proportional gain \[A·s/rad\].
    pub velocity_kp: f64,
    /// Velocity loop integral gain \[A/rad\].
    pub velocity_ki: f64,
    /// Velocity measurement filter time constant \[s\] (0 = none).
    pub velocity_filter: f64,
    /// Share of the velocity feed-forward the position loop adds to its
    /// output (1 = all of it, 0 = none: the position error alone drives).
    pub velocity_feedforward: f64,
    /// Control (and simulation) rate \[Hz\], 4–16 kHz.
    pub control_rate_hz: f64,
}

/// Everything a [`super::DriveModel`] needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveParams {
    /// Motor.
    pub motor: MotorParams,
    /// DC link.
    pub bus: BusParams,
    /// Encoder.
    pub encoder: EncoderParams,
    /// Axis mechanics and switches.
    pub axis: AxisParams,
    /// Control loops.
    pub control: ControlParams,
    /// Inputs, outputs, master encoder, brake, temperature reading
    /// ([`super::io`]).
    pub io: super::IoParams,
}

/// A parameter that failed validation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamError {
    /// Dotted name of the offending field.
    pub field: &'static str,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid parameter {}: {}", self.field, self.reason)
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ParamError {}

const RPM: f64 = 2.0 * PI / 60.0;

impl AxisParams {
    /// A plain rotary axis in degrees, direct drive, no switches.
    pub fn rotary_degrees(load_inertia: f64) -> Self {
        AxisParams {
            kind: AxisKind::Rotary,
            feed_constant: 360.0,
            gear_ratio: 1.0,
            load_inertia,
            load: LoadTorque::None,
            negative_limit: None,
            positive_limit: None,
            limit_hysteresis: 0.0,
            home_switch: None,
            negative_stop: None,
            positive_stop: None,
            initial_position: 0.0,
        }
    }

    /// Inertia of a linear mass `mass` \[kg\] reflected to the motor when one
    /// motor revolution moves it by `metres_per_motor_rev`.
    pub fn reflected_mass_inertia(mass: f64, metres_per_motor_rev: f64) -> f64 {
        let r = metres_per_motor_rev / (2.0 * PI);
        mass * r * r
    }

    /// Position units per motor revolution.
    pub fn units_per_motor_rev(&self) -> f64 {
        self.feed_constant / self.gear_ratio
    }
}

impl MotorParams {
    /// Small servo, Kollmorgen-AKM2x-like: 0.64 Nm continuous (1.6 A),
    /// 2.56 Nm peak (6.4 A), 6000 rpm, 320 V bus.
    pub fn servo_small() -> Self {
        MotorParams {
            kind: MotorKind::Servo,
            kt: 0.4,
            ke: 0.4,
            resistance: 5.0,
            current_time_constant: 2.0e-4,
            max_current: 6.4,
            rated_current: 1.6,
            overcurrent_trip: 9.6,
            rotor_inertia: 1.6e-5,
            viscous_friction: 1.0e-5,
            coulomb_friction: 0.01,
            static_friction: 0.015,
            max_speed: 6000.0 * RPM,
            thermal_resistance: 7.0,
            thermal_capacity: 85.0,
            ambient_temperature: 25.0,
            max_temperature: 120.0,
        }
    }

    /// Medium servo, AKM4x-like: 3 Nm continuous (3 A), 9 Nm peak, 3000 rpm,
    /// 560 V bus.
    pub fn servo_medium() -> Self {
        MotorParams {
            kind: MotorKind::Servo,
            kt: 1.0,
            ke: 1.0,
            resistance: 2.0,
            current_time_constant: 3.0e-4,
            max_current: 9.0,
            rated_current: 3.0,
            overcurrent_trip: 13.5,
            rotor_inertia: 1.1e-4,
            viscous_friction: 5.0e-5,
            coulomb_friction: 0.04,
            static_friction: 0.06,
            max_speed: 3000.0 * RPM,
            thermal_resistance: 4.0,
            thermal_capacity: 300.0,
            ambient_temperature: 25.0,
            max_temperature: 120.0,
        }
    }

    /// NEMA 23 hybrid stepper: 1.2 Nm holding, 2.8 A, 200 steps × 16 µsteps,
    /// 48 V supply.
    pub fn stepper() -> Self {
        MotorParams {
            kind: MotorKind::Stepper(StepperParams {
                full_steps: 200,
                microsteps: 16,
                holding_torque: 1.2,
                inductance: 2.5e-3,
                closed_loop: false,
            }),
            kt: 1.2 / 2.8,
            ke: 0.0,
            resistance: 0.9,
            current_time_constant: 2.5e-3 / 0.9,
            max_current: 2.8,
            rated_current: 2.8,
            overcurrent_trip: 4.2,
            rotor_inertia: 3.0e-5,
            viscous_friction: 6.0e-3,
            coulomb_friction: 0.02,
            static_friction: 0.03,
            max_speed: 1500.0 * RPM,
            thermal_resistance: 3.0,
            thermal_capacity: 150.0,
            ambient_temperature: 25.0,
            max_temperature: 110.0,
        }
    }
}

impl DriveParams {
    /// Small servo ([`MotorParams::servo_small`]) on a matched rotary load,
    /// 2^20-count encoder, 8 kHz loops.
    pub fn servo_small() -> Self {
        DriveParams {
            motor: MotorParams::servo_small(),
            bus: BusParams {
                nominal_voltage: 320.0,
                capacitance: 470e-6,
                brake_on_voltage: Some(380.0),
                brake_resistance: 100.0,
                over_voltage: 420.0,
                under_voltage: 200.0,
            },
            encoder: EncoderParams { counts_per_rev: 1 << 20, index_angle: 0.0 },
            axis: AxisParams::rotary_degrees(1.6e-5),
            // Velocity loop ≈ 940 rad/s bandwidth on 3.2e-5 kg·m², PI zero
            // a quarter of that; position loop well inside.
            control: ControlParams {
                position_kp: 150.0,
                position_ki: 0.0,
                velocity_kp: 0.075,
                velocity_ki: 17.5,
                velocity_filter: 1.0e-4,
                velocity_feedforward: 1.0,
                control_rate_hz: 8000.0,
            },
            io: super::IoParams::default(),
        }
    }

    /// Medium servo ([`MotorParams::servo_medium`]), 2^20 counts, 8 kHz.
    pub fn servo_medium() -> Self {
        DriveParams {
            motor: MotorParams::servo_medium(),
            bus: BusParams {
                nominal_voltage: 560.0,
                capacitance: 1000e-6,
                brake_on_voltage: Some(680.0),
                brake_resistance: 60.0,
                over_voltage: 760.0,
                under_voltage: 350.0,
            },
            encoder: EncoderParams { counts_per_rev: 1 << 20, index_angle: 0.0 },
            axis: AxisParams::rotary_degrees(1.1e-4),
            control: ControlParams {
                position_kp: 120.0,
                position_ki: 0.0,
                velocity_kp: 0.154,
                velocity_ki: 27.0,
                velocity_filter: 1.0e-4,
                velocity_feedforward: 1.0,
                control_rate_hz: 8000.0,
            },
            io: super::IoParams::default(),
        }
    }

    /// Stepper ([`MotorParams::stepper`]) open loop with a 4000-count
    /// encoder for monitoring, 48 V, 4 kHz.
    pub fn stepper() -> Self {
        DriveParams {
            motor: MotorParams::stepper(),
            bus: BusParams {
                nominal_voltage: 48.0,
                capacitance: 0.0,
                brake_on_voltage: None,
                brake_resistance: 10.0,
                over_voltage: 60.0,
                under_voltage: 20.0,
            },
            encoder: EncoderParams { counts_per_rev: 4000, index_angle: 0.0 },
            axis: AxisParams::rotary_degrees(3.0e-5),
            control: ControlParams {
                position_kp: 0.0,
                position_ki: 0.0,
                velocity_kp: 0.0,
                velocity_ki: 0.0,
                velocity_filter: 0.0,
                velocity_feedforward: 1.0,
                control_rate_hz: 4000.0,
            },
            io: super::IoParams::default(),
        }
    }

    /// Control period \[s\] = 1 / control rate.
    pub fn control_period(&self) -> f64 {
        1.0 / self.control.control_rate_hz
    }

    /// Checks every field: finite, signs, orderings, ranges.
    pub fn validate(&self) -> Result<(), ParamError> {
        let m = &self.motor;
        // Physical ranges keep every product in the model far from overflow.
        range("motor.kt", m.kt, 1e-6, 1e3)?;
        range("motor.resistance", m.resistance, 1e-6, 1e6)?;
        range("motor.rotor_inertia", m.rotor_inertia, 1e-9, 1e3)?;
        range("motor.max_current", m.max_current, 1e-6, 1e5)?;
        range("motor.max_speed", m.max_speed, 1e-3, 1e5)?;
        range("motor.viscous_friction", m.viscous_friction, 0.0, 1e6)?;
        range("motor.static_friction", m.static_friction, 0.0, MAX_TORQUE)?;
        range("bus.nominal_voltage", self.bus.nominal_voltage, 1e-3, 1e6)?;
        range("axis.load_inertia", self.axis.load_inertia, 0.0, 1e3)?;
        pos("motor.kt", m.kt)?;
        nonneg("motor.ke", m.ke)?;
        pos("motor.resistance", m.resistance)?;
        pos("motor.current_time_constant", m.current_time_constant)?;
        pos("motor.max_current", m.max_current)?;
        pos("motor.rated_current", m.rated_current)?;
        check("motor.rated_current", m.rated_current <= m.max_current, "must not exceed max_current")?;
        pos("motor.overcurrent_trip", m.overcurrent_trip)?;
        check("motor.overcurrent_trip", m.overcurrent_trip > m.max_current, "must exceed max_current")?;
        pos("motor.rotor_inertia", m.rotor_inertia)?;
        nonneg("motor.viscous_friction", m.viscous_friction)?;
        nonneg("motor.coulomb_friction", m.coulomb_friction)?;
        nonneg("motor.static_friction", m.static_friction)?;
        check(
            "motor.static_friction",
            m.static_friction >= m.coulomb_friction,
            "must be at least coulomb_friction",
        )?;
        pos("motor.max_speed", m.max_speed)?;
        pos("motor.thermal_resistance", m.thermal_resistance)?;
        pos("motor.thermal_capacity", m.thermal_capacity)?;
        finite("motor.ambient_temperature", m.ambient_temperature)?;
        finite("motor.max_temperature", m.max_temperature)?;
        check(
            "motor.max_temperature",
            m.max_temperature > m.ambient_temperature,
            "must exceed ambient_temperature",
        )?;
        if let MotorKind::Stepper(s) = m.kind {
            check(
                "motor.stepper.full_steps",
                s.full_steps >= 4 && s.full_steps % 4 == 0 && s.full_steps <= 100_000,
                "must be a multiple of 4 in 4..=100000",
            )?;
            check("motor.stepper.microsteps", (1..=1024).contains(&s.microsteps), "must be in 1..=1024")?;
            pos("motor.stepper.holding_torque", s.holding_torque)?;
            nonneg("motor.stepper.inductance", s.inductance)?;
        }
        let b = &self.bus;
        pos("bus.nominal_voltage", b.nominal_voltage)?;
        nonneg("bus.capacitance", b.capacitance)?;
        pos("bus.brake_resistance", b.brake_resistance)?;
        pos("bus.over_voltage", b.over_voltage)?;
        nonneg("bus.under_voltage", b.under_voltage)?;
        check(
            "bus.over_voltage",
            b.under_voltage < b.nominal_voltage && b.nominal_voltage < b.over_voltage,
            "need under_voltage < nominal_voltage < over_voltage",
        )?;
        if let Some(v) = b.brake_on_voltage {
            pos("bus.brake_on_voltage", v)?;
            check("bus.brake_on_voltage", v > b.nominal_voltage, "must exceed nominal_voltage")?;
        }
        let e = &self.encoder;
        check("encoder.counts_per_rev", (4..=(1 << 30)).contains(&e.counts_per_rev), "must be in 4..=2^30")?;
        finite("encoder.index_angle", e.index_angle)?;
        check("encoder.index_angle", (0.0..2.0 * PI).contains(&e.index_angle), "must be in [0, 2π)")?;
        let a = &self.axis;
        pos("axis.feed_constant", a.feed_constant)?;
        pos("axis.gear_ratio", a.gear_ratio)?;
        nonneg("axis.load_inertia", a.load_inertia)?;
        match a.load {
            LoadTorque::None => {}
            LoadTorque::Constant(t) => range("axis.load", t, -MAX_TORQUE, MAX_TORQUE)?,
            LoadTorque::Pendulum { peak, zero } => {
                range("axis.load.peak", peak, -MAX_TORQUE, MAX_TORQUE)?;
                range("axis.load.zero", zero, -1e6, 1e6)?;
            }
            LoadTorque::Spring { stiffness, rest } => {
                range("axis.load.stiffness", stiffness, 0.0, 1e6)?;
                range("axis.load.rest", rest, -1e12, 1e12)?;
            }
        }
        for (f, v) in [
            ("axis.negative_limit", a.negative_limit),
            ("axis.positive_limit", a.positive_limit),
            ("axis.negative_stop", a.negative_stop),
            ("axis.positive_stop", a.positive_stop),
        ] {
            if let Some(v) = v {
                finite(f, v)?;
            }
        }
        range("axis.limit_hysteresis", a.limit_hysteresis, 0.0, 1e12)?;
        if let Some((lo, hi)) = a.home_switch {
            finite("axis.home_switch", lo)?;
            finite("axis.home_switch", hi)?;
            check("axis.home_switch", lo <= hi, "need a <= b")?;
        }
        finite("axis.initial_position", a.initial_position)?;
        if let Some(n) = a.negative_stop {
            check("axis.initial_position", a.initial_position >= n, "beyond negative_stop")?;
        }
        if let Some(p) = a.positive_stop {
            check("axis.initial_position", a.initial_position <= p, "beyond positive_stop")?;
            if let Some(n) = a.negative_stop {
                check("axis.positive_stop", p > n, "must exceed negative_stop")?;
            }
        }
        self.io.validate()?;
        let c = &self.control;
        range("control.position_kp", c.position_kp, 0.0, 1e9)?;
        range("control.position_ki", c.position_ki, 0.0, 1e12)?;
        range("control.velocity_kp", c.velocity_kp, 0.0, 1e9)?;
        range("control.velocity_ki", c.velocity_ki, 0.0, 1e12)?;
        range("control.velocity_filter", c.velocity_filter, 0.0, 1.0)?;
        range("control.velocity_feedforward", c.velocity_feedforward, 0.0, 10.0)?;
        finite("control.control_rate_hz", c.control_rate_hz)?;
        check(
            "control.control_rate_hz",
            (4000.0..=16000.0).contains(&c.control_rate_hz),
            "must be in 4..=16 kHz",
        )?;
        // Position-dependent loads are explicit in the step: keep their
        // natural frequency well below the step rate (ω·dt ≤ 0.5).
        let stiffness = match a.load {
            LoadTorque::Spring { stiffness, .. } => stiffness,
            LoadTorque::Pendulum { peak, .. } => peak.abs() / a.gear_ratio,
            _ => 0.0,
        };
        let dt = 1.0 / c.control_rate_hz;
        check(
            "axis.load",
            stiffness * dt * dt <= 0.25 * (m.rotor_inertia + a.load_inertia),
            "too stiff for the control rate",
        )?;
        Ok(())
    }
}

/// Largest load torque accepted anywhere \[Nm\].
pub const MAX_TORQUE: f64 = 1e6;

fn range(field: &'static str, v: f64, lo: f64, hi: f64) -> Result<(), ParamError> {
    check(field, v.is_finite() && (lo..=hi).contains(&v), "out of the supported range")
}

fn check(field: &'static str, ok: bool, reason: &'static str) -> Result<(), ParamError> {
    if ok { Ok(()) } else { Err(ParamError { field, reason }) }
}

fn finite(field: &'static str, v: f64) -> Result<(), ParamError> {
    check(field, v.is_finite(), "must be finite")
}

fn pos(field: &'static str, v: f64) -> Result<(), ParamError> {
    check(field, v.is_finite() && v > 0.0, "must be finite and > 0")
}

fn nonneg(field: &'static str, v: f64) -> Result<(), ParamError> {
    check(field, v.is_finite() && v >= 0.0, "must be finite and >= 0")
}
