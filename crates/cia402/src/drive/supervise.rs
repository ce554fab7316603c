//! Supervision (following error, limit switches, software limits, SYNC
//! loss, injected faults: the faults a period raises) and the touch probe
//! (60B8h–60BDh).

use super::config::ProbeInput;
use super::control::{CYCLIC, code};
use super::mode::op;
use super::profile::Limits;
use super::{Drive, EmcyRequest};
use crate::model::{Event, EventKind};
use crate::state_machine::{DriveFunction, State};

/// Supervision flags and timers.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Supervision {
    /// Time the following error has been outside 6065h \[s\].
    pub fe_timer: f64,
    /// Statusword bit 13 (pp/csp): following error.
    pub fe_active: bool,
    /// Injected: treat the following error as outside the window.
    pub force_following_error: bool,
    /// Injected fault code, raised at the next period.
    pub pending_fault: Option<u16>,
    /// The node reported a SYNC timeout (cleared by the next SYNC).
    pub sync_lost: bool,
    /// Negative (−1) or positive (+1) limit switch blocks motion that way.
    pub limit_block: i8,
    /// Past the negative (−1) or positive (+1) software limit 607Dh
    /// ([`IoConfig::software_limit_switches`](super::IoConfig::software_limit_switches)).
    pub soft_limit: i8,
}

/// Where a touch probe takes its trigger from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    /// Touch probe input 1 or 2 (0, 1), wired per [`ProbeInput`].
    Input(usize),
    /// The encoder index (zero impulse).
    Index,
}

/// Touch probe function and captures (CiA 402-2 touch probe; ETG.6010 §5
/// coding of 60B8h/60B9h).
///
/// 60B8h per probe (probe 2 shifted by 8): bit 0 enable, bit 1 continuous
/// (0: first event only), bits 2–3 trigger (00 touch probe input — probe 1
/// uses touch probe input 1, probe 2 input 2, each wired per
/// [`IoConfig::probe_inputs`](super::IoConfig::probe_inputs); 01 encoder
/// index pulse; 10 the source in 60D0h:1/2 when the drive has that object;
/// 11 reserved, captures nothing), bit 4 capture rising edge, bit 5 capture
/// falling edge. 60B9h: bit 0 enabled, bit 1 rising edge stored, bit 2
/// falling edge stored (probe 2: bits 8–10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Probe {
    pub function: u16,
    pub status: u16,
    /// 60BAh, 60BBh, 60BCh, 60BDh.
    pub pos: [i32; 4],
    /// 60D0h:1/2 (1, 2 touch probe input 1/2, 5 / 6 hardware / software
    /// zero impulse; 0 none).
    pub source: [i16; 2],
    /// 60D0h honoured (trigger selection 10b).
    pub source_object: bool,
    /// The physical inputs behind touch probe input 1/2.
    inputs: [ProbeInput; 2],
    /// Dedicated inputs: level as set by the application, level as last
    /// sampled by the control period.
    dedicated: [bool; 2],
    dedicated_seen: [bool; 2],
}

impl Probe {
    /// Probes wired to `inputs`, 60D0h honoured when `source_object`.
    pub fn new(inputs: [ProbeInput; 2], source_object: bool) -> Probe {
        Probe { inputs, source_object, source: [1, 2], ..Probe::default() }
    }

    /// 60B8h written: enabling a probe (re)arms it, disabling clears it.
    pub fn configure(&mut self, f: u16) {
        for k in 0..2 {
            let sh = 8 * k;
            let en = f >> sh & 1 != 0;
            let was = self.function >> sh & 1 != 0;
            if en && !was {
                self.status = (self.status & !(0x7 << sh)) | 1 << sh;
            } else if !en {
                self.status &= !(0x7 << sh);
            }
        }
        self.function = f;
    }

    /// The trigger of enabled probe `k` (`None`: disabled or nothing).
    fn source_of(&self, k: usize) -> Option<Source> {
        let f = self.function >> (8 * k);
        if f & 1 == 0 {
            return None;
        }
        match (f >> 2) & 3 {
            0 => Some(Source::Input(k)),
            1 => Some(Source::Index),
            2 if self.source_object => match self.source[k] {
                1 => Some(Source::Input(0)),
                2 => Some(Source::Input(1)),
                5 | 6 => Some(Source::Index),
                _ => None,
            },
            _ => None,
        }
    }

    /// The model switch behind touch probe input `n` (`None`: dedicated).
    fn input_kind(&self, n: usize) -> Option<EventKind> {
        match self.inputs[n] {
            ProbeInput::HomeSwitch => Some(EventKind::Home),
            ProbeInput::PositiveLimit => Some(EventKind::PositiveLimit),
            ProbeInput::NegativeLimit => Some(EventKind::NegativeLimit),
            ProbeInput::Dedicated => None,
        }
    }

