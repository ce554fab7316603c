//! Tests of the CiA 402-2 §6.2 device control state machine.

use super::*;
use proptest::prelude::*;

const SHUTDOWN: u16 = 0x06;
const SWITCH_ON: u16 = 0x07;
const ENABLE_OP: u16 = 0x0F;
const DISABLE_VOLTAGE: u16 = 0x00;
const QUICK_STOP: u16 = 0x02;
const FAULT_RESET: u16 = 0x80;

/// Brings a fresh machine into `target` (ramps left in progress where the
/// state involves one, so the table also covers commands during a ramp).
fn machine_in(target: State, options: Options) -> StateMachine {
    let mut m = StateMachine::new(options);
    match target {
        State::NotReadyToSwitchOn => {}
        State::SwitchOnDisabled => {
            m.self_test_passed();
        }
        State::ReadyToSwitchOn => {
            m.self_test_passed();
            m.controlword(SHUTDOWN);
        }
        State::SwitchedOn => {
            m.self_test_passed();
            m.controlword(SHUTDOWN);
            m.controlword(SWITCH_ON);
        }
        State::OperationEnabled => {
            m.self_test_passed();
            m.controlword(SHUTDOWN);
            m.controlword(ENABLE_OP);
        }
        State::QuickStopActive => {
            m.self_test_passed();
            m.controlword(SHUTDOWN);
            m.controlword(ENABLE_OP);
            m.controlword(QUICK_STOP);
        }
        State::FaultReactionActive => {
            m.self_test_passed();
            m.controlword(SHUTDOWN);
            m.controlword(ENABLE_OP);
            m.fault(0x2310);
        }
        State::Fault => {
            m.self_test_passed();
            m.fault(0x2310);
        }
    }
    assert_eq!(m.state(), target);
    m
}

fn assert_sw_matches(m: &StateMachine) {
    let sw = m.statusword();
    let matching: Vec<State> = State::ALL
        .into_iter()
        .filter(|s| {
            let (mask, v) = s.statusword_pattern();
            sw & mask == v
        })
        .collect();
    assert_eq!(matching, vec![m.state()], "statusword {sw:#06x}");
}

/// Every command from every state (CiA 402-2 §6.2.1 transition table);
/// commands that are not legal in a state leave it unchanged.
#[test]
fn every_command_from_every_state() {
    use State as S;
    // Options: quick stop 2 (ramp then SOD), shutdown 0, disable op 0.
    let mut o = Options::default();
    o.set_disable_operation(0).unwrap();
    o.set_shutdown(0).unwrap();
    #[rustfmt::skip]
    let table: [(State, [State; 6]); 8] = [
        //                       shutdown            switch on          enable op            disable voltage       quick stop            fault reset
        (S::NotReadyToSwitchOn, [S::NotReadyToSwitchOn, S::NotReadyToSwitchOn, S::NotReadyToSwitchOn, S::NotReadyToSwitchOn, S::NotReadyToSwitchOn, S::NotReadyToSwitchOn]),
        (S::SwitchOnDisabled,   [S::ReadyToSwitchOn, S::SwitchOnDisabled, S::SwitchOnDisabled, S::SwitchOnDisabled, S::SwitchOnDisabled, S::SwitchOnDisabled]),
        (S::ReadyToSwitchOn,    [S::ReadyToSwitchOn, S::SwitchedOn, S::OperationEnabled, S::SwitchOnDisabled, S::SwitchOnDisabled, S::ReadyToSwitchOn]),
        (S::SwitchedOn,         [S::ReadyToSwitchOn, S::SwitchedOn, S::OperationEnabled, S::SwitchOnDisabled, S::SwitchOnDisabled, S::SwitchedOn]),
        (S::OperationEnabled,   [S::ReadyToSwitchOn, S::SwitchedOn, S::OperationEnabled, S::SwitchOnDisabled, S::QuickStopActive, S::OperationEnabled]),
        (S::QuickStopActive,    [S::QuickStopActive, S::QuickStopActive, S::QuickStopActive, S::SwitchOnDisabled, S::QuickStopActive, S::QuickStopActive]),
        (S::FaultReactionActive,[S::FaultReactionActive, S::FaultReactionActive, S::FaultReactionActive, S::FaultReactionActive, S::FaultReactionActive, S::FaultReactionActive]),
        (S::Fault,              [S::Fault, S::Fault, S::Fault, S::Fault, S::Fault, S::SwitchOnDisabled]),
    ];
    let cws = [SHUTDOWN, SWITCH_ON, ENABLE_OP, DISABLE_VOLTAGE, QUICK_STOP, FAULT_RESET];
    for (from, expected) in table {
        for (cw, want) in cws.into_iter().zip(expected) {
            let mut m = machine_in(from, o);
            let out = m.controlword(cw);
            assert_eq!(m.state(), want, "from {from:?} with cw {cw:#04x}");
            assert_eq!(out.previous, from);
            assert_eq!(out.state, want);
            assert_eq!(out.transitions == 0, from == want);
            assert_sw_matches(&m);
        }
    }
}

