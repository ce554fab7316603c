//! What a model step reports: edge events with interpolated positions,
//! switch levels, fault flags, and the fault-injection inputs.

/// Kind of a per-step event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventKind {
    /// The encoder index (zero) pulse was passed.
    Index,
    /// Negative limit switch edge.
    NegativeLimit,
    /// Positive limit switch edge.
    PositiveLimit,
    /// Home switch edge.
    Home,
    /// The axis ran into a mechanical end stop (`active`: the positive one).
    HardStop,
    /// The motor stalled (servo: blocked at the stop or at the current limit;
    /// stepper: slipped, see [`super::DriveModel::lost_steps`]).
    Stall,
}

/// One event inside a step, located by linear interpolation of the motion
/// between the start and end of the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// What happened.
    pub kind: EventKind,
    /// Switch edges: the switch became active (`true`) or inactive. Index:
    /// always `true`. Hard stop: `true` for the positive stop.
    pub active: bool,
    /// Motor angle at the event \[rad\] (exact switch/index location).
    pub position: f64,
    /// Encoder reading at the event (what a touch-probe latch returns).
    pub counts: i64,
    /// Motion direction at the event: `true` = positive.
    pub positive_direction: bool,
    /// Fraction of the step at which it happened, in `[0, 1]`.
    pub fraction: f64,
}

const EMPTY: Event = Event {
    kind: EventKind::Index,
    active: false,
    position: 0.0,
    counts: 0,
    positive_direction: true,
    fraction: 0.0,
};

/// Capacity of [`StepEvents`]; switches cross at most once per step, so only
/// index pulses at more than several revolutions per step can overflow.
pub const MAX_EVENTS: usize = 12;

/// Events of one step in time order (fixed capacity, no allocation).
#[derive(Debug, Clone, PartialEq)]
pub struct StepEvents {
    buf: [Event; MAX_EVENTS],
    len: usize,
    index_crossings: u32,
}

impl Default for StepEvents {
    fn default() -> Self {
        StepEvents { buf: [EMPTY; MAX_EVENTS], len: 0, index_crossings: 0 }
    }
}

impl StepEvents {
    pub(crate) fn clear(&mut self) {
        self.len = 0;
        self.index_crossings = 0;
    }

    /// Inserts in time order; drops the event if full.
    pub(crate) fn push(&mut self, e: Event) {
        if e.kind == EventKind::Index {
            self.index_crossings = self.index_crossings.saturating_add(1);
        }
        if self.len == MAX_EVENTS {
            return;
        }
        let mut i = self.len;
        while i > 0 && self.buf[i - 1].fraction > e.fraction {
            self.buf[i] = self.buf[i - 1];
            i -= 1;
        }
        self.buf[i] = e;
        self.len += 1;
    }

    pub(crate) fn add_index_crossings(&mut self, n: u32) {
        self.index_crossings = self.index_crossings.saturating_add(n);
    }

    /// The events, earliest first.
    pub fn as_slice(&self) -> &[Event] {
        &self.buf[..self.len]
    }

    /// Iterates the events, earliest first.
    pub fn iter(&self) -> core::slice::Iter<'_, Event> {
        self.as_slice().iter()
    }

    /// Number of stored events.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no event happened.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Index pulses passed in this step (also those not stored).
    pub fn index_crossings(&self) -> u32 {
        self.index_crossings
    }

    /// First event of a kind.
    pub fn first(&self, kind: EventKind) -> Option<&Event> {
        self.iter().find(|e| e.kind == kind)
    }
}

/// One of the three switch inputs (60FDh bits 0–2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SwitchInput {
    /// Negative limit switch (bit 0).
    NegativeLimit = 0,
    /// Positive limit switch (bit 1).
    PositiveLimit = 1,
    /// Home switch (bit 2).
    Home = 2,
}

/// Switch levels after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Switches {
    /// Negative limit switch active.
    pub negative_limit: bool,
    /// Positive limit switch active.
    pub positive_limit: bool,
    /// Home switch active.
    pub home: bool,
}

