//! NMT commands (CiA 301 §7.2.8.3.1) and the state machine (§7.3.2).

mod common;

use common::{Dev, NODE, ms};
use drivebus_can::{CanId, Frame};
use drivebus_nmt::{
    CommandSet, InitSubState, NmtCommand, NmtConfig, NmtEvent, NmtState, RemoteState, Service,
};

const PRE: NmtState = NmtState::PreOperational;
const OP: NmtState = NmtState::Operational;
const STOP: NmtState = NmtState::Stopped;
const RESET_APP: NmtState = NmtState::Initialisation(InitSubState::ResetApplication);
const RESET_COMM: NmtState = NmtState::Initialisation(InitSubState::ResetCommunication);

/// A booted device brought to `state` by commands, output drained.
fn in_state(state: NmtState) -> Dev {
    let mut d = Dev::booted();
    match state {
        NmtState::Operational => {
            d.cmd(0x01, NODE, ms(1));
        }
        NmtState::Stopped => {
            d.cmd(0x02, NODE, ms(1));
        }
        NmtState::PreOperational => {}
        NmtState::Initialisation(InitSubState::ResetCommunication) => {
            d.cmd(0x82, NODE, ms(1));
        }
        NmtState::Initialisation(_) => {
            d.cmd(0x81, NODE, ms(1));
        }
    }
    assert_eq!(d.nmt.state(), state);
    d.take();
    d
}

fn expected(from: NmtState, cmd: NmtCommand) -> (NmtState, Option<NmtEvent>) {
    let change = |to: NmtState| {
        if from == to { (from, None) } else { (to, Some(NmtEvent::StateChanged { from, to })) }
    };
    match cmd {
        NmtCommand::Start => change(OP),
        NmtCommand::Stop => change(STOP),
        NmtCommand::EnterPreOperational => change(PRE),
        NmtCommand::ResetNode => (RESET_APP, Some(NmtEvent::ResetApplication)),
        NmtCommand::ResetCommunication => (RESET_COMM, Some(NmtEvent::ResetCommunication)),
    }
}

#[test]
fn every_command_in_every_state_addressed_broadcast_and_other() {
    for from in [PRE, OP, STOP] {
        for cmd in NmtCommand::ALL {
            for target in [NODE, 0, NODE + 1, 127] {
                let mut d = in_state(from);
                let ev = d.cmd(cmd.cs(), target, ms(10));
                let (state, event) =
                    if target == NODE || target == 0 { expected(from, cmd) } else { (from, None) };
                assert_eq!((d.nmt.state(), ev), (state, event), "{from:?} {cmd:?} → node {target}");
                assert!(d.take().is_empty(), "NMT commands are never answered");
            }
        }
    }
}

#[test]
fn commands_are_ignored_in_initialisation() {
    for init in [RESET_APP, RESET_COMM] {
        for cmd in NmtCommand::ALL {
            let mut d = in_state(init);
            assert_eq!(d.cmd(cmd.cs(), 0, ms(5)), None);
            assert_eq!(d.cmd(cmd.cs(), NODE, ms(5)), None);
            assert_eq!(d.nmt.state(), init);
        }
    }
    // Power-on state, before boot.
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 0);
    assert_eq!(d.nmt.state(), RESET_APP);
    assert_eq!(d.cmd(0x01, NODE, ms(0)), None);
    assert!(d.take().is_empty());
}

#[test]
fn malformed_command_frames_are_ignored() {
    let mut d = in_state(PRE);
    // DLC ≠ 2: CiA 301 defines the command as exactly two bytes.
    assert_eq!(d.rx(Frame::new(0x000, &[0x01]), ms(1)), None);
    assert_eq!(d.rx(Frame::new(0x000, &[0x01, NODE, 0x00]), ms(1)), None);
    assert_eq!(d.rx(Frame::new(0x000, &[0x01, 0, 0, 0, 0, 0, 0, 0]), ms(1)), None);
    assert_eq!(d.rx(Frame::new(0x000, &[]), ms(1)), None);
    // RTR on 000h and an extended frame with id 0.
    assert_eq!(d.rx(Frame::remote(0x000, 2), ms(1)), None);
    let ext = Frame::try_new(CanId::Extended(0), &[0x01, NODE]).unwrap();
    assert_eq!(d.rx(ext, ms(1)), None);
    // Unknown command specifiers.
    for cs in [0x00, 0x03, 0x7F, 0x83, 0xFF] {
        assert_eq!(d.cmd(cs, NODE, ms(1)), None);
        assert_eq!(d.cmd(cs, 0, ms(1)), None);
    }
    assert_eq!(d.nmt.state(), PRE);
    assert!(d.take().is_empty());
}

#[test]
fn boot_up_then_pre_operational() {
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 0);
    assert_eq!(d.boot(ms(7)), Some(NmtEvent::StateChanged { from: RESET_APP, to: PRE }));
    assert_eq!(d.take(), [Frame::new(0x705, &[0x00])]);
    // boot() outside Initialisation does nothing.
    assert_eq!(d.boot(ms(8)), None);
    assert!(d.take().is_empty());
}

