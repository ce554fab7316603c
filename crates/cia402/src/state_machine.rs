//! CiA 402 device control: the power drive system state machine
//! (CiA 402-2 §6.2 "Device control" / IEC 61800-7-201 §6.2, state machine
//! figure and table of transitions 0–16; controlword 6040h and statusword
//! 6041h coding tables; option codes 605Ah–605Eh and 6007h).
//!
//! Pure logic, no clock: the caller feeds controlwords, faults, a lost
//! connection and the "motion stopped" signal. Stopping *reactions* (ramps,
//! coast, current/voltage limit braking) are returned as [`DriveFunction`]
//! and executed by the operating-mode layer on the motor model; when the
//! axis has come to rest the mode layer calls [`StateMachine::motion_stopped`]
//! to complete the transition that waited for it.

pub use crate::codes::{ControlCommand, State};

/// Statusword 6041h bits owned by device control (bits 0–6); the whole
/// table is [`crate::codes::sw`].
pub mod sw {
    pub use crate::codes::sw::{
        DEVICE_CONTROL_MASK, FAULT, OPERATION_ENABLED, QUICK_STOP, READY_TO_SWITCH_ON, SWITCH_ON_DISABLED,
        SWITCHED_ON, VOLTAGE_ENABLED,
    };
}

/// How the drive has to bring the motor to rest (or let it go).
/// Mirrors the codings of 605Ah–605Eh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reaction {
    /// Disable the drive function: power stage off, the motor coasts.
    DisableDrive,
    /// Decelerate on the slow-down ramp (profile deceleration 6084h).
    SlowDownRamp,
    /// Decelerate on the quick-stop ramp (quick stop deceleration 6085h).
    QuickStopRamp,
    /// Decelerate at the current limit.
    CurrentLimit,
    /// Decelerate at the voltage limit (short-circuit / dynamic braking).
    VoltageLimit,
}

/// What the power stage and the operating mode must do now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DriveFunction {
    /// Drive function disabled: no torque, the motor is free.
    Disabled,
    /// Operation enabled: the selected operating mode runs.
    Enabled,
    /// A stop is in progress with this reaction; the mode layer executes it
    /// and calls [`StateMachine::motion_stopped`] once the axis is at rest.
    Stopping(Reaction),
    /// Quick stop active with options 5–8 after the stop: the drive stays
    /// enabled and holds position at standstill.
    Holding,
}

/// Option codes that are not supported (or reserved / manufacturer-specific).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OptionOutOfRange {
    /// The rejected value.
    pub value: i16,
}

/// The option-code objects 605Ah–605Eh and 6007h (all INTEGER16).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Options {
    quick_stop: i16,
    shutdown: i16,
    disable_operation: i16,
    halt: i16,
    fault_reaction: i16,
    abort_connection: i16,
}

impl Default for Options {
    /// Typical factory defaults: quick stop 2 (quick-stop ramp then switch on
    /// disabled), shutdown 0, disable operation 1, halt 1, fault reaction 2,
    /// abort connection 1 (fault).
    fn default() -> Self {
        Options {
            quick_stop: 2,
            shutdown: 0,
            disable_operation: 1,
            halt: 1,
            fault_reaction: 2,
            abort_connection: 1,
        }
    }
}

macro_rules! option_accessor {
    ($get:ident, $set:ident, $field:ident, $lo:expr, $hi:expr, $doc:literal) => {
        #[doc = concat!("Current value of ", $doc, ".")]
        pub const fn $get(&self) -> i16 {
            self.$field
        }
        #[doc = concat!("Sets ", $doc, "; values outside ", stringify!($lo), "..=", stringify!($hi),
                                                    " (reserved or manufacturer-specific) are refused.")]
        pub fn $set(&mut self, value: i16) -> Result<(), OptionOutOfRange> {
            if ($lo..=$hi).contains(&value) {
                self.$field = value;
                Ok(())
            } else {
                Err(OptionOutOfRange { value })
            }
        }
    };
}

impl Options {
    option_accessor!(quick_stop, set_quick_stop, quick_stop, 0, 8, "605Ah quick stop option code");
    option_accessor!(shutdown, set_shutdown, shutdown, 0, 1, "605Bh shutdown option code");
    option_accessor!(
        disable_operation,
        set_disable_operation,
        disable_operation,
        0,
        1,
        "605Ch disable operation option code"
    );
    option_accessor!(halt, set_halt, halt, 1, 4, "605Dh halt option code");
    option_accessor!(
        fault_reaction,
        set_fault_reaction,
        fault_reaction,
        0,
        4,
        "605Eh fault reaction option code"
    );
    option_accessor!(
        abort_connection,
        set_abort_connection,
        abort_connection,
        i16::MIN,
        3,
        "6007h abort connection option code (negative values are manufacturer-specific: \
         [`StateMachine::connection_lost`] does nothing, the application reacts)"
    );

