//! Error behaviour 1029h (CiA 301 §7.5.2.32; DDS6 §6.3.17).

mod common;

use common::{Dev, NODE, ms};
use drivebus_can::Frame;
use drivebus_nmt::{ErrorAction, ErrorClass, NmtConfig, NmtEvent, NmtState};
use drivebus_od::SdoAbort;

const PRE: NmtState = NmtState::PreOperational;
const OP: NmtState = NmtState::Operational;
const STOP: NmtState = NmtState::Stopped;

fn reaction(value: u8, from: NmtState) -> (Option<NmtEvent>, NmtState) {
    let mut d = Dev::booted();
    d.write(0x1029, 1, &[value], ms(0)).unwrap();
    d.nmt.set_state(from);
    let ev = d.nmt.on_error(ErrorClass::COMMUNICATION);
    (ev, d.nmt.state())
}

#[test]
fn communication_error_reactions() {
    // 0: pre-operational, only from operational.
    assert_eq!(reaction(0, OP), (Some(NmtEvent::StateChanged { from: OP, to: PRE }), PRE));
    assert_eq!(reaction(0, PRE), (None, PRE));
    assert_eq!(reaction(0, STOP), (None, STOP));
    // 1: no change.
    for s in [PRE, OP, STOP] {
        assert_eq!(reaction(1, s), (None, s));
    }
    // 2: stopped.
    assert_eq!(reaction(2, OP), (Some(NmtEvent::StateChanged { from: OP, to: STOP }), STOP));
    assert_eq!(reaction(2, PRE), (Some(NmtEvent::StateChanged { from: PRE, to: STOP }), STOP));
    assert_eq!(reaction(2, STOP), (None, STOP));
    // 128..255: manufacturer-specific, the node implements it.
    assert_eq!(reaction(0x80, OP), (None, OP));
}

#[test]
fn reserved_values_are_refused() {
    let mut d = Dev::booted();
    for v in [3u8, 50, 127] {
        assert_eq!(d.write(0x1029, 1, &[v], ms(0)), Err(SdoAbort::INVALID_VALUE));
    }
    d.write(0x1029, 2, &[2], ms(0)).unwrap();
    d.write(0x1029, 1, &[0xFF], ms(0)).unwrap();
    assert_eq!(d.nmt.error_action(ErrorClass::COMMUNICATION), ErrorAction::Manufacturer(0xFF));
    assert_eq!(d.nmt.error_action(ErrorClass(2)), ErrorAction::Stopped);
    // A class beyond 1029h uses the CiA 301 default 0.
    assert_eq!(d.nmt.error_action(ErrorClass(9)), ErrorAction::PreOperational);
}

#[test]
fn other_classes_are_independent() {
    let mut d = Dev::booted();
    d.write(0x1029, 1, &[1], ms(0)).unwrap();
    d.write(0x1029, 2, &[2], ms(0)).unwrap();
    d.nmt.set_state(OP);
    assert_eq!(d.nmt.on_error(ErrorClass::COMMUNICATION), None);
    assert_eq!(d.nmt.on_error(ErrorClass(2)), Some(NmtEvent::StateChanged { from: OP, to: STOP }));
}

#[test]
fn no_reaction_in_initialisation() {
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 1);
    assert_eq!(d.nmt.on_error(ErrorClass::COMMUNICATION), None);
    d.od.set_value(0x1029, 1, &drivebus_od::Value::U8(2)).unwrap();
    assert_eq!(d.nmt.on_error(ErrorClass::COMMUNICATION), None);
    assert!(d.nmt.state().is_initialisation());
}

#[test]
fn values_survive_boot_and_are_read_from_the_dictionary() {
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 1);
    d.od.set_value(0x1029, 1, &drivebus_od::Value::U8(2)).unwrap();
    d.boot(ms(0));
    assert_eq!(d.nmt.error_action(ErrorClass::COMMUNICATION), ErrorAction::Stopped);
}

#[test]
fn personality_without_1029h() {
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 0);
    d.boot(ms(0));
    d.nmt.set_state(OP);
    // Default 0: pre-operational.
    assert_eq!(d.nmt.error_action(ErrorClass::COMMUNICATION), ErrorAction::PreOperational);
    d.nmt.set_error_behaviour(ErrorClass::COMMUNICATION, 1);
    d.boot(ms(1)); // not in Initialisation: ignored, the value stays
    assert_eq!(d.nmt.on_error(ErrorClass::COMMUNICATION), None);
    assert_eq!(d.nmt.state(), OP);
}

/// The wiring the node does: a heartbeat timeout is a communication error.
#[test]
fn heartbeat_timeout_drives_the_reaction() {
    let mut d = Dev::booted();
    d.write(0x1029, 1, &[0], ms(0)).unwrap();
    d.write(0x1016, 1, &0x0002_0064u32.to_le_bytes(), ms(0)).unwrap();
    d.cmd(0x01, 0, ms(0));
    d.rx(Frame::new(0x702, &[0x05]), ms(0));
    d.poll(ms(100));
    for ev in d.events() {
        if matches!(ev, NmtEvent::HeartbeatTimeout { .. } | NmtEvent::LifeGuardingLost) {
            assert_eq!(
                d.nmt.on_error(ErrorClass::COMMUNICATION),
                Some(NmtEvent::StateChanged { from: OP, to: PRE })
            );
        }
    }
    assert_eq!(d.nmt.state(), PRE);
}