#[test]
fn auto_start_goes_operational_after_boot_up() {
    let mut d = Dev::new(NmtConfig { auto_start: true, ..NmtConfig::new(NODE) }, 0, 0);
    assert_eq!(d.boot(ms(0)), Some(NmtEvent::StateChanged { from: RESET_APP, to: OP }));
    assert_eq!(d.take(), [Frame::new(0x705, &[0x00])]);
    assert_eq!(d.nmt.state(), OP);
}

#[test]
fn resets_restart_with_a_new_boot_up() {
    for (cs, ev, sub) in
        [(0x81, NmtEvent::ResetApplication, RESET_APP), (0x82, NmtEvent::ResetCommunication, RESET_COMM)]
    {
        let mut d = in_state(OP);
        assert_eq!(d.cmd(cs, 0, ms(20)), Some(ev));
        assert_eq!(d.nmt.state(), sub);
        assert!(d.take().is_empty(), "the boot-up waits for the node to restore the dictionary");
        // Nothing runs in Initialisation.
        assert_eq!(d.poll(ms(5000)), None);
        assert_eq!(d.boot(ms(21)), Some(NmtEvent::StateChanged { from: sub, to: PRE }));
        assert_eq!(d.take(), [Frame::new(0x705, &[0x00])]);
    }
}

#[test]
fn unconfigured_node_id_waits_in_initialisation() {
    let mut d = Dev::new(NmtConfig::new(0xFF), 0, 0);
    assert_eq!(d.boot(ms(0)), None);
    assert_eq!(d.nmt.state(), RESET_COMM);
    assert!(d.take().is_empty());
    assert!(d.nmt.state().allows(Service::Lss));
    // LSS assigns node-ID 9; the next boot uses it.
    d.nmt.set_node_id(9);
    assert_eq!(d.boot(ms(1)), Some(NmtEvent::StateChanged { from: RESET_COMM, to: PRE }));
    assert_eq!(d.take(), [Frame::new(0x709, &[0x00])]);
    assert_eq!(d.nmt.node_id(), 9);
}

#[test]
fn node_id_change_takes_effect_at_reset_communication() {
    let mut d = Dev::booted();
    d.nmt.set_node_id(6);
    assert_eq!(d.nmt.node_id(), NODE);
    assert_eq!(d.cmd(0x01, 6, ms(1)), None, "not yet node 6");
    d.cmd(0x82, NODE, ms(2));
    d.boot(ms(3));
    assert_eq!(d.take(), [Frame::new(0x706, &[0x00])]);
    assert!(d.cmd(0x01, 6, ms(4)).is_some());
}

#[test]
fn unsupported_command_is_ignored() {
    // KC1 §6.4.1 and AKD §5.4.1 do not list 80h.
    let cfg = NmtConfig {
        supported_commands: CommandSet::ALL.without(NmtCommand::EnterPreOperational),
        ..NmtConfig::new(NODE)
    };
    let mut d = Dev::new(cfg, 0, 0);
    d.boot(ms(0));
    d.cmd(0x01, NODE, ms(1));
    assert_eq!(d.cmd(0x80, NODE, ms(2)), None);
    assert_eq!(d.cmd(0x80, 0, ms(2)), None);
    assert_eq!(d.nmt.state(), OP);
    assert!(d.nmt.config().supported_commands.contains(NmtCommand::ResetNode));
}

#[test]
fn stopped_runs_only_nmt_and_error_control() {
    let mut d = in_state(STOP);
    let s = d.nmt.state();
    for svc in [Service::Pdo, Service::Sdo, Service::Sync, Service::Time, Service::Emcy] {
        assert!(!s.allows(svc), "{svc:?}");
    }
    assert!(s.allows(Service::Nmt) && s.allows(Service::ErrorControl));
    // Error control answers: node guarding with state 04h ...
    d.rx(Frame::remote(0x705, 1), ms(10));
    assert_eq!(d.take(), [Frame::new(0x705, &[0x04])]);
    // ... and a heartbeat consumer still runs (1016h sub 1: node 9, 100 ms).
    d.write(0x1016, 1, &0x0009_0064u32.to_le_bytes(), ms(10)).unwrap();
    assert_eq!(
        d.rx(Frame::new(0x709, &[0x05]), ms(20)),
        Some(NmtEvent::RemoteStateChange { node: 9, state: RemoteState::Operational })
    );
    d.poll(ms(120));
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 9 }]);
}

#[test]
fn local_transitions() {
    let mut d = in_state(PRE);
    assert_eq!(d.nmt.set_state(OP), Some(NmtEvent::StateChanged { from: PRE, to: OP }));
    assert_eq!(d.nmt.set_state(OP), None);
    assert_eq!(d.nmt.set_state(STOP), Some(NmtEvent::StateChanged { from: OP, to: STOP }));
    assert_eq!(d.nmt.set_state(NmtState::Initialisation(InitSubState::Initialising)), None);
    assert_eq!(d.nmt.set_state(RESET_COMM), Some(NmtEvent::ResetCommunication));
    assert_eq!(d.nmt.set_state(OP), None, "boot first");
    assert_eq!(d.nmt.set_state(RESET_APP), Some(NmtEvent::ResetApplication));
    d.boot(ms(5));
    assert_eq!(d.nmt.state(), PRE);
    assert!(d.take().len() == 1);
}