    /// Reaction coded by 605Ah (the 5–8 "stay" variants map to 1–4).
    pub const fn quick_stop_reaction(&self) -> Reaction {
        match self.quick_stop {
            1 | 5 => Reaction::SlowDownRamp,
            2 | 6 => Reaction::QuickStopRamp,
            3 | 7 => Reaction::CurrentLimit,
            4 | 8 => Reaction::VoltageLimit,
            _ => Reaction::DisableDrive,
        }
    }

    /// 605Ah 5–8: stay in Quick stop active after the stop.
    pub const fn quick_stop_stays(&self) -> bool {
        self.quick_stop >= 5
    }

    /// Reaction for the halt function (605Dh, controlword bit 8); executed
    /// by the mode layer without a state change.
    pub const fn halt_reaction(&self) -> Reaction {
        match self.halt {
            2 => Reaction::QuickStopRamp,
            3 => Reaction::CurrentLimit,
            4 => Reaction::VoltageLimit,
            _ => Reaction::SlowDownRamp,
        }
    }

    /// Reaction coded by 605Eh.
    pub const fn fault_reaction_reaction(&self) -> Reaction {
        match self.fault_reaction {
            1 => Reaction::SlowDownRamp,
            2 => Reaction::QuickStopRamp,
            3 => Reaction::CurrentLimit,
            4 => Reaction::VoltageLimit,
            _ => Reaction::DisableDrive,
        }
    }

    const fn shutdown_reaction(&self) -> Reaction {
        if self.shutdown == 1 { Reaction::SlowDownRamp } else { Reaction::DisableDrive }
    }

    const fn disable_operation_reaction(&self) -> Reaction {
        if self.disable_operation == 1 { Reaction::SlowDownRamp } else { Reaction::DisableDrive }
    }
}

/// Result of one input to the state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outcome {
    /// State before the input.
    pub previous: State,
    /// State after the input.
    pub state: State,
    /// Bit `n` set = transition `n` (CiA 402-2 §6.2.1 numbering) was taken.
    pub transitions: u32,
    /// What the power stage / mode must do now.
    pub drive_function: DriveFunction,
    /// A rising edge of controlword bit 7 was seen (in any state): the
    /// application clears its latched faults and warnings. If a fault
    /// condition persists it reports it again with [`StateMachine::fault`].
    pub fault_reset: bool,
}

impl Outcome {
    /// Whether transition `n` was taken.
    pub const fn took(&self, n: u8) -> bool {
        n < 32 && self.transitions & (1 << n) != 0
    }
}

/// Where an operation-enabled stop ramp (605Bh / 605Ch option 1) leads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Pending {
    /// Transition 8 after the ramp.
    Shutdown,
    /// Transition 5 after the ramp.
    DisableOperation,
}

/// The CiA 402 device control state machine.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateMachine {
    state: State,
    options: Options,
    function: DriveFunction,
    pending: Option<Pending>,
    bit7: bool,
    fault_code: u16,
    transitions: u32,
    fault_reset: bool,
}

impl StateMachine {
    /// A drive just powered on: Not ready to switch on (after transition 0),
    /// waiting for [`StateMachine::self_test_passed`].
    pub fn new(options: Options) -> Self {
        StateMachine {
            state: State::NotReadyToSwitchOn,
            options,
            function: DriveFunction::Disabled,
            pending: None,
            bit7: false,
            fault_code: 0,
            transitions: 0,
            fault_reset: false,
        }
    }

    /// Current state.
    pub const fn state(&self) -> State {
        self.state
    }

    /// Current drive function / stopping reaction.
    pub const fn drive_function(&self) -> DriveFunction {
        self.function
    }

    /// Option codes.
    pub const fn options(&self) -> &Options {
        &self.options
    }

    /// Option codes, for the OD binding to write 605Ah–605Eh / 6007h.
    pub fn options_mut(&mut self) -> &mut Options {
        &mut self.options
    }

    /// Error code of the fault that caused the last transition 13 (603Fh);
    /// 0 after a fault reset.
    pub const fn fault_code(&self) -> u16 {
        self.fault_code
    }