#[test]
fn exact_statusword_values() {
    let o = Options::default();
    let expect = [
        (State::NotReadyToSwitchOn, 0x0020),
        (State::SwitchOnDisabled, 0x0060),
        (State::ReadyToSwitchOn, 0x0031),
        (State::SwitchedOn, 0x0033),
        (State::OperationEnabled, 0x0037),
        (State::QuickStopActive, 0x0017),
        (State::FaultReactionActive, 0x003F),
        (State::Fault, 0x0028),
    ];
    for (s, sw) in expect {
        let m = machine_in(s, o);
        assert_eq!(m.statusword(), sw, "{s:?}");
        assert_eq!(State::from_statusword(sw), Some(s));
    }
}

#[test]
fn transition_numbers() {
    let mut m = StateMachine::new(Options::default());
    assert!(m.self_test_passed().took(1));
    assert!(m.controlword(SHUTDOWN).took(2));
    let o = m.controlword(ENABLE_OP);
    assert!(o.took(3) && o.took(4));
    assert_eq!(o.drive_function, DriveFunction::Enabled);
    // Disable operation with 605Ch = 1 ramps first, then transition 5.
    let o = m.controlword(SWITCH_ON);
    assert_eq!(o.state, State::OperationEnabled);
    assert_eq!(o.drive_function, DriveFunction::Stopping(Reaction::SlowDownRamp));
    let o = m.motion_stopped();
    assert!(o.took(5));
    assert_eq!(o.state, State::SwitchedOn);
    assert!(m.controlword(SHUTDOWN).took(6));
    assert!(m.controlword(QUICK_STOP).took(7));
    m.controlword(SHUTDOWN);
    m.controlword(ENABLE_OP);
    // Shutdown with 605Bh = 0: immediate transition 8, coasting.
    let o = m.controlword(SHUTDOWN);
    assert!(o.took(8));
    assert_eq!(o.drive_function, DriveFunction::Disabled);
    m.controlword(ENABLE_OP);
    assert!(m.controlword(DISABLE_VOLTAGE).took(9));
    m.controlword(SHUTDOWN);
    m.controlword(SWITCH_ON);
    assert!(m.controlword(DISABLE_VOLTAGE).took(10));
    m.controlword(SHUTDOWN);
    m.controlword(ENABLE_OP);
    assert!(m.controlword(QUICK_STOP).took(11));
    assert!(m.motion_stopped().took(12));
    let o = m.fault(0x3210);
    assert!(o.took(13) && o.took(14), "disabled drive: no reaction to wait for");
    assert_eq!(m.fault_code(), 0x3210);
    assert!(m.controlword(FAULT_RESET).took(15));
    assert_eq!(m.fault_code(), 0);
}

#[test]
fn shutdown_option_1_ramps_then_ready() {
    let mut o = Options::default();
    o.set_shutdown(1).unwrap();
    let mut m = machine_in(State::OperationEnabled, o);
    let out = m.controlword(SHUTDOWN);
    assert_eq!(out.state, State::OperationEnabled);
    assert_eq!(out.drive_function, DriveFunction::Stopping(Reaction::SlowDownRamp));
    // Re-enabling during the ramp cancels it.
    assert_eq!(m.controlword(ENABLE_OP).drive_function, DriveFunction::Enabled);
    m.controlword(SHUTDOWN);
    let out = m.motion_stopped();
    assert!(out.took(8));
    assert_eq!(m.state(), State::ReadyToSwitchOn);
    // A spurious motion_stopped does nothing.
    assert_eq!(m.motion_stopped().transitions, 0);
}

