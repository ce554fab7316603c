//! The standard homing methods 1–14, 17–30, 33, 34, 35 and 37
//! (CiA 402-2 homing mode, "Homing methods", figures for methods 1–35; 37 from
//! CiA 402-2 v4 / ETG.6010 table 27 as the successor of 35).
//!
//! Every switch method reduces to one rule: find the *reference edge* of a
//! switch crossed in the *final direction*, then (methods 1–14) take the
//! first index pulse beyond it in that direction, or (17–30) the edge itself.
//! Crossing the reference edge the wrong way means the axis is on the far
//! side: reverse. Methods 7–14 / 23–30 also reverse once at the limit switch
//! ahead ("if the initial direction of movement leads away from the home
//! switch, the drive shall reverse on encountering the relevant limit
//! switch"); so do 3–6 / 19–22, which then also home on a home switch
//! that is active over part of the travel only (a cam: the reference is
//! the edge with the active side where the method expects it). Any other
//! limit switch, a hard stop or a stall is an error.

use super::method::{HomingContext, HomingError, HomingEvent, HomingMethod, MethodStep};
use crate::model::EventKind;

/// Which switch edge a method references.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    /// Methods 1/17: negative limit switch.
    NegativeLimit,
    /// Methods 2/18: positive limit switch.
    PositiveLimit,
    /// Methods 3–6 / 19–22: a home switch with one edge, active on the
    /// positive (3, 4) or negative (5, 6) side of it.
    StepHome {
        /// Active on the positive side of the edge.
        active_positive: bool,
    },
    /// Methods 7–14 / 23–30: a home switch active over part of the travel;
    /// the reference is its lower (negative) or upper (positive) edge.
    Momentary {
        /// The upper edge.
        upper: bool,
        /// Initial direction when the switch is inactive (7–10: positive).
        initial_positive: bool,
    },
    /// Methods 33/34: the next index pulse.
    IndexOnly,
    /// Methods 35/37: the current position.
    Current,
}

/// The rule for one method code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Spec {
    target: Target,
    /// Direction of the final crossing and of the index search.
    positive: bool,
    /// Home on the first index pulse after the edge (1–14, 33, 34).
    index: bool,
}

const fn momentary(upper: bool, initial_positive: bool, positive: bool) -> Spec {
    Spec { target: Target::Momentary { upper, initial_positive }, positive, index: true }
}

fn spec(code: i8) -> Option<Spec> {
    let step_home = |active_positive| Target::StepHome { active_positive };
    let s = |target, positive| Spec { target, positive, index: true };
    Some(match code {
        // 1: home = first index right of where NLS becomes inactive.
        1 => s(Target::NegativeLimit, true),
        2 => s(Target::PositiveLimit, false),
        // 3/4: switch active on the positive side; index left/right of the edge.
        3 => s(step_home(true), false),
        4 => s(step_home(true), true),
        // 5/6: switch active on the negative side; index right/left.
        5 => s(step_home(false), true),
        6 => s(step_home(false), false),
        // 7–10 start positive: left of lower, right of lower, left of
        // upper, right of upper edge.
        7 => momentary(false, true, false),
        8 => momentary(false, true, true),
        9 => momentary(true, true, false),
        10 => momentary(true, true, true),
        // 11–14 start negative, mirrors of 7–10.
        11 => momentary(true, false, true),
        12 => momentary(true, false, false),
        13 => momentary(false, false, true),
        14 => momentary(false, false, false),
        17..=30 => match spec(code - 16) {
            Some(s) => Spec { index: false, ..s },
            None => return None,
        },
        33 => s(Target::IndexOnly, false),
        34 => s(Target::IndexOnly, true),
        35 | 37 => Spec { target: Target::Current, positive: true, index: false },
        _ => return None,
    })
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// Looking for the reference edge.
    Search,
    /// Edge found at this position; looking for the index pulse beyond it.
    Index(f64),
}

/// One of the standard methods (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct StandardMethod {
    code: i8,
    spec: Spec,
    phase: Phase,
    /// Current travel direction.
    positive: bool,
    /// Zero-search (slow) speed in use.
    slow: bool,
    /// Already reversed at a limit switch (7–14, 23–30).
    reversed_at_limit: bool,
}

impl StandardMethod {
    /// All standard codes.
    pub const CODES: [i8; 32] = [
        1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29,
        30, 33, 34, 35, 37,
    ];

    /// The method for a standard code, `None` for any other code.
    pub fn new(code: i8) -> Option<Self> {
        let spec = spec(code)?;
        Some(StandardMethod {
            code,
            spec,
            phase: Phase::Search,
            positive: spec.positive,
            slow: false,
            reversed_at_limit: false,
        })
    }

    fn velocity(&self, ctx: &HomingContext<'_>) -> MethodStep {
        let v = if self.slow { ctx.config.zero_speed } else { ctx.config.switch_speed };
        MethodStep::Move(if self.positive { v } else { -v })
    }

