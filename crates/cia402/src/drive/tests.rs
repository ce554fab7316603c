//! Unit tests on the drive's private state (what the bus cannot reach).

use super::*;
use crate::homing::HomingMode;
use drivebus_node::NodeConfig;

fn hm_drive() -> (Node, Drive) {
    let mut node = Node::new(NodeConfig::new(1));
    let handlers: Vec<Box<dyn ModeHandler + Send>> = alloc::vec![Box::new(HomingMode::default())];
    let mut d = Drive::install_with(&mut node, DriveConfig::default(), handlers).unwrap();
    let od = node.od_mut();
    d.request_mode(od, op::HM);
    for cw in [0x06, 0x07, 0x0F] {
        d.controlword(od, cw);
    }
    d.step_n(od, 8);
    (node, d)
}

/// CiA 402-2 §6.2.2: in hm, bit 13 is "homing error" and only the homing
/// handler sets it; the drive's following-error flag must not leak in.
#[test]
fn drive_following_error_does_not_set_bit13_in_hm() {
    let (mut node, mut d) = hm_drive();
    assert_eq!(d.statusword() & 0x3400, 0x0400, "homing not started");
    // The drive's own supervision flag is up (as while 6065h is exceeded).
    d.sup.fe_active = true;
    d.step_n(node.od_mut(), 1);
    assert_eq!(d.state_machine().state(), crate::state_machine::State::OperationEnabled);
    assert_eq!(d.statusword() & 0x3400, 0x0400, "bit 13 is the handler's: {:04X}", d.statusword());
}

/// In pp (the drive's own mode) bit 13 is the drive's following error.
#[test]
fn drive_following_error_sets_bit13_in_pp() {
    let mut node = Node::new(NodeConfig::new(1));
    let mut d = Drive::install(&mut node, DriveConfig::default()).unwrap();
    let od = node.od_mut();
    for cw in [0x06, 0x07, 0x0F] {
        d.controlword(od, cw);
    }
    d.step_n(od, 8);
    d.sup.fe_active = true;
    // The flag is read by the mode step, before supervision re-evaluates it.
    d.step_n(od, 1);
    assert_eq!(d.statusword() & 0x2000, 0x2000);
}

fn enabled_pp() -> (Node, Drive) {
    let mut node = Node::new(NodeConfig::new(1));
    let mut cfg = DriveConfig::default();
    // 605Ah 6: stay in Quick stop active (the quick stop's end is visible).
    cfg.options.set_quick_stop(6).unwrap();
    let mut d = Drive::install(&mut node, cfg).unwrap();
    let od = node.od_mut();
    for cw in [0x06, 0x07, 0x0F] {
        d.controlword(od, cw);
    }
    d.step_n(od, 8);
    (node, d)
}

/// `set_fault_action`: a per-code reaction instead of 605Eh.
#[test]
fn error_reactions_replace_the_fault_reaction() {
    use crate::state_machine::{Reaction, State};
    // Quick stop: EMCY, Quick stop active, no fault; cleared when enabled again.
    let (mut node, mut d) = enabled_pp();
    d.set_fault_action(0x1234, Some(ErrorReaction::QuickStop));
    d.inject(Injection::Fault(0x1234));
    d.step_n(node.od_mut(), 2);
    assert_eq!(d.state_machine().state(), State::QuickStopActive);
    assert_eq!(d.emcy, alloc::vec![EmcyRequest::Raise(0x1234)]);
    d.emcy.clear();
    d.step_n(node.od_mut(), 4000);
    d.controlword(node.od_mut(), 0x0F);
    assert_eq!(d.state_machine().state(), State::OperationEnabled);
    assert_eq!(d.emcy, alloc::vec![EmcyRequest::Clear(0x1234)]);
    // Warning: EMCY and statusword bit 7, the motion goes on.
    let (mut node, mut d) = enabled_pp();
    d.set_fault_action(0x1234, Some(ErrorReaction::Warning));
    d.inject(Injection::Fault(0x1234));
    d.step_n(node.od_mut(), 2);
    assert_eq!(d.state_machine().state(), State::OperationEnabled);
    assert_eq!(d.statusword() & 0x80, 0x80);
    // Fault with its own reaction: disable at once despite 605Eh = 2.
    let (mut node, mut d) = enabled_pp();
    d.set_fault_action(0x1234, Some(ErrorReaction::React(Reaction::DisableDrive)));
    d.inject(Injection::Fault(0x1234));
    d.step_n(node.od_mut(), 2);
    assert_eq!(d.state_machine().state(), State::Fault);
    // `None` restores 605Eh: a fault again.
    let (mut node, mut d) = enabled_pp();
    d.set_fault_action(0x1234, Some(ErrorReaction::Warning));
    d.set_fault_action(0x1234, None);
    d.inject(Injection::Fault(0x1234));
    d.step_n(node.od_mut(), 2);
    assert_eq!(d.state_machine().state(), State::Fault);
}
