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
