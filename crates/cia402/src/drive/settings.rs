//! The drive's run-time settings: fault injections, the inputs a machine
//! or a personality sets (interlock, limit switches, probes), scaling,
//! fault actions, jerk and ramps, and the manufacturer-mode stand-ins.

use super::*;

impl Drive {
    /// Applies a fault injection; faults show at the next control period.
    pub fn inject(&mut self, what: Injection) {
        match what {
            Injection::Model(i) => self.model.inject(i),
            Injection::FollowingError => self.sup.force_following_error = true,
            Injection::Fault(code) => self.sup.pending_fault = Some(code),
            Injection::ConnectionLost => self.connection_lost(0x8130),
        }
    }

    /// Physical digital outputs as set through 60FEh:1 (masked by 60FEh:2;
    /// bit 0 "set brake", bits 16–31 the output lines with
    /// [`IoConfig::output_lines`], see [`Drive::output_lines`]).
    pub fn digital_outputs(&self) -> u32 {
        self.extra.outputs
    }

    /// Sets the interlock input (60FDh bit 3). With
    /// [`IoConfig::interlock`] an active interlock disables the voltage and
    /// keeps the drive in Switch on disabled.
    pub fn set_interlock(&mut self, active: bool) {
        self.interlock = active;
    }

    /// Switches the limit-switch function off or on again: off, an active
    /// 60FDh bit 0/1 neither stops the motor nor sets statusword bits 7/11
    /// (e.g. Technosoft iPOS 60B8h bit 6, which frees the limit inputs for
    /// the touch probes). On by default.
    pub fn set_limit_switches(&mut self, on: bool) {
        self.limit_switches_off = !on;
    }

    /// Puts direct scaling objects in force ([`FactorGroup::scaling`], e.g.
    /// Technosoft iPOS 6093h/6094h/210Fh), or the CiA 402-2 chain again
    /// (`None`); the position stays where it is. `false` (nothing changed)
    /// if a term is 0 or the units would not be exact.
    pub fn set_scaling(&mut self, scaling: Option<Scaling>) -> bool {
        let f = FactorGroup { scaling, ..self.factor };
        if Units::new(&f).is_none() {
            return false;
        }
        if f != self.factor {
            self.factor = f;
            self.retune_units();
        }
        true
    }

    /// Homing ends without setting the position to the home offset: the
    /// counter keeps its value and a return-to-home goes back to the point
    /// found (Technosoft iPOS 210Bh bit 12). Applies from the next homing.
    pub fn set_homing_keeps_position(&mut self, on: bool) {
        self.params.homing_keeps_position = on;
    }

    /// What a fault with `code` does from now on instead of 605Eh's (and,
    /// for a lost connection with 6007h = 1, instead of its fault); `None`
    /// goes back to 605Eh.
    pub fn set_fault_action(&mut self, code: u16, action: Option<ErrorReaction>) {
        self.fault_actions.retain(|(c, _)| *c != code);
        if let Some(a) = action {
            self.fault_actions.push((code, a));
        }
    }

    /// The fault taken with [`ErrorReaction::NoAction`] whose condition still
    /// lasts, if any.
    pub fn ignored_fault(&self) -> Option<u16> {
        self.ignored_fault
    }

    /// The action for a fault with `code`, if a personality set one.
    pub(crate) fn fault_action(&self, code: u16) -> Option<ErrorReaction> {
        self.fault_actions.iter().find(|(c, _)| *c == code).map(|(_, a)| *a)
    }

    /// How pp reaches a target on a modulo axis (60F2h bits 7–6, e.g. the
    /// Technosoft iPOS's 60F2h); the shortest way until set.
    pub fn set_positioning_option(&mut self, code: u16) {
        self.rado = pp::Rado::from_option_code(code);
    }

    /// Sets position actual internal value (6063h) to `increments` where
    /// the axis stands (e.g. Technosoft iPOS 2081h): the reference shifts,
    /// the demand moves with it, nothing moves (a mode handler's mode is
    /// entered again from the new position).
    pub fn set_position_increments(&mut self, increments: i64) {
        let delta = increments.saturating_sub(self.position_increments());
        self.inc_offset = self.inc_offset.saturating_add(delta);
        self.inc_frac = 0;
        let d = self.units.inc_to_pos_f(delta as f64);
        self.dem.pos += d;
        self.pp.reset(self.dem.pos);
        // A mode handler holds a position of the old coordinates: it
        // starts again from here.
        if self.mode_active {
            self.exit_mode();
            self.enter_mode(false);
        }
    }