    /// Latches an edge; `pos` is the position \[position units\] at the event.
    pub fn on_event(&mut self, e: &Event, pos: i64) {
        for k in 0..2 {
            let hit = match self.source_of(k) {
                Some(Source::Index) => e.kind == EventKind::Index,
                Some(Source::Input(n)) => self.input_kind(n) == Some(e.kind),
                None => false,
            };
            if hit {
                // The index pulse has only a "rising" edge.
                self.latch(k, e.active, pos);
            }
        }
    }

    /// Sets dedicated input `n` (0, 1); out of range is ignored.
    pub fn set_dedicated(&mut self, n: usize, active: bool) {
        if let Some(l) = self.dedicated.get_mut(n) {
            *l = active;
        }
    }

    /// A dedicated input changed since the last sample.
    pub fn dedicated_pending(&self) -> bool {
        self.dedicated != self.dedicated_seen
    }

    /// Once per control period: edges of the dedicated inputs, latched at
    /// `pos` (the input is sampled at the control rate).
    pub fn sample_dedicated(&mut self, pos: i64) {
        for n in 0..2 {
            if self.dedicated[n] == self.dedicated_seen[n] {
                continue;
            }
            self.dedicated_seen[n] = self.dedicated[n];
            if self.inputs[n] != ProbeInput::Dedicated {
                continue;
            }
            let rising = self.dedicated[n];
            for k in 0..2 {
                if self.source_of(k) == Some(Source::Input(n)) {
                    self.latch(k, rising, pos);
                }
            }
        }
    }

    fn latch(&mut self, k: usize, rising: bool, pos: i64) {
        let sh = 8 * k;
        let f = self.function >> sh;
        let (en_bit, st_bit, slot) = if rising { (4, 1, 2 * k) } else { (5, 2, 2 * k + 1) };
        if f >> en_bit & 1 == 0 {
            return;
        }
        let continuous = f & 2 != 0;
        if !continuous && self.status >> (sh + st_bit) & 1 != 0 {
            return;
        }
        self.pos[slot] = pos as i32;
        self.status |= 1 << (sh + st_bit);
    }
}

impl Drive {
    /// Faults from the model, following error, limit switches, SYNC loss,
    /// injections (CiA 402-2 §6.2: transition 13, 603Fh, EMCY).
    pub(super) fn supervise(&mut self) {
        let mut fault = self.sup.pending_fault.take();
        if fault.is_none() {
            fault = self.model.faults().error_code();
        }
        // Following error (6065h/6066h) while position-controlled.
        let enabled = self.sm.drive_function() == DriveFunction::Enabled;
        let position_mode = matches!(self.mode, op::PP | op::HM | op::IP | op::CSP);
        // One owner per mode: a handler that supervises 6065h itself (csp)
        // is not second-guessed; only the injection still applies.
        let owned = position_mode && self.handler_owns_following_error();
        if enabled && position_mode {
            let fe = self.dem.pos - self.actual_pos_f();
            let w = self.params.following_error_window;
            let out = self.sup.force_following_error || (!owned && w != u32::MAX && fe.abs() > f64::from(w));
            if out {
                self.sup.fe_timer += self.dt;
                if self.sup.fe_timer * 1000.0 > f64::from(self.params.following_error_timeout) {
                    self.sup.fe_active = true;
                    fault = fault.or(Some(code::FOLLOWING_ERROR));
                }
            } else {
                self.sup.fe_timer = 0.0;
                self.sup.fe_active = false;
            }
        }
        // Interlock input (60FDh bit 3): while active the drive function
        // is kept off (disable voltage, CiA 402-2 §6.2 transition 9/10/7).
        if self.cfg.io.interlock
            && self.interlock
            && !matches!(self.sm.state(), State::SwitchOnDisabled | State::Fault | State::FaultReactionActive)
        {
            let out = self.sm.controlword(self.cw & 0x80);
            self.after_transition(out);
        }
        // Limit switches (60FDh bits 0/1). While homing they are the
        // method's reference signals (CiA 402-2 §6.6: methods 1, 2, 17, 18
        // search them), not a limit: no stop, no warning.
        let sw = self.model.switches();
        let homing = enabled && self.mode == op::HM;
        self.sup.limit_block = if homing || self.limit_switches_off {
            0
        } else if sw.negative_limit {
            -1
        } else if sw.positive_limit {
            1
        } else {
            0
        };
        // Software limits as limit switches (iPOS §4.3.2): a limit passed
        // moving towards it stops the motion like the switch does.
        // Once passed, the limit holds until a motion away from it (§4.3.2:
        // "the motor will stand still until a new command is given to
        // travel within the space defined by the limits").
        let soft = if homing || !self.cfg.io.software_limit_switches {
            0
        } else {
            match self.passed_soft_limit() {
                0 if self.dem.vel * f64::from(self.sup.soft_limit) >= 0.0 => self.sup.soft_limit,
                0 => 0,
                side => side,
            }
        };
        if soft != 0 && soft != self.sup.soft_limit && enabled && self.dem.vel * f64::from(soft) > 0.0 {
            self.limit_stop();
        }
        self.sup.soft_limit = soft;
        if self.sup.limit_block == 0 {
            self.sup.limit_block = soft;
        }
        self.limit_active = self.sup.limit_block != 0;
        self.warning = self.limit_active || self.sup.sync_lost;
        for i in 0..self.events.len() {
            let e = self.events.as_slice()[i];
            let toward = match e.kind {
                EventKind::NegativeLimit if e.active => self.dem.vel < 0.0,
                EventKind::PositiveLimit if e.active => self.dem.vel > 0.0,
                _ => false,
            };
            if toward && enabled && !homing && !self.limit_switches_off {
                match self.cfg.io.limit_switch {
                    super::LimitSwitchReaction::Fault => fault = fault.or(Some(code::LIMIT_SWITCH)),
                    super::LimitSwitchReaction::StopAndWarn => self.limit_stop(),
                }
            }
        }
        if enabled && self.sup.sync_lost && self.cfg.sync_loss_fault && CYCLIC.contains(&self.mode) {
            fault = fault.or(Some(code::SYNC_LOST));
        }
        if let Some(c) = fault
            && !matches!(self.sm.state(), State::Fault | State::FaultReactionActive)
        {
            match self.fault_action(c) {
                Some(a) => self.take_fault(c, a),
                None => {
                    let out = self.sm.fault(c);
                    self.after_transition(out);
                }
            }
        } else if fault.is_none()
            && let Some(c) = self.ignored_fault.take()
        {
            // The condition of a fault taken without action is gone.
            self.raised.retain(|r| *r != c);
            self.emcy.push(EmcyRequest::Clear(c));
        }
    }

