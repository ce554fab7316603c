//! The CiA 402 codes a drive and a master share (CiA 402-2 §6.2
//! "Device control", §6.3 "Modes of operation"): the eight states and
//! their statusword coding, the controlword commands, the statusword bits,
//! the modes of operation with their 6502h bits and names.
//!
//! This module needs no other part of the crate: a master uses it with
//! `drivebus-cia402 = { default-features = false }` (no drive model).

/// The eight states of the CiA 402 state machine (CiA 402-2 §6.2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum State {
    /// Low-level power applied, drive initialising / self-testing.
    NotReadyToSwitchOn,
    /// Initialisation complete, high voltage may be off, drive function disabled.
    SwitchOnDisabled,
    /// High voltage may be applied, drive function disabled.
    ReadyToSwitchOn,
    /// Power amplifier ready, drive function disabled.
    SwitchedOn,
    /// Drive function enabled, power applied to the motor.
    OperationEnabled,
    /// Quick stop function being executed (or holding after it, options 5–8).
    QuickStopActive,
    /// A fault occurred; the fault reaction (605Eh) is being executed.
    FaultReactionActive,
    /// Fault reaction completed, drive function disabled.
    Fault,
}

impl State {
    /// All states, in the order of the statusword coding table.
    pub const ALL: [State; 8] = [
        State::NotReadyToSwitchOn,
        State::SwitchOnDisabled,
        State::ReadyToSwitchOn,
        State::SwitchedOn,
        State::OperationEnabled,
        State::QuickStopActive,
        State::FaultReactionActive,
        State::Fault,
    ];

    /// `(mask, value)` identifying this state in the statusword
    /// (CiA 402-2 §6.2.1, table "State coding": `sw & mask == value`).
    pub const fn statusword_pattern(self) -> (u16, u16) {
        match self {
            State::NotReadyToSwitchOn => (0x4F, 0x00),
            State::SwitchOnDisabled => (0x4F, 0x40),
            State::ReadyToSwitchOn => (0x6F, 0x21),
            State::SwitchedOn => (0x6F, 0x23),
            State::OperationEnabled => (0x6F, 0x27),
            State::QuickStopActive => (0x6F, 0x07),
            State::FaultReactionActive => (0x4F, 0x0F),
            State::Fault => (0x4F, 0x08),
        }
    }

    /// Decodes the state from a statusword; `None` if no pattern matches.
    pub const fn from_statusword(sw: u16) -> Option<State> {
        let mut i = 0;
        while i < State::ALL.len() {
            let (m, v) = State::ALL[i].statusword_pattern();
            if sw & m == v {
                return Some(State::ALL[i]);
            }
            i += 1;
        }
        None
    }

    /// The state's name as CiA 402-2 writes it ("switch on disabled").
    pub const fn name(self) -> &'static str {
        match self {
            State::NotReadyToSwitchOn => "not ready to switch on",
            State::SwitchOnDisabled => "switch on disabled",
            State::ReadyToSwitchOn => "ready to switch on",
            State::SwitchedOn => "switched on",
            State::OperationEnabled => "operation enabled",
            State::QuickStopActive => "quick stop active",
            State::FaultReactionActive => "fault reaction active",
            State::Fault => "fault",
        }
    }
}