    /// Statusword bits 0–6 (the rest belongs to the mode layer).
    pub fn statusword(&self) -> u16 {
        use sw::*;
        let base = match self.state {
            State::NotReadyToSwitchOn => 0,
            State::SwitchOnDisabled => SWITCH_ON_DISABLED,
            State::ReadyToSwitchOn => READY_TO_SWITCH_ON,
            State::SwitchedOn => READY_TO_SWITCH_ON | SWITCHED_ON,
            State::OperationEnabled | State::QuickStopActive => {
                READY_TO_SWITCH_ON | SWITCHED_ON | OPERATION_ENABLED
            }
            State::FaultReactionActive => READY_TO_SWITCH_ON | SWITCHED_ON | OPERATION_ENABLED | FAULT,
            State::Fault => FAULT,
        };
        // Bit 4: high voltage is applied whenever the power stage may be
        // energised, including a powered fault reaction (ramp).
        let voltage = match self.state {
            State::ReadyToSwitchOn | State::SwitchedOn | State::OperationEnabled | State::QuickStopActive => {
                true
            }
            State::FaultReactionActive => matches!(self.function, DriveFunction::Stopping(_)),
            _ => false,
        };
        // Bit 5 is low-active: cleared only while a quick stop is active.
        let qs = self.state != State::QuickStopActive;
        base | if voltage { VOLTAGE_ENABLED } else { 0 } | if qs { QUICK_STOP } else { 0 }
    }

    fn begin(&mut self) -> State {
        self.transitions = 0;
        self.fault_reset = false;
        self.state
    }

    fn go(&mut self, n: u8, to: State) {
        self.transitions |= 1 << n;
        self.state = to;
    }

    fn finish(&self, previous: State) -> Outcome {
        Outcome {
            previous,
            state: self.state,
            transitions: self.transitions,
            drive_function: self.function,
            fault_reset: self.fault_reset,
        }
    }

    /// Transition 1 (Not ready to switch on → Switch on disabled): the
    /// drive's self-test and initialisation finished; automatic in CiA 402.
    /// (CiA 402-2 numbers "Start → Not ready to switch on" as transition 0,
    /// which [`StateMachine::new`] stands for.)
    pub fn self_test_passed(&mut self) -> Outcome {
        let prev = self.begin();
        if self.state == State::NotReadyToSwitchOn {
            self.go(1, State::SwitchOnDisabled);
        }
        self.finish(prev)
    }

    /// Processes a received controlword (6040h). Bit 7 is edge-triggered:
    /// only its rising edge is a fault reset, and while it stays set no other
    /// command is decoded (every command coding requires bit 7 = 0).
    pub fn controlword(&mut self, cw: u16) -> Outcome {
        let prev = self.begin();
        let bit7 = cw & 0x80 != 0;
        let rising = bit7 && !self.bit7;
        self.bit7 = bit7;
        if rising {
            self.fault_reset = true;
            self.apply(ControlCommand::FaultReset);
        } else if let Some(cmd) = ControlCommand::decode(cw) {
            self.apply(cmd);
        }
        self.finish(prev)
    }

    /// Applies a decoded command (used by [`Self::controlword`] and for the
    /// 6007h actions). Commands not legal in the current state are ignored.
    fn apply(&mut self, cmd: ControlCommand) {
        use ControlCommand as C;
        use State as S;
        match (self.state, cmd) {
            (S::SwitchOnDisabled, C::Shutdown) => self.go(2, S::ReadyToSwitchOn),
            (S::ReadyToSwitchOn, C::SwitchOn) => self.go(3, S::SwitchedOn),
            (S::ReadyToSwitchOn, C::EnableOperation) => {
                // "Switch on + enable operation": transitions 3 and 4 at once.
                self.go(3, S::SwitchedOn);
                self.enable(4);
            }
            (S::ReadyToSwitchOn, C::DisableVoltage | C::QuickStop) => self.go(7, S::SwitchOnDisabled),
            (S::SwitchedOn, C::EnableOperation) => self.enable(4),
            (S::SwitchedOn, C::Shutdown) => self.go(6, S::ReadyToSwitchOn),
            (S::SwitchedOn, C::DisableVoltage | C::QuickStop) => self.go(10, S::SwitchOnDisabled),
            (S::OperationEnabled, C::EnableOperation) => {
                // Re-enabling cancels an unfinished 605Bh/605Ch slow-down.
                self.pending = None;
                self.function = DriveFunction::Enabled;
            }
            (S::OperationEnabled, C::SwitchOn) => {
                let r = self.options.disable_operation_reaction();
                self.stop_from_enabled(Pending::DisableOperation, r);
            }
            (S::OperationEnabled, C::Shutdown) => {
                let r = self.options.shutdown_reaction();
                self.stop_from_enabled(Pending::Shutdown, r);
            }
            (S::OperationEnabled, C::DisableVoltage) => {
                self.disable();
                self.go(9, S::SwitchOnDisabled);
            }
            (S::OperationEnabled, C::QuickStop) => {
                self.pending = None;
                self.go(11, S::QuickStopActive);
                let r = self.options.quick_stop_reaction();
                if r == Reaction::DisableDrive {
                    // 605Ah = 0: no ramp to wait for, straight on to SOD.
                    self.disable();
                    self.go(12, S::SwitchOnDisabled);
                } else {
                    self.function = DriveFunction::Stopping(r);
                }
            }
            (S::QuickStopActive, C::DisableVoltage) => {
                self.disable();
                self.go(12, S::SwitchOnDisabled);
            }
            (S::QuickStopActive, C::EnableOperation) if self.options.quick_stop_stays() => {
                self.enable(16);
            }
            (S::Fault, C::FaultReset) => {
                self.fault_code = 0;
                self.go(15, S::SwitchOnDisabled);
            }
            _ => {}
        }
    }