    /// Sets the jerk of the jerk-limited ramp (6086h = 3), e.g. from a
    /// manufacturer object: a [`ProfileJerk::Time`] (Technosoft iPOS 2023h
    /// jerk time) follows later 6083h/6084h changes; a [`ProfileJerk::Rate`]
    /// is also shown in 60A4h:1/2 when the drive has that object (a time
    /// stays in force until 60A4h is written). Takes effect at the next
    /// planned move. Rates of 0 or a time of 0 run the linear ramp.
    pub fn set_profile_jerk(&mut self, od: &mut ObjectDictionary, jerk: ProfileJerk) {
        self.jerk = jerk;
        if let ProfileJerk::Rate { acceleration, deceleration } = jerk
            && self.cfg.profile_jerk_object
        {
            for (sub, v) in [(1u8, acceleration), (2, deceleration)] {
                if let Ok(r) = od.find(0x60A4, sub) {
                    od.set_le(r, &v.to_le_bytes());
                }
            }
        }
    }

    /// Changes the drive's own ramps ([`ZeroRamp`], what a 0 in 6083h,
    /// 6084h or 609Ah selects), e.g. from a manufacturer parameter
    /// (Kollmorgen DRV.ACC). Takes effect at the next write or reload of
    /// those objects.
    pub fn set_zero_ramp(&mut self, ramp: ZeroRamp) {
        self.cfg.zero_ramp = ramp;
    }

    /// The jerk of the jerk-limited ramp in force.
    pub fn profile_jerk(&self) -> ProfileJerk {
        self.jerk
    }

    /// Drives the dedicated touch probe input `probe` (0: touch probe 1,
    /// 1: touch probe 2) of a probe wired to [`ProbeInput::Dedicated`]
    /// ([`IoConfig::probe_inputs`]). An edge is latched at the actual
    /// position of the next control period (the input is sampled at the
    /// control rate). Out-of-range probes are ignored.
    pub fn set_probe_input(&mut self, probe: usize, active: bool) {
        self.probe.set_dedicated(probe, active);
    }

    /// A snapshot of the drive for a personality's decisions (state, mode,
    /// statusword, controlword, inputs, NMT operational).
    pub fn view(&self) -> DriveView {
        DriveView {
            state: self.sm.state(),
            mode: self.mode,
            statusword: self.base_statusword(),
            controlword: self.cw,
            digital_inputs: self.digital_inputs(),
            operational: self.operational,
            software_limit: self.sup.soft_limit,
        }
    }

    /// The manufacturer mode (negative 6060h) in force, if any.
    pub fn manufacturer_mode(&self) -> Option<i8> {
        self.manufacturer.map(|(m, _)| m)
    }

    /// The mode the drive runs for a 6060h value: itself for a mode it
    /// runs, the stand-in of a manufacturer mode
    /// ([`DriveConfig::manufacturer_modes`]); `None`: refused (CiA 402-2
    /// §6.3.2). The one place 6060h is checked.
    pub fn stand_in(&self, m: i8) -> Option<i8> {
        if m < 0 {
            return self.cfg.manufacturer_modes.iter().find(|(c, _)| *c == m).map(|&(_, s)| s);
        }
        (op::supported_bit(m) & self.modes != 0).then_some(m)
    }

    /// 6060h taken: the mode (or a manufacturer mode's stand-in) runs.
    pub(crate) fn select_mode(&mut self, od: &mut ObjectDictionary, m: i8) {
        let Some(run) = self.stand_in(m) else { return };
        self.manufacturer = (m < 0).then_some((m, run));
        self.request_mode(od, run);
        self.publish(od);
    }

    /// 6061h: the manufacturer code while its stand-in runs.
    pub(crate) fn mode_shown(&mut self) -> i8 {
        match self.manufacturer {
            Some((m, run)) if run == self.mode => m,
            Some(_) => {
                // The stand-in was left (another 6060h, a reset).
                self.manufacturer = None;
                self.mode
            }
            None => self.mode,
        }
    }
}