impl core::fmt::Display for State {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Statusword 6041h bits (CiA 402-2 §6.2.2).
pub mod sw {
    /// Bit 0: ready to switch on.
    pub const READY_TO_SWITCH_ON: u16 = 1 << 0;
    /// Bit 1: switched on.
    pub const SWITCHED_ON: u16 = 1 << 1;
    /// Bit 2: operation enabled.
    pub const OPERATION_ENABLED: u16 = 1 << 2;
    /// Bit 3: fault.
    pub const FAULT: u16 = 1 << 3;
    /// Bit 4: voltage enabled (high voltage applied to the drive).
    pub const VOLTAGE_ENABLED: u16 = 1 << 4;
    /// Bit 5: quick stop — *cleared* while a quick stop is active.
    pub const QUICK_STOP: u16 = 1 << 5;
    /// Bit 6: switch on disabled.
    pub const SWITCH_ON_DISABLED: u16 = 1 << 6;
    /// Bit 7: warning.
    pub const WARNING: u16 = 1 << 7;
    /// Bit 9: remote (the controlword is obeyed).
    pub const REMOTE: u16 = 1 << 9;
    /// Bit 10: target reached.
    pub const TARGET_REACHED: u16 = 1 << 10;
    /// Bit 11: internal limit active.
    pub const INTERNAL_LIMIT: u16 = 1 << 11;
    /// Bit 12: mode specific (pp set-point acknowledge, hm homing attained,
    /// csp/csv/cst target value ignored).
    pub const MODE_12: u16 = 1 << 12;
    /// Bit 13: mode specific (pp following error, hm homing error).
    pub const MODE_13: u16 = 1 << 13;
    /// Bits 0–6: the state coding (device control).
    pub const DEVICE_CONTROL_MASK: u16 = 0x7F;
}

/// Controlword 6040h commands and bits (CiA 402-2 §6.2.1, §6.2.3).
pub mod cw {
    /// Shutdown (transitions 2, 6, 8).
    pub const SHUTDOWN: u16 = 0x06;
    /// Switch on (transition 3); disable operation (5) in Operation enabled.
    pub const SWITCH_ON: u16 = 0x07;
    /// Disable operation (transition 5).
    pub const DISABLE_OPERATION: u16 = 0x07;
    /// Enable operation (transitions 4, 16).
    pub const ENABLE_OPERATION: u16 = 0x0F;
    /// Disable voltage (transitions 7, 9, 10, 12).
    pub const DISABLE_VOLTAGE: u16 = 0x00;
    /// Quick stop (transitions 7, 10, 11).
    pub const QUICK_STOP: u16 = 0x02;
    /// Fault reset: a rising edge of bit 7 (transition 15).
    pub const FAULT_RESET: u16 = 0x80;
    /// Bit 4: pp new set-point, hm homing operation start.
    pub const NEW_SET_POINT: u16 = 1 << 4;
    /// Bit 5: pp change set immediately.
    pub const CHANGE_IMMEDIATELY: u16 = 1 << 5;
    /// Bit 6: pp relative target.
    pub const RELATIVE: u16 = 1 << 6;
    /// Bit 8: halt.
    pub const HALT: u16 = 1 << 8;
}

/// Device control commands decoded from controlword 6040h bits 0–3 and 7
/// (CiA 402-2 §6.2.1, table "Command coding").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControlCommand {
    /// `0xxx x110` (mask 0x87 = 0x06): transitions 2, 6, 8.
    Shutdown,
    /// `0xxx 0111` (mask 0x8F = 0x07): transition 3; the same coding is
    /// "disable operation" (transition 5) in Operation enabled.
    SwitchOn,
    /// `0xxx 1111` (mask 0x8F = 0x0F): transitions 4, 16; in Ready to
    /// switch on it is "switch on + enable operation" (3 then 4).
    EnableOperation,
    /// `0xxx xx0x` (mask 0x82 = 0x00): transitions 7, 9, 10, 12.
    DisableVoltage,
    /// `0xxx x01x` (mask 0x86 = 0x02): transitions 7, 10, 11.
    QuickStop,
    /// Rising edge of bit 7: transition 15.
    FaultReset,
}

impl ControlCommand {
    /// Decodes bits 0–3 and 7 of a controlword (without edge detection on
    /// bit 7: a set bit 7 yields `None`).
    pub const fn decode(cw: u16) -> Option<ControlCommand> {
        if cw & 0x82 == 0x00 {
            Some(ControlCommand::DisableVoltage)
        } else if cw & 0x86 == 0x02 {
            Some(ControlCommand::QuickStop)
        } else if cw & 0x87 == 0x06 {
            Some(ControlCommand::Shutdown)
        } else if cw & 0x8F == 0x07 {
            Some(ControlCommand::SwitchOn)
        } else if cw & 0x8F == 0x0F {
            Some(ControlCommand::EnableOperation)
        } else {
            None
        }
    }

    /// The controlword a master writes for the command (bits 0–3 and 7).
    pub const fn controlword(self) -> u16 {
        match self {
            ControlCommand::Shutdown => cw::SHUTDOWN,
            ControlCommand::SwitchOn => cw::SWITCH_ON,
            ControlCommand::EnableOperation => cw::ENABLE_OPERATION,
            ControlCommand::DisableVoltage => cw::DISABLE_VOLTAGE,
            ControlCommand::QuickStop => cw::QUICK_STOP,
            ControlCommand::FaultReset => cw::FAULT_RESET,
        }
    }
}

/// The master's next step on the way to Operation enabled, from the state
/// the drive reports (CiA 402-2 §6.2.1, transitions 2, 3, 4, 12 and 15).
/// The one enable sequence of every master: the CANopen master's
/// `RemoteDrive::enable`, the EtherCAT master's and the cyclic probes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EnableStep {
    /// Operation enabled: nothing to do.
    Done,
    /// Write `controlword`; the drive answers with state `expect`.
    Write {
        /// The command to write (6040h bits 0–3).
        controlword: u16,
        /// The state it leads to.
        expect: State,
    },
    /// Fault: a rising edge of bit 7 ([`cw::DISABLE_VOLTAGE`] then
    /// [`cw::FAULT_RESET`]) leads to Switch on disabled.
    FaultReset,
    /// Not ready to switch on, fault reaction active or a pattern no state
    /// has: the drive leaves it by itself; wait (a cyclic master keeps
    /// writing [`cw::DISABLE_VOLTAGE`], which no transition out of these
    /// states needs).
    Wait,
}