    fn enable(&mut self, n: u8) {
        self.pending = None;
        self.function = DriveFunction::Enabled;
        self.go(n, State::OperationEnabled);
    }

    fn disable(&mut self) {
        self.pending = None;
        self.function = DriveFunction::Disabled;
    }

    fn stop_from_enabled(&mut self, pending: Pending, reaction: Reaction) {
        if reaction == Reaction::DisableDrive {
            self.disable();
            self.complete_pending(pending);
        } else {
            // The state stays Operation enabled until the ramp has finished.
            self.pending = Some(pending);
            self.function = DriveFunction::Stopping(reaction);
        }
    }

    fn complete_pending(&mut self, pending: Pending) {
        match pending {
            Pending::Shutdown => self.go(8, State::ReadyToSwitchOn),
            Pending::DisableOperation => self.go(5, State::SwitchedOn),
        }
    }

    /// The mode layer reports that the stopping reaction brought the axis to
    /// rest. Completes transitions 5/8 (after a 605Bh/605Ch ramp), 12 (605Ah
    /// 1–4), 14 (605Eh 1–4), or switches to holding (605Ah 5–8).
    pub fn motion_stopped(&mut self) -> Outcome {
        let prev = self.begin();
        if let DriveFunction::Stopping(_) = self.function {
            match self.state {
                State::OperationEnabled => {
                    if let Some(p) = self.pending.take() {
                        self.function = DriveFunction::Disabled;
                        self.complete_pending(p);
                    }
                }
                State::QuickStopActive => {
                    if self.options.quick_stop_stays() {
                        self.function = DriveFunction::Holding;
                    } else {
                        self.function = DriveFunction::Disabled;
                        self.go(12, State::SwitchOnDisabled);
                    }
                }
                State::FaultReactionActive => {
                    self.function = DriveFunction::Disabled;
                    self.go(14, State::Fault);
                }
                _ => {}
            }
        }
        self.finish(prev)
    }

    /// A fault was detected (transition 13 from any state but the fault
    /// states). `code` is the CiA 402 / CiA 301 error code for 603Fh.
    /// With 605Eh = 0, or if the drive function was not enabled, there is
    /// nothing to stop and transition 14 follows at once.
    pub fn fault(&mut self, code: u16) -> Outcome {
        let r = self.options.fault_reaction_reaction();
        self.fault_with(code, r)
    }

    /// A fault with the reaction `r` instead of 605Eh's (a manufacturer's
    /// per-error option code).
    pub fn fault_with(&mut self, code: u16, r: Reaction) -> Outcome {
        let prev = self.begin();
        if !matches!(self.state, State::FaultReactionActive | State::Fault) {
            self.fault_code = code;
            let powered = !matches!(self.function, DriveFunction::Disabled);
            self.pending = None;
            self.go(13, State::FaultReactionActive);
            if powered && r != Reaction::DisableDrive {
                self.function = DriveFunction::Stopping(r);
            } else {
                self.function = DriveFunction::Disabled;
                self.go(14, State::Fault);
            }
        }
        self.finish(prev)
    }

    /// A quick stop the device decides itself (an error whose class stops
    /// the motor without a fault, LAM DDS6 §5 class 2): the controlword's
    /// Quick stop command (transition 11 from Operation enabled, then per
    /// 605Ah).
    pub fn quick_stop(&mut self) -> Outcome {
        let prev = self.begin();
        self.apply(ControlCommand::QuickStop);
        self.finish(prev)
    }

    /// The connection to the master was lost (heartbeat / node guarding
    /// timeout, bus-off): executes the 6007h abort connection option
    /// (0 none, 1 fault with `code`, 2 disable voltage, 3 quick stop;
    /// negative = manufacturer-specific, left to the application).
    pub fn connection_lost(&mut self, code: u16) -> Outcome {
        match self.options.abort_connection {
            1 => self.fault(code),
            2 | 3 => {
                let prev = self.begin();
                let cmd = if self.options.abort_connection == 2 {
                    ControlCommand::DisableVoltage
                } else {
                    ControlCommand::QuickStop
                };
                self.apply(cmd);
                self.finish(prev)
            }
            _ => {
                let prev = self.begin();
                self.finish(prev)
            }
        }
    }
}

#[cfg(test)]
mod tests;
