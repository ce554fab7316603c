//! Bus-off of one node and its automatic recovery (issue 17 §3), frame
//! exact on the bit-timed virtual bus: the controller recovers after
//! 128 × 11 recessive bits (ISO 11898-1), then the node sends the CiA 301
//! EMCY 8140h "recovered from bus off" with 1001h bit 4 (communication
//! error) and its error reset; 1001h holds bit 4 while bus-off.

mod common;
use common::*;
use drivebus_bus::{Bus, BusConfig, FaultRule, LinkState};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_node::{Node, NodeDevice};
use drivebus_od::NoHooks;

fn read(bus: &mut Bus, dut: drivebus_bus::NodeId, index: u16, sub: u8) -> Vec<u8> {
    let now = bus.now();
    let dev = bus.node_mut::<NodeDevice>(dut).expect("dut");
    dev.read_object(index, sub, now).expect("readable").to_vec()
}

#[test]
fn bus_off_recovers_after_128_times_11_bits_and_sends_8140h() {
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let probe = bus.attach_probe();
    let dut = bus.attach(NodeDevice::new(Node::new(device()), NoHooks));
    bus.run_for(Duration::from_millis(1));
    // 1017h = 20 ms heartbeat.
    bus.send_from(probe, fr("605#2B17100014000000"));
    bus.run_for(Duration::from_millis(5));
    assert_eq!(bus.take_received(probe), frs(&["705#00", "585#6017100000000000"]));

    // The next heartbeat is destroyed and the controller goes bus-off.
    bus.add_fault(FaultRule::bus_off().from(dut).times(1));
    while bus.link_state(dut) == Some(LinkState::Active) {
        bus.step().expect("the heartbeat is due");
    }
    let off_at = bus.now();
    let Some(LinkState::BusOff { recover_at: Some(back) }) = bus.link_state(dut) else {
        panic!("bus-off with automatic recovery: {:?}", bus.link_state(dut))
    };
    // 128 × 11 bits at 125 kbit/s.
    assert_eq!(back - off_at, Duration::from_micros(11_264));
    // 1001h: generic + communication error; 1003h sub 1: 8140h.
    assert_eq!(read(&mut bus, dut, 0x1001, 0), [0x11]);
    assert_eq!(read(&mut bus, dut, 0x1003, 1), 0x8140u32.to_le_bytes());

    // Silent while bus-off; an SDO request is not heard.
    bus.send_from(probe, fr("605#4000100000000000"));
    bus.run_until(Instant::from_micros(back.as_micros() - 1));
    assert_eq!(bus.take_received(probe), []);
    assert!(matches!(bus.link_state(dut), Some(LinkState::BusOff { .. })));

    // Recovered: 8140h with 1001h = 11h, its reset, then the heartbeat.
    bus.run_until(back + Duration::from_millis(25));
    assert_eq!(bus.link_state(dut), Some(LinkState::Active));
    let got: Vec<(Instant, Frame)> = bus.received(probe).to_vec();
    let frames: Vec<Frame> = got.iter().map(|(_, f)| *f).collect();
    assert_eq!(frames, frs(&["085#4081110000000000", "085#0000000000000000", "705#7F"]));
    assert!(got[0].0 > back && got[0].0 < back + Duration::from_millis(1), "at once: {:?}", got[0].0);
    assert_eq!(read(&mut bus, dut, 0x1001, 0), [0x00]);
    assert_eq!(read(&mut bus, dut, 0x1003, 1), 0x8140u32.to_le_bytes());
    // SDO works again.
    bus.take_received(probe);
    bus.send_from(probe, fr("605#4000100000000000"));
    bus.run_for(Duration::from_millis(2));
    assert_eq!(bus.take_received(probe), frs(&["585#4300100092010200"]));
}

#[test]
fn manual_recovery_sends_8140h_too_and_1029h_reacts_to_bus_off() {
    // Without automatic recovery the node stays off until recovered by
    // hand (what `drivebus control bus on NODE` does).
    let mut bus = Bus::new(BusConfig { auto_recovery: false, ..BusConfig::with_bitrate(1_000_000) });
    let probe = bus.attach_probe();
    let dut = bus.attach(NodeDevice::new(Node::new(device()), NoHooks));
    bus.run_for(Duration::from_millis(1));
    // Operational: 1029h sub 1 = 0 (default) sends it to pre-operational
    // on a communication error, which bus-off is (CiA 301 §7.5.2.32).
    bus.send_from(probe, fr("000#0105"));
    bus.run_for(Duration::from_millis(1));
    bus.take_received(probe);
    bus.set_bus_off(dut);
    bus.run_for(Duration::from_millis(100));
    assert_eq!(bus.link_state(dut), Some(LinkState::BusOff { recover_at: None }));
    assert_eq!(bus.take_received(probe), []);
    assert_eq!(read(&mut bus, dut, 0x1001, 0), [0x11]);
    bus.recover(dut);
    bus.run_for(Duration::from_millis(1));
    assert_eq!(bus.take_received(probe), frs(&["085#4081110000000000", "085#0000000000000000"]));
    let now = bus.now();
    let node = &bus.node::<NodeDevice>(dut).expect("dut").node;
    assert_eq!(node.nmt_state(), drivebus_nmt::NmtState::PreOperational, "at {now:?}");
}
