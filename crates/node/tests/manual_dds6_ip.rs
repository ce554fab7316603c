//! Replay of the LAM DDS6 manual's interpolated-position trace (seed004
//! §4.4.5, DDS6-EX9 of `seed004-dds6-examples.md`): RPDO2 remapped to
//! controlword + 60C1h:1, RPDO2 and TPDO2 synchronous (type 1), 20 ms SYNC.
//! Every printed frame is replayed at its printed time (SYNC every 20 ms);
//! see `manual_dds6.rs` for how the drive's CiA 402 values are preset. Checked here besides: a synchronous RPDO takes
//! effect at the next SYNC (CiA 301 §7.2.2.2).

mod common;
mod manual;

use common::trace as shared_trace;
use drivebus_node::Node;
use drivebus_od::Value;
use manual::*;

/// The DDS6 of the traces: node-ID 0Dh, defaults of the manual (see
/// [`dds6_node`]).
fn node() -> Node {
    dds6_node(0x0D)
}

// EX9: the printed trace, shared with the personality replay.
const EX9_TEXT: &str = include_str!("../../personality/traces/dds6_ex9.txt");

/// The trace lines of [`EX9_TEXT`] (comments and blank lines dropped).
fn ex9() -> Vec<&'static str> {
    shared_trace::timed_lines(EX9_TEXT, 402)
}

/// DDS6-EX9, §4.4.5: the whole printed trace (402 frames).
#[test]
fn dds6_ex9_interpolated_position_sync_pdo() {
    let mut r = rig(node());
    play(&mut r, &ex9());
}

/// DDS6-EX9 rows 79–87: the set-point of RPDO2 received after SYNC n is
/// applied at SYNC n+1, not on reception.
#[test]
fn dds6_ex9_synchronous_rpdo_applies_at_next_sync() {
    let mut r = rig(node());
    let setup: Vec<&str> = ex9().iter().copied().take_while(|f| !f.contains(">080")).collect();
    play(&mut r, &setup);
    play(&mut r, &[">080#", "<28D#37 16 00 00 00 00", ">30D#1F 00 57 02 00 00"]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(0)));
    play(&mut r, &[">080#", "<28D#37 16 00 00 00 00"]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(599)));
}