impl EnableStep {
    /// The step from `state` (`None`: a statusword no state matches).
    /// Quick stop active goes back through Switch on disabled (transition
    /// 12), which every quick stop option allows; transition 16 exists only
    /// for options 5–8.
    pub const fn from(state: Option<State>) -> EnableStep {
        let (controlword, expect) = match state {
            Some(State::OperationEnabled) => return EnableStep::Done,
            Some(State::Fault) => return EnableStep::FaultReset,
            Some(State::NotReadyToSwitchOn | State::FaultReactionActive) | None => return EnableStep::Wait,
            Some(State::SwitchOnDisabled) => (cw::SHUTDOWN, State::ReadyToSwitchOn),
            Some(State::ReadyToSwitchOn) => (cw::SWITCH_ON, State::SwitchedOn),
            Some(State::SwitchedOn) => (cw::ENABLE_OPERATION, State::OperationEnabled),
            Some(State::QuickStopActive) => (cw::DISABLE_VOLTAGE, State::SwitchOnDisabled),
        };
        EnableStep::Write { controlword, expect }
    }

    /// The step for a statusword.
    pub const fn from_statusword(sw: u16) -> EnableStep {
        EnableStep::from(State::from_statusword(sw))
    }

    /// The controlword a cyclic master writes in this step; for a fault
    /// reset, `edge_high` picks the second half of the edge.
    pub const fn cyclic_controlword(self, edge_high: bool) -> u16 {
        match self {
            EnableStep::Done => cw::ENABLE_OPERATION,
            EnableStep::Write { controlword, .. } => controlword,
            EnableStep::FaultReset if edge_high => cw::FAULT_RESET,
            EnableStep::FaultReset | EnableStep::Wait => cw::DISABLE_VOLTAGE,
        }
    }
}

/// Modes of operation (6060h / 6061h values, CiA 402-2 §6.3.2).
pub mod mode {
    /// Profile position.
    pub const PP: i8 = 1;
    /// Velocity (frequency converter).
    pub const VL: i8 = 2;
    /// Profile velocity.
    pub const PV: i8 = 3;
    /// Profile torque.
    pub const TQ: i8 = 4;
    /// Homing.
    pub const HM: i8 = 6;
    /// Interpolated position.
    pub const IP: i8 = 7;
    /// Cyclic synchronous position.
    pub const CSP: i8 = 8;
    /// Cyclic synchronous velocity.
    pub const CSV: i8 = 9;
    /// Cyclic synchronous torque.
    pub const CST: i8 = 10;

    /// The 6502h "supported drive modes" bit of a mode (0 for codes without
    /// one: 0 "no mode", 5 reserved, negative manufacturer modes).
    pub const fn supported_bit(mode: i8) -> u32 {
        match mode {
            1..=4 => 1 << (mode - 1),
            6..=10 => 1 << (mode - 1),
            _ => 0,
        }
    }

    /// The mode's name ("profile position"; negative codes are the
    /// manufacturer's).
    pub const fn name(mode: i8) -> &'static str {
        match mode {
            PP => "profile position",
            VL => "velocity",
            PV => "profile velocity",
            TQ => "profile torque",
            HM => "homing",
            IP => "interpolated position",
            CSP => "cyclic sync position",
            CSV => "cyclic sync velocity",
            CST => "cyclic sync torque",
            0 => "none",
            m if m < 0 => "manufacturer specific",
            _ => "reserved",
        }
    }

    /// Whether 6061h is to show a mode written to 6060h now, by the
    /// statusword: in Operation enabled it is. Before it a drive may take
    /// the new mode only once enabled (iPOS manual §4.2.4), so a master
    /// checks 6061h after enabling instead ([`super::ModeNotShown`] if it
    /// does not show the mode then).
    pub const fn shown_at_once(statusword: u16) -> bool {
        matches!(super::State::from_statusword(statusword), Some(super::State::OperationEnabled))
    }

    /// The short name CLI options use (`pp`, `csp`, …); `None` for codes
    /// without one.
    pub const fn short(mode: i8) -> Option<&'static str> {
        Some(match mode {
            PP => "pp",
            VL => "vl",
            PV => "pv",
            TQ => "tq",
            HM => "hm",
            IP => "ip",
            CSP => "csp",
            CSV => "csv",
            CST => "cst",
            _ => return None,
        })
    }
}