    /// A fault with a personality's action (`Drive::set_fault_action`).
    pub(crate) fn take_fault(&mut self, c: u16, a: super::ErrorReaction) {
        match a {
            super::ErrorReaction::React(r) => {
                let out = self.sm.fault_with(c, r);
                self.after_transition(out);
            }
            super::ErrorReaction::Warning | super::ErrorReaction::QuickStop => {
                let stops =
                    a == super::ErrorReaction::QuickStop && self.sm.state() == State::OperationEnabled;
                // Each stop it causes is reported; a condition that stays
                // is reported once (until a fault reset).
                if stops || !self.raised.contains(&c) {
                    if !self.raised.contains(&c) {
                        self.raised.push(c);
                    }
                    self.emcy.push(EmcyRequest::Raise(c));
                }
                self.error_warning |= a == super::ErrorReaction::Warning;
                if stops {
                    self.sup.fe_timer = 0.0;
                    self.sup.force_following_error = false;
                    let out = self.sm.quick_stop();
                    self.after_transition(out);
                }
            }
            super::ErrorReaction::NoAction => {
                // Signalled once; the latch is cleared so that the fault
                // comes back only while its condition lasts.
                self.model.clear_faults();
                self.ignored_fault = Some(c);
                if c != code::GUARDING && !self.raised.contains(&c) {
                    self.raised.push(c);
                    self.emcy.push(EmcyRequest::Raise(c));
                }
            }
        }
    }

    /// −1 / +1 when the position actual value is below / above 607Dh
    /// (both 0: no limits, as for pp targets).
    pub(super) fn passed_soft_limit(&self) -> i8 {
        let (lo, hi) = self.params.software_limits;
        if lo == 0 && hi == 0 {
            return 0;
        }
        let p = self.position();
        if p < i64::from(lo) {
            -1
        } else if p > i64::from(hi) {
            1
        } else {
            0
        }
    }

    /// Limit switch reached moving towards it: stop on the quick-stop ramp.
    pub(super) fn limit_stop(&mut self) {
        if self.mode == op::PP {
            let d = self.units.acc_to_pos(f64::from(self.params.quick_stop_deceleration));
            let (p, v) = (self.dem.pos, self.dem.vel);
            let stop_at = p + v * v.abs() / (2.0 * d);
            let lim = Limits { velocity: v.abs().max(1.0), acceleration: d, deceleration: d };
            self.pp.target = stop_at;
            self.pp.buffered = None;
            self.pp.traj =
                super::profile::Trajectory::plan(p, v, stop_at, lim, super::profile::Shape::Linear);
            self.pp.s_curve = false;
            self.pp.t = 0.0;
            self.pp.moving = true;
        }
    }
}
