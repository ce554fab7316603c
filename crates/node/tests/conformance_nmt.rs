//! Conformance-style cases, category NMT (CiA 301 §7.2.8.3.1, §7.3.2).

mod common;
use common::*;
use drivebus_can::Duration;
use drivebus_node::NmtState;

#[test]
fn nmt_01_boot_up_then_pre_operational() {
    let r = Rig::new(device());
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
}

#[test]
fn nmt_02_start_stop_preop_addressed_and_broadcast() {
    let mut r = Rig::new(device());
    r.exchange("000#0105", &[]);
    assert_eq!(r.node().nmt_state(), NmtState::Operational);
    r.exchange("000#0200", &[]);
    assert_eq!(r.node().nmt_state(), NmtState::Stopped);
    r.exchange("000#8005", &[]);
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    // Another node's command changes nothing.
    r.exchange("000#0106", &[]);
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    // Wrong length is ignored (exactly two bytes, §7.2.8.3.1).
    r.exchange("000#01", &[]);
    r.exchange("000#010500", &[]);
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
}

#[test]
fn nmt_03_reset_node_and_reset_communication_boot_up_again() {
    let mut r = Rig::new(device());
    r.exchange("000#8105", &["705#00"]);
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    r.exchange("000#0105", &[]);
    r.exchange("000#8200", &["705#00"]);
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
}

#[test]
fn nmt_04_stopped_answers_no_sdo_but_nmt_and_guarding() {
    let mut r = Rig::new(device());
    r.exchange("000#0205", &[]);
    r.exchange("605#4000100000000000", &[]);
    // Node guarding still answers in stopped: state 4, toggle 0.
    r.exchange("705#R1", &["705#04"]);
    r.exchange("000#8005", &[]);
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
}

#[test]
fn nmt_05_reset_communication_restores_communication_parameters() {
    let mut r = Rig::new(device());
    let w = r.sdo_write(5, 0x1017, 0, &[0x64, 0x00]);
    Rig::assert_written(w, 5, 0x1017, 0);
    r.exchange("000#8205", &["705#00"]);
    // 1017h is back to its default (0): no heartbeat within a second.
    r.run_for(Duration::from_secs(1));
    assert!(r.take().is_empty());
    let v = r.sdo_read(5, 0x1017, 0);
    assert_eq!(v, fr("585#4B17100000000000"));
}