#[test]
fn quick_stop_each_option() {
    use Reaction as R;
    let cases = [
        (0, None, State::SwitchOnDisabled),
        (1, Some(R::SlowDownRamp), State::SwitchOnDisabled),
        (2, Some(R::QuickStopRamp), State::SwitchOnDisabled),
        (3, Some(R::CurrentLimit), State::SwitchOnDisabled),
        (4, Some(R::VoltageLimit), State::SwitchOnDisabled),
        (5, Some(R::SlowDownRamp), State::QuickStopActive),
        (6, Some(R::QuickStopRamp), State::QuickStopActive),
        (7, Some(R::CurrentLimit), State::QuickStopActive),
        (8, Some(R::VoltageLimit), State::QuickStopActive),
    ];
    for (code, reaction, after) in cases {
        let mut o = Options::default();
        o.set_quick_stop(code).unwrap();
        let mut m = machine_in(State::OperationEnabled, o);
        let out = m.controlword(QUICK_STOP);
        assert!(out.took(11), "option {code}");
        match reaction {
            None => {
                assert!(out.took(12));
                assert_eq!(out.drive_function, DriveFunction::Disabled);
                assert_eq!(m.state(), State::SwitchOnDisabled);
                continue;
            }
            Some(r) => {
                assert_eq!(out.drive_function, DriveFunction::Stopping(r));
                assert_eq!(m.state(), State::QuickStopActive);
                assert_eq!(m.statusword() & 0x6F, 0x07);
            }
        }
        // Enable operation during the stop: only 5–8 may return (16).
        let mut probe = m.clone();
        let back = probe.controlword(ENABLE_OP);
        assert_eq!(back.took(16), code >= 5, "option {code}");
        let out = m.motion_stopped();
        assert_eq!(m.state(), after, "option {code}");
        if code >= 5 {
            assert_eq!(out.drive_function, DriveFunction::Holding);
            assert!(m.controlword(ENABLE_OP).took(16));
            assert_eq!(m.drive_function(), DriveFunction::Enabled);
        } else {
            assert!(out.took(12));
            assert_eq!(out.drive_function, DriveFunction::Disabled);
        }
    }
}

#[test]
fn fault_reaction_each_option() {
    use Reaction as R;
    let cases = [
        (0, R::DisableDrive),
        (1, R::SlowDownRamp),
        (2, R::QuickStopRamp),
        (3, R::CurrentLimit),
        (4, R::VoltageLimit),
    ];
    for (code, reaction) in cases {
        let mut o = Options::default();
        o.set_fault_reaction(code).unwrap();
        let mut m = machine_in(State::OperationEnabled, o);
        let out = m.fault(0x4310);
        assert!(out.took(13));
        if reaction == R::DisableDrive {
            assert!(out.took(14));
            assert_eq!(m.state(), State::Fault);
            assert_eq!(out.drive_function, DriveFunction::Disabled);
        } else {
            assert_eq!(m.state(), State::FaultReactionActive);
            assert_eq!(out.drive_function, DriveFunction::Stopping(reaction));
            assert_eq!(m.statusword(), 0x003F);
            // Commands and further faults are ignored while reacting.
            assert_eq!(m.controlword(FAULT_RESET).state, State::FaultReactionActive);
            assert_eq!(m.fault(0x2310).transitions, 0);
            assert_eq!(m.fault_code(), 0x4310);
            assert!(m.motion_stopped().took(14));
            assert_eq!(m.state(), State::Fault);
        }
        assert_eq!(m.statusword(), 0x0028);
        // Bit 7 may still be high from above: it needs a fresh rising edge.
        m.controlword(0);
        assert!(m.controlword(FAULT_RESET).took(15));
    }
}

#[test]
fn fault_in_every_state() {
    for s in State::ALL {
        let mut m = machine_in(s, Options::default());
        m.fault(0x1000);
        assert!(matches!(m.state(), State::FaultReactionActive | State::Fault), "{s:?}");
        assert_sw_matches(&m);
    }
}

#[test]
fn fault_reset_needs_rising_edge() {
    let mut m = machine_in(State::Fault, Options::default());
    // Bit 7 held high from power-on is not an edge on the second frame.
    assert!(m.controlword(0x80).took(15));
    m.fault(0x2310);
    assert_eq!(m.state(), State::Fault);
    let out = m.controlword(0x80);
    assert_eq!(out.state, State::Fault, "level, not edge");
    assert!(!out.fault_reset);
    // Bit 7 high also masks the other commands.
    assert_eq!(m.controlword(0x86).state, State::Fault);
    m.controlword(0x00);
    let out = m.controlword(0x8F);
    assert!(out.fault_reset && out.took(15));
    // Bit 7 still set: shutdown is not decoded until it drops.
    assert_eq!(m.controlword(0x86).state, State::SwitchOnDisabled);
    assert_eq!(m.controlword(0x06).state, State::ReadyToSwitchOn);
    // Fault reset edges outside Fault are reported but change nothing.
    let out = m.controlword(0x80);
    assert!(out.fault_reset);
    assert_eq!(out.state, State::ReadyToSwitchOn);
}

