//! Inputs and faults changed while the bus runs (issue 17 §3), seen by
//! our master on the virtual bus in simulated time: a digital input in
//! 60FDh, an encoder fault's EMCY and its recovery after the clear, a node
//! powered off and on, a node bus-off and recovered (by hand, and by itself
//! with the EMCY 8140h), frames dropped or
//! corrupted by a rule.

use std::time::Duration;

use drivebus_bus::{Bus, BusConfig, FaultRule, ProbeId};
use drivebus_can::Instant;
use drivebus_master::{DriveState, MasterConfig, MasterEvent, SdoError, SimBus};
use drivebus_personality::machine::{Change, FaultKind, Input};
use drivebus_personality::{PersonalityDevice, Profile};

const NODE: u8 = 5;

fn generic() -> (SimBus, ProbeId, drivebus_bus::NodeId) {
    generic_on(BusConfig::with_bitrate(1_000_000))
}

fn generic_on(cfg: BusConfig) -> (SimBus, ProbeId, drivebus_bus::NodeId) {
    let mut bus = Bus::new(cfg);
    let id = bus.attach(Profile::Generic.build_on_default_machine(NODE).unwrap());
    let probe = bus.attach_probe();
    let cfg = MasterConfig { sdo_timeout: Duration::from_millis(300), ..Default::default() };
    let mut sim = SimBus::with_config(bus, cfg);
    sim.set_limit(Duration::from_secs(60));
    (sim, probe, id)
}

/// Makes `change` on the running drive, as the control interface does.
fn change(sim: &mut SimBus, id: drivebus_bus::NodeId, change: Change) {
    let bus = sim.bus_mut();
    let now = bus.now();
    let dev = bus.node_mut::<PersonalityDevice>(id).expect("the drive has power");
    dev.app.change_machine(now, change, None).unwrap();
    bus.wake(id);
}

fn emcy_codes(bus: &Bus, probe: ProbeId) -> Vec<u16> {
    bus.received(probe)
        .iter()
        .filter(|(_, f)| f.std_id() == Some(0x80 + u16::from(NODE)) && f.len() == 8)
        .map(|(_, f)| u16::from_le_bytes([f.data()[0], f.data()[1]]))
        .collect()
}

#[test]
fn a_digital_input_set_at_run_time_shows_in_60fd() {
    let (mut sim, _, id) = generic();
    let m = sim.master().clone();
    let read = || async { m.sdo(NODE).read::<u32>(0x60FD, 0).await.unwrap() };
    let before = sim.block_on(read()).unwrap();
    assert_eq!(before & (1 << 18), 0);
    change(&mut sim, id, Change::Input(Input::Digital { line: 3, level: true }));
    sim.run_for(Duration::from_millis(5));
    // generic: line n in 60FDh bit 15 + n.
    assert_ne!(sim.block_on(read()).unwrap() & (1 << 18), 0);
    change(&mut sim, id, Change::Input(Input::Digital { line: 3, level: false }));
    sim.run_for(Duration::from_millis(5));
    assert_eq!(sim.block_on(read()).unwrap() & (1 << 18), 0);
}

#[test]
fn a_bad_input_is_refused_naming_the_key() {
    let (mut sim, _, id) = generic();
    let bus = sim.bus_mut();
    let now = bus.now();
    let dev = bus.node_mut::<PersonalityDevice>(id).unwrap();
    let e = dev
        .app
        .change_machine(now, Change::Input(Input::Digital { line: 17, level: true }), None)
        .unwrap_err();
    assert_eq!(e.key, "line");
}

#[test]
fn an_encoder_fault_sends_its_emcy_and_clears_for_a_fault_reset() {
    let (mut sim, probe, id) = generic();
    let m = sim.master().clone();
    let d = sim.block_on(m.drive(NODE)).unwrap().unwrap().with_timeout(Duration::from_millis(500));
    sim.block_on(d.enable()).unwrap().unwrap();
    change(&mut sim, id, Change::Fault(FaultKind::Encoder));
    sim.run_for(Duration::from_millis(50));
    assert!(emcy_codes(sim.bus(), probe).contains(&0x7305), "{:?}", emcy_codes(sim.bus(), probe));
    assert_eq!(sim.block_on(d.state()).unwrap().unwrap(), DriveState::Fault);
    // While the encoder is broken the fault comes back.
    let _ = sim.block_on(d.fault_reset()).unwrap();
    sim.run_for(Duration::from_millis(50));
    assert_eq!(sim.block_on(d.state()).unwrap().unwrap(), DriveState::Fault);
    change(&mut sim, id, Change::ClearFaults);
    sim.run_for(Duration::from_millis(20));
    assert!(sim.block_on(d.fault_reset()).unwrap().unwrap());
    sim.run_for(Duration::from_millis(50));
    assert_eq!(sim.block_on(d.state()).unwrap().unwrap(), DriveState::SwitchOnDisabled);
    sim.block_on(d.enable()).unwrap().unwrap();
}