    fn is_reference_edge(&self, e: &HomingEvent) -> bool {
        match self.spec.target {
            Target::NegativeLimit => e.kind == EventKind::NegativeLimit,
            Target::PositiveLimit => e.kind == EventKind::PositiveLimit,
            // The edge with the switch's active side where the method
            // expects it: the only edge of a step switch; on a cam switch
            // (active over part of the travel) the far edge is not it.
            Target::StepHome { active_positive } => {
                e.kind == EventKind::Home && (e.active == e.positive_direction) == active_positive
            }
            // Becoming active moving up, or inactive moving down, is the
            // lower edge.
            Target::Momentary { upper, .. } => {
                e.kind == EventKind::Home && (e.active != e.positive_direction) == upper
            }
            Target::IndexOnly | Target::Current => false,
        }
    }

    fn reverses_at_limit(&self) -> bool {
        // 3–6 / 19–22 too: CiA 402-2 says nothing of limit switches for
        // them; reversing once lets them home on a cam switch from its
        // inactive far side, where a step switch never leaves the axis.
        matches!(self.spec.target, Target::Momentary { .. } | Target::StepHome { .. })
    }

    /// Processes one event; `Some` ends the period's processing.
    fn on_event(&mut self, e: &HomingEvent) -> Option<MethodStep> {
        let limit = matches!(e.kind, EventKind::NegativeLimit | EventKind::PositiveLimit);
        let blocked = matches!(e.kind, EventKind::HardStop | EventKind::Stall);
        match self.phase {
            Phase::Search => {
                if blocked {
                    return Some(MethodStep::Failed(HomingError::SwitchNotFound));
                }
                if self.is_reference_edge(e) {
                    if e.positive_direction == self.spec.positive {
                        if !self.spec.index {
                            return Some(MethodStep::Found(e.position));
                        }
                        self.phase = Phase::Index(e.position);
                    }
                    // Wrong way across the edge: the reference lies behind.
                    self.positive = self.spec.positive;
                    self.slow = true;
                } else if limit && e.active {
                    let ahead = (e.kind == EventKind::PositiveLimit) == e.positive_direction;
                    if self.reverses_at_limit() && !self.reversed_at_limit && ahead {
                        self.reversed_at_limit = true;
                        self.positive = !e.positive_direction;
                    } else {
                        return Some(MethodStep::Failed(HomingError::UnexpectedLimitSwitch));
                    }
                }
                None
            }
            Phase::Index(edge) => {
                let beyond = if self.spec.positive { e.position > edge } else { e.position < edge };
                if e.kind == EventKind::Index && beyond {
                    Some(MethodStep::Found(e.position))
                } else if blocked {
                    Some(MethodStep::Failed(HomingError::IndexNotFound))
                } else if limit && e.active && !self.is_reference_edge(e) {
                    Some(MethodStep::Failed(HomingError::UnexpectedLimitSwitch))
                } else {
                    None
                }
            }
        }
    }
}

impl HomingMethod for StandardMethod {
    fn code(&self) -> i8 {
        self.code
    }

    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let sw = ctx.switches;
        self.phase = Phase::Search;
        self.reversed_at_limit = false;
        let (positive, slow) = match self.spec.target {
            Target::Current => return MethodStep::Found(ctx.position),
            Target::IndexOnly => {
                self.phase = Phase::Index(ctx.position);
                (self.spec.positive, true)
            }
            // On the limit switch: leave it in the final direction at once.
            Target::NegativeLimit => (sw.negative_limit, sw.negative_limit),
            Target::PositiveLimit => (!sw.positive_limit, sw.positive_limit),
            // 3–6: "the initial direction of movement shall be dependent on
            // the state of the home switch": towards its edge.
            Target::StepHome { active_positive } => (active_positive != sw.home, sw.home),
            // 7–14: on the switch, move towards the edge being sought.
            Target::Momentary { upper, initial_positive } => {
                if sw.home {
                    (upper, true)
                } else {
                    (initial_positive, false)
                }
            }
        };
        self.positive = positive;
        self.slow = slow;
        let ahead_active = if positive { sw.positive_limit } else { sw.negative_limit };
        let is_target = matches!(
            (self.spec.target, positive),
            (Target::NegativeLimit, false) | (Target::PositiveLimit, true)
        );
        if ahead_active && !is_target {
            if self.reverses_at_limit() {
                // Already on the limit switch ahead: this is the one reversal.
                self.reversed_at_limit = true;
                self.positive = !positive;
            } else {
                return MethodStep::Failed(HomingError::UnexpectedLimitSwitch);
            }
        }
        self.velocity(ctx)
    }

    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        for e in ctx.events {
            if let Some(step) = self.on_event(e) {
                return step;
            }
        }
        if let Phase::Index(edge) = self.phase {
            // An index pulse comes once per revolution: beyond that it is missing.
            if (ctx.position - edge).abs() > 1.1 * ctx.config.units_per_rev {
                return MethodStep::Failed(HomingError::IndexNotFound);
            }
        }
        self.velocity(ctx)
    }
}