#[test]
fn connection_lost_options() {
    let expect = [
        (-1, State::OperationEnabled),
        (0, State::OperationEnabled),
        (1, State::FaultReactionActive),
        (2, State::SwitchOnDisabled),
        (3, State::QuickStopActive),
    ];
    for (code, want) in expect {
        let mut o = Options::default();
        o.set_abort_connection(code).unwrap();
        let mut m = machine_in(State::OperationEnabled, o);
        m.connection_lost(0x8130);
        assert_eq!(m.state(), want, "6007h = {code}");
    }
}

#[test]
fn option_ranges() {
    let mut o = Options::default();
    assert!(o.set_quick_stop(9).is_err());
    assert!(o.set_quick_stop(-1).is_err());
    assert!(o.set_halt(0).is_err());
    assert!(o.set_fault_reaction(5).is_err());
    assert!(o.set_abort_connection(4).is_err());
    assert!(o.set_abort_connection(-1).is_ok());
    o.set_abort_connection(1).unwrap();
    assert!(o.set_shutdown(2).is_err());
    assert!(o.set_disable_operation(2).is_err());
    assert_eq!(o, Options::default());
    for (h, r) in [
        (1, Reaction::SlowDownRamp),
        (2, Reaction::QuickStopRamp),
        (3, Reaction::CurrentLimit),
        (4, Reaction::VoltageLimit),
    ] {
        o.set_halt(h).unwrap();
        assert_eq!(o.halt_reaction(), r);
    }
}

#[derive(Debug, Clone)]
enum Input {
    Cw(u16),
    Fault(u16),
    Stopped,
    SelfTest,
    Lost,
}

fn input() -> impl Strategy<Value = Input> {
    prop_oneof![
        6 => prop_oneof![
            Just(0x06u16), Just(0x07), Just(0x0F), Just(0x00), Just(0x02), Just(0x80)
        ].prop_map(Input::Cw),
        2 => any::<u16>().prop_map(Input::Cw),
        1 => any::<u16>().prop_map(Input::Fault),
        2 => Just(Input::Stopped),
        1 => Just(Input::SelfTest),
        1 => Just(Input::Lost),
    ]
}

proptest! {
    #[test]
    fn statusword_always_one_legal_state(
        qs in 0i16..=8, sd in 0i16..=1, dop in 0i16..=1, fr in 0i16..=4, ac in 0i16..=3,
        inputs in proptest::collection::vec(input(), 0..64),
    ) {
        let mut o = Options::default();
        o.set_quick_stop(qs).unwrap();
        o.set_shutdown(sd).unwrap();
        o.set_disable_operation(dop).unwrap();
        o.set_fault_reaction(fr).unwrap();
        o.set_abort_connection(ac).unwrap();
        let mut m = StateMachine::new(o);
        for i in inputs {
            let out = match i {
                Input::Cw(cw) => m.controlword(cw),
                Input::Fault(c) => m.fault(c),
                Input::Stopped => m.motion_stopped(),
                Input::SelfTest => m.self_test_passed(),
                Input::Lost => m.connection_lost(0x8130),
            };
            prop_assert_eq!(out.state, m.state());
            let sw = m.statusword();
            let n = State::ALL.iter().filter(|s| {
                let (mask, v) = s.statusword_pattern();
                sw & mask == v
            }).count();
            prop_assert_eq!(n, 1);
            prop_assert_eq!(State::from_statusword(sw), Some(m.state()));
            // The drive function is consistent with the state.
            let f = m.drive_function();
            match m.state() {
                State::OperationEnabled => prop_assert!(!matches!(f, DriveFunction::Disabled | DriveFunction::Holding)),
                State::QuickStopActive => prop_assert!(matches!(f, DriveFunction::Stopping(_) | DriveFunction::Holding)),
                State::FaultReactionActive => prop_assert!(matches!(f, DriveFunction::Stopping(_))),
                _ => prop_assert_eq!(f, DriveFunction::Disabled),
            }
        }
    }
}
