//! Local NMT commands (`Node::nmt_command`): the device changes its own
//! NMT state as if the command had come from the master (CiA 301
//! §7.3.2.2), whatever set of remote commands it implements.

use drivebus_can::{Frame, Instant};
use drivebus_nmt::CommandSet;
use drivebus_node::{NmtCommand, NmtState, Node, NodeConfig};
use drivebus_od::NoHooks;

fn at(ms: u64) -> Instant {
    Instant::from_nanos(ms * 1_000_000)
}

#[test]
fn local_start_stop_and_reset() {
    let mut cfg = NodeConfig::new(5);
    // A device that takes no remote Start: the local command still applies.
    cfg.nmt.supported_commands = CommandSet::ALL.without(NmtCommand::Start);
    let mut node = Node::new(cfg);
    let mut out: Vec<Frame> = Vec::new();
    node.boot(at(0), &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new(0x705, &[0x00])]);
    assert_eq!(node.nmt_state(), NmtState::PreOperational);

    // The remote Start is ignored (not implemented) …
    out.clear();
    node.handle_frame(&Frame::new(0x000, &[0x01, 0x05]), at(1), &mut NoHooks, &mut out);
    assert_eq!(node.nmt_state(), NmtState::PreOperational);
    // … the local one is carried out, silently (CiA 301 Figure 48: a state
    // change sends nothing; heartbeat/guarding report it).
    node.nmt_command(NmtCommand::Start, at(2), &mut NoHooks, &mut out);
    assert_eq!(node.nmt_state(), NmtState::Operational);
    assert!(out.is_empty(), "{out:?}");

    node.nmt_command(NmtCommand::Stop, at(3), &mut NoHooks, &mut out);
    assert_eq!(node.nmt_state(), NmtState::Stopped);
    node.nmt_command(NmtCommand::EnterPreOperational, at(4), &mut NoHooks, &mut out);
    assert_eq!(node.nmt_state(), NmtState::PreOperational);

    // Reset node / reset communication end in a new boot-up message and
    // pre-operational (CiA 301 §7.3.2.2.1, Figure 48 transitions 12/13).
    node.nmt_command(NmtCommand::Start, at(5), &mut NoHooks, &mut out);
    node.nmt_command(NmtCommand::ResetNode, at(6), &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new(0x705, &[0x00])]);
    assert_eq!(node.nmt_state(), NmtState::PreOperational);
    out.clear();
    node.nmt_command(NmtCommand::ResetCommunication, at(7), &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new(0x705, &[0x00])]);
    assert_eq!(node.nmt_state(), NmtState::PreOperational);
}