impl Switches {
    /// Digital inputs 60FDh bits 0–2 (negative limit, positive limit, home).
    pub fn digital_inputs(&self) -> u32 {
        u32::from(self.negative_limit) | u32::from(self.positive_limit) << 1 | u32::from(self.home) << 2
    }
}

/// Latched fault flags of the power stage and motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Faults {
    /// Over-current (2310h).
    pub over_current: bool,
    /// DC link over-voltage (3210h).
    pub over_voltage: bool,
    /// DC link under-voltage (3220h).
    pub under_voltage: bool,
    /// Winding over-temperature (4310h).
    pub over_temperature: bool,
    /// Encoder / position sensor failure (7305h).
    pub encoder: bool,
}

impl Faults {
    /// Whether any flag is set.
    pub fn any(&self) -> bool {
        self.over_current || self.over_voltage || self.under_voltage || self.over_temperature || self.encoder
    }

    /// CiA 402 error code (603Fh / EMCY) of the most severe active fault.
    pub fn error_code(&self) -> Option<u16> {
        if self.over_current {
            Some(0x2310)
        } else if self.over_voltage {
            Some(0x3210)
        } else if self.under_voltage {
            Some(0x3220)
        } else if self.encoder {
            Some(0x7305)
        } else if self.over_temperature {
            Some(0x4310)
        } else {
            None
        }
    }
}

/// Fault injection inputs (test and demo scenarios).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModelInjection {
    /// Latch an over-current (2310h).
    OverCurrent,
    /// Force the winding over its temperature limit (4310h).
    OverTemperature,
    /// Force the bus above the over-voltage trip (3210h).
    BusOverVoltage,
    /// Force the bus below the under-voltage trip (3220h); the reduced
    /// voltage also limits the motor.
    BusUnderVoltage,
    /// Force the bus to a voltage \[V\], 0..=1e6 (`None` restores the supply
    /// model; an out-of-range value also does).
    BusVoltage(Option<f64>),
    /// The encoder stops counting (7305h); the reading freezes.
    EncoderFailure,
    /// Force a switch input to a level (`Some`: a limit switch tripped by
    /// an obstacle, a broken wire of a normally-closed switch reading
    /// active, one of a normally-open switch reading inactive) or give it
    /// back to the axis position (`None`). A level change shows as an edge
    /// at the present position in the next step.
    ForceSwitch(SwitchInput, Option<bool>),
    /// Add a load torque step \[Nm\] (replaces any earlier step; ignored
    /// beyond ±[`super::params::MAX_TORQUE`]).
    LoadTorqueStep(f64),
    /// Sets digital input `line` (1..=16; others are ignored) to `level`.
    DigitalInput {
        /// Input line, 1..=16.
        line: u8,
        /// High.
        level: bool,
    },
    /// Sets analog input `channel` (1..=4) to `volts` (ignored if not
    /// finite or beyond ±[`super::io::MAX_VOLTS`]).
    AnalogInput {
        /// Channel, 1..=4.
        channel: u8,
        /// Voltage \[V\].
        volts: f64,
    },
    /// The master encoder runs at this speed \[counts/s\] from now on
    /// (ignored beyond ±[`super::io::MAX_MASTER`]).
    MasterVelocity(f64),
    /// The master encoder jumps to this position \[counts\] (ignored
    /// beyond ±[`super::io::MAX_MASTER`]).
    MasterPosition(f64),
    /// Forces the motor temperature reading \[°C\] (`None`: back to the
    /// power-on reading, [`super::IoParams::motor_temperature`], usually
    /// the thermal model); above the motor's limit it trips 4310h.
    MotorTemperature(Option<f64>),
    /// Forces the holding brake engaged (`Some(true)`: stuck) or released
    /// (`Some(false)`: a manual release lever, a broken brake) whatever its
    /// command; `None` gives it back to the command.
    Brake(Option<bool>),
    /// Remove all forced conditions: faults, forced switches, the forced
    /// temperature (back to the power-on reading) and brake (latched flags stay until
    /// [`super::DriveModel::clear_faults`]; input levels and the master
    /// encoder are the plant's and stay).
    Clear,
}
