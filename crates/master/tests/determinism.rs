//! The simulated-time driver is repeatable: the same calls give the same
//! frames, in the same order, at the same times (what `drivebus demo` and
//! the Python package's `Simulation` promise).

use drivebus_bus::{Bus, BusConfig};
use drivebus_master::{ScanOptions, SimBus};
use drivebus_personality::Profile;

/// A scan of 1..40 with one drive present: 39 probes time out at once.
fn scan_log() -> Vec<String> {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    bus.attach(Profile::Akd.build_on_default_machine(1).unwrap());
    let mut sim = SimBus::new(bus);
    let m = sim.master().clone();
    let found = sim.block_on(m.scan_with(ScanOptions { nodes: 1..=40, ..Default::default() })).unwrap();
    assert_eq!(found.iter().map(|n| n.node).collect::<Vec<_>>(), [1]);
    sim.bus().log_lines()
}

#[test]
fn timed_out_probes_abort_in_the_same_order_every_run() {
    let first = scan_log();
    // The master aborts each timed-out probe (0504 0000h, SDO timed out).
    let aborts = first.iter().filter(|l| l.ends_with("#8000100000000405")).count();
    assert_eq!(aborts, 39, "{first:#?}");
    for _ in 0..3 {
        assert_eq!(scan_log(), first);
    }
}