/// 6061h (modes of operation display) did not come to show the mode a
/// master wrote to 6060h: waited for in Operation enabled
/// ([`mode::shown_at_once`]), else once enabling reached it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeNotShown {
    /// The mode written to 6060h.
    pub mode: i8,
    /// What 6061h showed last.
    pub display: i8,
    /// The statusword then.
    pub statusword: u16,
}

impl core::fmt::Display for ModeNotShown {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (m, d, sw) = (self.mode, self.display, self.statusword);
        write!(
            f,
            "6061h shows mode {d} ({}), not mode {m} ({}) written to 6060h (statusword {sw:04X}h",
            mode::name(d),
            mode::name(m)
        )?;
        match State::from_statusword(sw) {
            Some(State::OperationEnabled) => f.write_str(", operation enabled)"),
            Some(s) => write!(f, ", {s}): a drive may take a new mode only in operation enabled"),
            None => f.write_str(")"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Following the steps from every state reaches Operation enabled on a
    /// drive that obeys the CiA 402 state table, in at most four writes.
    #[test]
    fn the_enable_steps_reach_operation_enabled_from_every_state() {
        for start in State::ALL {
            let mut state = start;
            let mut writes = 0;
            loop {
                match EnableStep::from(Some(state)) {
                    EnableStep::Done => break,
                    EnableStep::Write { controlword, expect } => {
                        let cmd = ControlCommand::decode(controlword).unwrap();
                        let allowed = matches!(
                            (state, cmd),
                            (State::SwitchOnDisabled, ControlCommand::Shutdown)
                                | (State::ReadyToSwitchOn, ControlCommand::SwitchOn)
                                | (State::SwitchedOn, ControlCommand::EnableOperation)
                                | (State::QuickStopActive, ControlCommand::DisableVoltage)
                        );
                        assert!(allowed, "{state:?}: {cmd:?} is no transition of the table");
                        state = expect;
                    }
                    EnableStep::FaultReset => state = State::SwitchOnDisabled,
                    // The drive moves on by itself (initialisation, the fault reaction).
                    EnableStep::Wait => {
                        state = if state == State::FaultReactionActive {
                            State::Fault
                        } else {
                            State::SwitchOnDisabled
                        }
                    }
                }
                writes += 1;
                assert!(writes <= 5, "{start:?}: no end");
            }
        }
        assert_eq!(EnableStep::from_statusword(0x0000), EnableStep::Wait);
        assert_eq!(EnableStep::from_statusword(0x0237), EnableStep::Done);
        assert_eq!(EnableStep::from_statusword(0x0008).cyclic_controlword(false), cw::DISABLE_VOLTAGE);
        assert_eq!(EnableStep::from_statusword(0x0008).cyclic_controlword(true), cw::FAULT_RESET);
    }

    #[test]
    fn every_state_decodes_from_its_own_pattern_only() {
        for s in State::ALL {
            let (_, v) = s.statusword_pattern();
            assert_eq!(State::from_statusword(v), Some(s));
            // Bits outside the state coding do not matter.
            assert_eq!(State::from_statusword(v | 0xFF80), Some(s));
        }
        assert_eq!(State::from_statusword(0x0001), None);
        assert_eq!(State::Fault.to_string(), "fault");
    }

    #[test]
    fn mode_shown_at_once_only_in_operation_enabled() {
        for s in State::ALL {
            let (_, v) = s.statusword_pattern();
            assert_eq!(mode::shown_at_once(v), s == State::OperationEnabled, "{s}");
        }
        let e = ModeNotShown { mode: mode::HM, display: 0, statusword: 0x0231 };
        assert_eq!(
            e.to_string(),
            "6061h shows mode 0 (none), not mode 6 (homing) written to 6060h (statusword 0231h, \
             ready to switch on): a drive may take a new mode only in operation enabled"
        );
        let e = ModeNotShown { mode: mode::PP, display: mode::PV, statusword: 0x1237 };
        assert!(e.to_string().ends_with("(statusword 1237h, operation enabled)"), "{e}");
    }

    #[test]
    fn commands_round_trip() {
        for c in [
            ControlCommand::Shutdown,
            ControlCommand::SwitchOn,
            ControlCommand::EnableOperation,
            ControlCommand::DisableVoltage,
            ControlCommand::QuickStop,
        ] {
            assert_eq!(ControlCommand::decode(c.controlword()), Some(c));
        }
        assert_eq!(ControlCommand::decode(cw::FAULT_RESET), None, "edge-detected by the state machine");
    }

    #[test]
    fn modes() {
        assert_eq!(mode::supported_bit(mode::CSP), 1 << 7);
        assert_eq!(mode::supported_bit(5), 0);
        assert_eq!(mode::name(mode::HM), "homing");
        assert_eq!(mode::name(-3), "manufacturer specific");
        assert_eq!(mode::short(mode::CST), Some("cst"));
    }
}
