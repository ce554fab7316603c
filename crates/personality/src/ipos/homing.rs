//! The iPOS manufacturer homing methods on a mechanical limit (§6).

use drivebus_cia402::homing::{HomingContext, HomingMethod, MethodStep};
use drivebus_cia402::model::EventKind;

/// The iPOS homing methods on a mechanical limit (§6): −1 / −2 run into the
/// negative / positive limit, then reverse at 6099h:2 to the first index
/// pulse; −3 / −4 run into the limit, then travel |607Ch| back, and that
/// point reports 607Ch (so the limit is 0). The limit is detected when the
/// axis hits its end stop or stalls (the manual's current threshold
/// 207Bh/207Ch, or the control error of an open-loop stepper, is what such
/// a contact produces on the real drive).
#[derive(Debug, Clone, Copy)]
pub struct MechanicalLimitHoming {
    code: i8,
    /// Where the limit was met (position units), once met.
    limit: Option<f64>,
}

impl MechanicalLimitHoming {
    /// Method −1..−4; `None` otherwise.
    pub fn new(code: i8) -> Option<Self> {
        (-4..=-1).contains(&code).then_some(MechanicalLimitHoming { code, limit: None })
    }

    fn towards_positive(&self) -> bool {
        matches!(self.code, -2 | -4)
    }

    fn with_index(&self) -> bool {
        matches!(self.code, -1 | -2)
    }
}

impl HomingMethod for MechanicalLimitHoming {
    fn code(&self) -> i8 {
        self.code
    }

    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        self.limit = None;
        let v = ctx.config.switch_speed;
        MethodStep::Move(if self.towards_positive() { v } else { -v })
    }

    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let away = if self.towards_positive() { -1.0 } else { 1.0 };
        let slow = ctx.config.zero_speed * away;
        match self.limit {
            None => {
                if let Some(e) =
                    ctx.events.iter().find(|e| matches!(e.kind, EventKind::HardStop | EventKind::Stall))
                {
                    self.limit = Some(e.position);
                    return MethodStep::Move(slow);
                }
                let v = ctx.config.switch_speed;
                MethodStep::Move(if self.towards_positive() { v } else { -v })
            }
            Some(at) => {
                if self.with_index() {
                    if let Some(e) = ctx.events.iter().find(|e| e.kind == EventKind::Index) {
                        return MethodStep::Found(e.position);
                    }
                } else if (ctx.position - at).abs() >= ctx.config.home_offset.abs() {
                    return MethodStep::Found(ctx.position);
                }
                MethodStep::Move(slow)
            }
        }
    }
}
