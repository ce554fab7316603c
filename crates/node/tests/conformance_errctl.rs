//! Conformance-style cases, categories heartbeat and node guarding
//! (CiA 301 §7.2.8.3.2), with exact timing.

mod common;
use common::*;
use drivebus_can::Duration;
use drivebus_node::NmtState;

#[test]
fn hb_01_producer_period_and_state_byte() {
    let mut r = Rig::new(device());
    let t0 = r.now();
    Rig::assert_written(r.sdo_write(5, 0x1017, 0, &100u16.to_le_bytes()), 5, 0x1017, 0);
    r.run_for(Duration::from_millis(250));
    let hb: Vec<_> = r.take_timed_ms(t0).into_iter().map(|(t, f)| (t.round() as u64, f)).collect();
    assert_eq!(hb, vec![(100, fr("705#7F")), (200, fr("705#7F"))]);
    r.send("000#0105");
    r.run_for(Duration::from_millis(100));
    assert_eq!(r.take(), frs(&["705#05"]));
}

#[test]
fn hb_02_consumer_timeout_raises_8130_and_applies_1029h() {
    let mut r = Rig::new(device());
    // Monitor node 6 with 150 ms; go operational.
    Rig::assert_written(r.sdo_write(5, 0x1016, 1, &0x0006_0096u32.to_le_bytes()), 5, 0x1016, 1);
    r.send("000#0105");
    // Monitoring starts with the first heartbeat.
    r.send("706#05");
    r.run_for(Duration::from_millis(149));
    assert!(r.take().is_empty());
    r.run_for(Duration::from_millis(2));
    // EMCY 8130h, 1001h = generic | communication; 1029h default 0 → pre-operational.
    assert_eq!(r.take(), frs(&["085#3081110000000000"]));
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    // Recovery clears the error: error-reset EMCY.
    r.send("706#05");
    assert_eq!(r.take(), frs(&["085#0000000000000000"]));
}

/// `NodeConfig::comm_error_emcy`: the same loss in a device's own EMCY
/// form (KC1/AKD: register 10h without the generic bit, category 01h).
#[test]
fn hb_02b_consumer_timeout_emcy_in_the_device_form() {
    let mut cfg = device();
    cfg.comm_error_emcy = Some((0x10, [0x01, 0, 0, 0, 0]));
    let mut r = Rig::new(cfg);
    Rig::assert_written(r.sdo_write(5, 0x1016, 1, &0x0006_0096u32.to_le_bytes()), 5, 0x1016, 1);
    r.send("000#0105");
    r.send("706#05");
    r.run_for(Duration::from_millis(151));
    assert_eq!(r.take(), frs(&["085#3081100100000000"]));
    assert_eq!(r.node().od().get_u32(0x1001, 0), Some(0x10));
    r.send("706#05");
    assert_eq!(r.take(), frs(&["085#0000000000000000"]));
}

#[test]
fn hb_03_duplicate_consumer_entry_is_refused() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1016, 1, &0x0006_0096u32.to_le_bytes()), 5, 0x1016, 1);
    let resp = r.sdo_write(5, 0x1016, 2, &0x0006_00C8u32.to_le_bytes());
    Rig::assert_abort(resp, 5, 0x1016, 2, 0x0604_0043);
}

#[test]
fn ng_01_guarding_toggle_and_state() {
    let mut r = Rig::new(device());
    r.exchange("705#R1", &["705#7F"]);
    r.exchange("705#R1", &["705#FF"]);
    r.send("000#0105");
    r.exchange("705#R1", &["705#05"]);
    r.exchange("705#R1", &["705#85"]);
}

#[test]
fn ng_02_life_guarding_loss() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x100C, 0, &100u16.to_le_bytes()), 5, 0x100C, 0);
    Rig::assert_written(r.sdo_write(5, 0x100D, 0, &[3]), 5, 0x100D, 0);
    r.send("000#0105");
    r.exchange("705#R1", &["705#05"]);
    r.run_for(Duration::from_millis(299));
    assert!(r.take().is_empty());
    r.run_for(Duration::from_millis(2));
    assert_eq!(r.take(), frs(&["085#3081110000000000"]));
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    // The master comes back: guarding resolves, the error clears.
    r.exchange("705#R1", &["705#FF", "085#0000000000000000"]);
}

#[test]
fn ng_03_no_guarding_answer_while_heartbeat_runs() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1017, 0, &1000u16.to_le_bytes()), 5, 0x1017, 0);
    r.exchange("705#R1", &[]);
}
