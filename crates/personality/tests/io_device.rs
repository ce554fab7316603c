//! A CiA 401 module built from its EDS (`crates/cia401/eds/io16.eds`) on
//! the virtual bus, its inputs driven by the machine file's schedule:
//! frames exact, in simulated time.

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_node::{EdsOptions, MemoryStorage};
use drivebus_personality::build::{DeviceApp, EdsDevice, build_device};
use drivebus_personality::machine::MachineFile;

const EDS: &str = include_str!("../../cia401/eds/io16.eds");

const MACHINE: &str = r#"
[[node]]
id = 3
io = { digital_inputs = [2], analog_inputs = [2.5], wiring = { 1 = 16 } }

[[node.inputs]]
at = 0.5
input = "digital"
line = 9
value = 1
duration = 0.25

[[node.inputs]]
at = 1.0
input = "analog"
line = 2
value = -10.0
"#;

fn bus() -> (Bus, drivebus_bus::NodeId, drivebus_bus::ProbeId) {
    let eds = drivebus_eds::parse(EDS).unwrap().eds;
    let m = MachineFile::parse(MACHINE).unwrap().io_machine_for(3).unwrap();
    let (dev, _) =
        build_device(&eds, EDS, 3, Box::new(MemoryStorage::new()), EdsOptions::default(), Some(&m)).unwrap();
    let mut bus = Bus::new(BusConfig::zero_time());
    let probe = bus.attach_probe();
    let id = bus.attach(dev);
    bus.run_for(Duration::from_micros(10));
    (bus, id, probe)
}

#[test]
fn scheduled_inputs_send_tpdos_at_their_times() {
    let (mut bus, _, probe) = bus();
    assert_eq!(bus.take_received(probe), [Frame::new(0x703, &[0])]);
    bus.send_from(probe, Frame::new(0, &[1, 3]));
    bus.run_for(Duration::from_millis(100));
    let t0 = Instant::ZERO;
    let ms = |v: Vec<(Instant, Frame)>| -> Vec<(u128, Frame)> {
        v.into_iter().map(|(t, f)| ((t - t0).as_nanos() / 1_000_000, f)).collect()
    };
    // Operational: the event-driven TPDOs send what the inputs are (line
    // 2; channel 1 at 2.5 V = 8192).
    assert_eq!(
        bus.take_received(probe),
        [Frame::new(0x183, &[0x02, 0x00]), Frame::new(0x283, &[0x00, 0x20, 0, 0, 0, 0, 0, 0])]
    );
    bus.run_for(Duration::from_secs(2));
    // Line 9 high at 0.5 s for 0.25 s; channel 2 to -10 V at 1 s, which
    // sends nothing: 6423h is FALSE (CiA 401's default).
    assert_eq!(
        ms(bus.take_received_timed(probe)),
        [(500, Frame::new(0x183, &[0x02, 0x01])), (750, Frame::new(0x183, &[0x02, 0x00]))]
    );
}

#[test]
fn rpdo1_sets_the_outputs_and_a_wired_one_reads_back() {
    let (mut bus, id, probe) = bus();
    bus.send_from(probe, Frame::new(0, &[1, 3]));
    bus.run_for(Duration::from_millis(1));
    bus.take_received(probe);
    bus.send_from(probe, Frame::new(0x203, &[0x01, 0x80]));
    bus.run_for(Duration::from_millis(1));
    let dev = bus.node::<EdsDevice>(id).unwrap();
    let DeviceApp::Io(io) = &dev.app else { panic!("not an I/O module") };
    assert_eq!(io.module.output_lines(), [0x01, 0x80]);
    assert_eq!(dev.node.od().get_u32(0x6200, 2), Some(0x80));
    // Output 1 is wired to input 16.
    assert_eq!(bus.take_received(probe), [Frame::new(0x183, &[0x02, 0x80])]);
}

#[test]
fn drive_keys_are_refused_for_a_device_node() {
    let f = MachineFile::parse("[[node]]\nid = 3\nlimits = { negative = -1.0, positive = 1.0 }\n").unwrap();
    let e = f.io_machine_for(3).unwrap_err();
    assert!(e.message.contains("limits"), "{e}");
    assert_eq!(e.line, 2);
    let f = MachineFile::parse("[[node]]\nid = 3\n[[node.inputs]]\nat = 1.0\ninput = \"brake\"\nvalue = 1\n")
        .unwrap();
    assert_eq!(f.io_machine_for(3).unwrap_err().line, 5);
}

/// 6423h TRUE (CiA 401: analog interrupts on): the scheduled change of
/// channel 2 at 1 s sends TPDO2 then (6421h's default 7: a change by the
/// delta 6426h = 0, i.e. any change), with both channels.
#[test]
fn analog_interrupts_send_tpdo2_once_enabled() {
    let (mut bus, _, probe) = bus();
    bus.send_from(probe, Frame::new(0, &[1, 3]));
    bus.run_for(Duration::from_millis(100));
    bus.take_received(probe);
    // SDO download 6423h:00 = 1.
    bus.send_from(probe, Frame::new(0x603, &[0x2F, 0x23, 0x64, 0x00, 0x01, 0, 0, 0]));
    bus.run_for(Duration::from_millis(100));
    assert_eq!(bus.take_received(probe), [Frame::new(0x583, &[0x60, 0x23, 0x64, 0, 0, 0, 0, 0])]);
    bus.run_for(Duration::from_millis(1000));
    let got: Vec<(u128, Frame)> = bus
        .take_received_timed(probe)
        .into_iter()
        .map(|(t, f)| ((t - Instant::ZERO).as_nanos() / 1_000_000, f))
        .filter(|(_, f)| f.id().raw() == 0x283)
        .collect();
    // -10 V is -32767 (0x8001).
    assert_eq!(got, [(1000, Frame::new(0x283, &[0x00, 0x20, 0x01, 0x80, 0, 0, 0, 0]))]);
}
