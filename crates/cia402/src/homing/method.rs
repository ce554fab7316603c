//! The pluggable homing-method interface and the method registry (6098h
//! values, 60E3h supported homing methods).

use alloc::boxed::Box;
use alloc::vec::Vec;

use super::standard::StandardMethod;
use crate::model::{EventKind, MAX_EVENTS, Switches};

/// A switch or index event seen by a homing method, in position units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomingEvent {
    /// What happened (index pulse, switch edge, hard stop, stall).
    pub kind: EventKind,
    /// Switch edges: the switch became active.
    pub active: bool,
    /// Position where it happened \[position units\].
    pub position: f64,
    /// Motion direction across it: `true` = positive.
    pub positive_direction: bool,
}

/// Events of one control period, earliest first (fixed capacity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomingEvents {
    buf: [HomingEvent; MAX_EVENTS],
    len: usize,
}

impl Default for HomingEvents {
    fn default() -> Self {
        let e =
            HomingEvent { kind: EventKind::Index, active: false, position: 0.0, positive_direction: true };
        HomingEvents { buf: [e; MAX_EVENTS], len: 0 }
    }
}

impl HomingEvents {
    /// Appends an event; dropped when full.
    pub fn push(&mut self, e: HomingEvent) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = e;
            self.len += 1;
        }
    }

    /// The events.
    pub fn as_slice(&self) -> &[HomingEvent] {
        &self.buf[..self.len]
    }
}

/// Motion parameters of a homing run, already converted to position units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomingConfig {
    /// 6098h homing method.
    pub method: i8,
    /// 6099h:1 speed during search for switch \[units/s\], > 0.
    pub switch_speed: f64,
    /// 6099h:2 speed during search for zero \[units/s\], > 0.
    pub zero_speed: f64,
    /// 609Ah homing acceleration \[units/s²\], > 0 (also the halt deceleration).
    pub acceleration: f64,
    /// 607Ch home offset \[units\]: the actual position given to the home
    /// position (CiA 402-2 homing mode, 607Ch "home offset").
    pub home_offset: f64,
    /// One motor revolution in position units: bounds the index-pulse search.
    pub units_per_rev: f64,
}

impl HomingConfig {
    /// Largest speed, acceleration or |home offset| accepted, keeping every
    /// integrated position far from overflow.
    pub const MAX_VALUE: f64 = 1e12;

    /// Whether speeds, acceleration and revolution length are usable
    /// (finite, > 0, ≤ [`Self::MAX_VALUE`]).
    pub fn is_valid(&self) -> bool {
        let p = |v: f64| v.is_finite() && v > 0.0 && v <= Self::MAX_VALUE;
        p(self.switch_speed)
            && p(self.zero_speed)
            && p(self.acceleration)
            && p(self.units_per_rev)
            && self.home_offset.abs() <= Self::MAX_VALUE
    }
}

/// What a homing method sees each control period.
#[derive(Debug, Clone, Copy)]
pub struct HomingContext<'a> {
    /// Homing parameters.
    pub config: &'a HomingConfig,
    /// Position actual \[units\] (measured, before homing's reset).
    pub position: f64,
    /// Velocity actual \[units/s\].
    pub velocity: f64,
    /// Switch levels after the last period.
    pub switches: Switches,
    /// Events of the last period, earliest first.
    pub events: &'a [HomingEvent],
    /// Torque actual \[per mille of rated torque\] (hard-stop methods).
    pub torque: f64,
}

/// Why homing failed (statusword bit 13).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomingError {
    /// 6098h names no registered method.
    UnsupportedMethod,
    /// Speeds or acceleration are zero or unusable.
    InvalidParameters,
    /// A limit switch the method does not use (or a second one) was hit.
    UnexpectedLimitSwitch,
    /// The axis hit a hard stop or stalled before the reference was found.
    SwitchNotFound,
    /// No index pulse within a revolution after the switch edge.
    IndexNotFound,
    /// A manufacturer-specific failure.
    Manufacturer(u16),
}

/// What a method asks for after looking at a period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MethodStep {
    /// Move (or keep moving) at this signed velocity \[units/s\], reached
    /// with the homing acceleration.
    Move(f64),
    /// Command this torque \[per mille of rated torque\] directly (e.g.
    /// hard-stop homing with a method-side current limit); the engine holds
    /// the position where the method returns to [`MethodStep::Move`].
    Torque(f64),
    /// The home position was found at `reference` \[units, actual-position
    /// frame before the reset\]; it becomes the home offset.
    Found(f64),
    /// Homing failed.
    Failed(HomingError),
}

/// A homing method (CiA 402-2 homing mode, object 6098h). Standard methods are
/// [`StandardMethod`]s; personalities register manufacturer methods
/// (negative codes) with [`HomingRegistry::register`].
pub trait HomingMethod {
    /// The 6098h code.
    fn code(&self) -> i8;
    /// Starts a run (rising edge of controlword bit 4); returns the first request.
    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep;
    /// One control period of the run.
    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep;
}

/// The methods a drive offers (60E3h lists their codes).
pub struct HomingRegistry {
    methods: Vec<Box<dyn HomingMethod + Send>>,
}

impl core::fmt::Debug for HomingRegistry {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list().entries(self.methods.iter().map(|m| m.code())).finish()
    }
}

impl HomingRegistry {
    /// No methods.
    pub fn empty() -> Self {
        HomingRegistry { methods: Vec::new() }
    }

    /// Every standard method: 1–14, 17–30, 33, 34, 35, 37.
    pub fn standard() -> Self {
        let mut r = Self::empty();
        for code in StandardMethod::CODES {
            if let Some(m) = StandardMethod::new(code) {
                r.register(Box::new(m));
            }
        }
        r
    }

    /// Adds a method, replacing one with the same code.
    pub fn register(&mut self, method: Box<dyn HomingMethod + Send>) {
        let code = method.code();
        self.methods.retain(|m| m.code() != code);
        self.methods.push(method);
    }

    /// Whether 6098h may take this value.
    pub fn is_supported(&self, code: i8) -> bool {
        self.methods.iter().any(|m| m.code() == code)
    }

    /// Supported codes in registration order (60E3h sub 1..n).
    pub fn codes(&self) -> impl Iterator<Item = i8> + '_ {
        self.methods.iter().map(|m| m.code())
    }

    pub(crate) fn get_mut(&mut self, code: i8) -> Option<&mut (dyn HomingMethod + Send)> {
        self.methods.iter_mut().find(|m| m.code() == code).map(|m| &mut **m as &mut (dyn HomingMethod + Send))
    }
}