#[test]
fn a_node_powered_off_stops_its_heartbeat_and_boots_when_powered_on() {
    let (mut sim, probe, id) = generic();
    let m = sim.master().clone();
    sim.block_on(async { m.sdo(NODE).write::<u16>(0x1017, 0, 100).await.unwrap() }).unwrap();
    let hb = |bus: &Bus, from: Instant| {
        bus.received(probe)
            .iter()
            .filter(|(t, f)| *t >= from && f.std_id() == Some(0x700 + u16::from(NODE)))
            .map(|(_, f)| f.data()[0])
            .collect::<Vec<u8>>()
    };
    sim.run_for(Duration::from_millis(500));
    let off_at = sim.now();
    assert!(sim.bus_mut().power_off(id).is_some());
    sim.run_for(Duration::from_millis(500));
    assert!(hb(sim.bus(), off_at).is_empty());
    let on_at = sim.now();
    assert!(sim.bus_mut().power_on(id, Profile::Generic.build_on_default_machine(NODE).unwrap()));
    sim.run_for(Duration::from_millis(50));
    // Boot-up (00h); the heartbeat time written before was volatile.
    assert_eq!(hb(sim.bus(), on_at), [0x00]);
    assert_eq!(sim.block_on(async { m.sdo(NODE).read::<u16>(0x1017, 0).await.unwrap() }).unwrap(), 0);
}

#[test]
fn dropped_responses_time_out_then_the_sdo_succeeds() {
    let (mut sim, _, _) = generic();
    let m = sim.master().clone();
    let rule = sim.bus_mut().add_fault(FaultRule::drop_frames().id(0x580 + u32::from(NODE)).times(1));
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert!(matches!(r, Err(SdoError::Timeout)), "{r:?}");
    assert!(sim.bus().fault(rule).is_some_and(|r| r.is_spent()));
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert_eq!(r.unwrap(), 0x0002_0192);
}

#[test]
fn a_bus_off_node_is_silent_until_it_recovers() {
    // Recovery by hand (the default recovers after 128 × 11 recessive bits).
    let (mut sim, probe, id) =
        generic_on(BusConfig { auto_recovery: false, ..BusConfig::with_bitrate(1_000_000) });
    let m = sim.master().clone();
    sim.block_on(async { m.sdo(NODE).write::<u16>(0x1017, 0, 50).await.unwrap() }).unwrap();
    sim.bus_mut().set_bus_off(id);
    let off_at = sim.now();
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert!(matches!(r, Err(SdoError::Timeout)), "{r:?}");
    let heard = |bus: &Bus, from: Instant| {
        bus.received(probe).iter().filter(|(t, f)| *t > from && f.std_id() == Some(0x705)).count()
    };
    assert_eq!(heard(sim.bus(), off_at), 0);
    sim.bus_mut().recover(id);
    let on_at = sim.now();
    sim.run_for(Duration::from_millis(120));
    assert!(heard(sim.bus(), on_at) >= 2, "heartbeats again");
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert_eq!(r.unwrap(), 0x0002_0192);
}

#[test]
fn a_node_that_keeps_going_bus_off_is_lost_then_recovers_by_itself_with_8140h() {
    // A broken transceiver: every frame of the node ends in an error
    // frame, its controller goes bus-off, recovers by itself after
    // 128 × 11 bits, and goes bus-off again, until the fault goes.
    let (mut sim, _, id) = generic();
    let m = sim.master().clone();
    sim.block_on(async { m.sdo(NODE).write::<u16>(0x1017, 0, 10).await.unwrap() }).unwrap();
    let mut ev = m.subscribe_events();
    m.monitor_heartbeat(NODE, Some(Duration::from_millis(30)));
    sim.run_for(Duration::from_millis(50));
    let rule = sim.bus_mut().add_fault(FaultRule::corrupt().from(id));
    sim.run_for(Duration::from_millis(100));
    assert!(sim.bus().stats().bus_off >= 2, "bus-off again after each recovery: {:?}", sim.bus().stats());
    sim.bus_mut().remove_fault(rule);
    sim.run_for(Duration::from_millis(100));
    let mut seen = Vec::new();
    while let Ok(e) = ev.try_recv() {
        match e {
            MasterEvent::HeartbeatLost { node: NODE } => seen.push("lost"),
            MasterEvent::Emcy { node: NODE, code: 0x8140, register, ref text, .. } => {
                assert_eq!(register & 0x11, 0x11, "generic + communication error");
                assert_eq!(text.as_deref(), Some("Recovered from bus off"));
                seen.push("8140h");
            }
            MasterEvent::HeartbeatRecovered { node: NODE } => seen.push("recovered"),
            _ => {}
        }
    }
    assert_eq!(seen, ["lost", "8140h", "recovered"]);
    assert!(!m.node_status(NODE).unwrap().lost);
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert_eq!(r.unwrap(), 0x0002_0192);
}

#[test]
fn a_corrupted_response_is_retransmitted_and_a_silent_one_is_refused() {
    let (mut sim, _, _) = generic();
    let m = sim.master().clone();
    // A CRC error: an error frame, the controller sends it again.
    sim.bus_mut().add_fault(FaultRule::corrupt().id(0x585).times(1));
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert_eq!(r.unwrap(), 0x0002_0192);
    assert_eq!(sim.bus().stats().error_frames, 1);
    // Corruption the CRC misses: the command specifier becomes 0xBF, not
    // an SDO response the master accepts.
    sim.bus_mut().add_fault(FaultRule::corrupt_with([0xFC, 0, 0, 0, 0, 0, 0, 0]).id(0x585).times(1));
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert!(r.is_err(), "{r:?}");
    let r = sim.block_on(async { m.sdo(NODE).read::<u32>(0x1000, 0).await }).unwrap();
    assert_eq!(r.unwrap(), 0x0002_0192);
}
