//! Replays of the LAM DDS6 CANopen manual's chapter 4.4 bus traces (seed004,
//! hardware rev. 1.00, firmware 0.22), node-ID 0Dh, frame by frame. Example
//! ids follow `seed004-dds6-examples.md`; the interpolated-position trace
//! (EX9) is in `manual_dds6_ip.rs`.
//!
//! The traces interleave SDO, NMT and PDO traffic with the drive's CiA 402
//! answers. [`play`] replays every printed frame in order and checks every
//! drive frame exactly; the *values* the drive reports (statusword, actual
//! position/velocity/torque, mode display) come from its 402 application
//! (issue 3) and are preset from the printed frame just before it is due.
//! What is under test is CiA 301: SDO framing, confirmations and upload
//! sizes, PDO configuration, COB-IDs, mapping and packing, event-driven and
//! NMT-start transmission.
//!
//! The tables were transcribed mechanically from the examples file (times
//! and bytes only; "repeated polling elided" marks the manual's "…" rows).
//! Frames carry the trace's timestamps (ms): the replay runs on simulated
//! time and the node must stay silent between the printed frames (no
//! timer-driven TPDO, heartbeat or other traffic). The only corrections are
//! the examples file's DLC flags (PDO rows printed with 7 data bytes for a
//! 6-byte mapping).

mod common;
mod manual;

use common::trace as shared_trace;
use drivebus_node::Node;
use manual::*;

/// The DDS6 of the traces: node-ID 0Dh, defaults of the manual (see
/// [`dds6_node`]).
fn node() -> Node {
    dds6_node(0x0D)
}

/// The printed traces, shared with the personality replays
/// (`crates/personality/traces/`): frame lines, comments dropped.
fn trace(text: &'static str, frames: usize) -> Vec<&'static str> {
    shared_trace::timed_lines(text, frames)
}
const EX1: &str = include_str!("../../personality/traces/dds6_ex1.txt");
const EX2: &str = include_str!("../../personality/traces/dds6_ex2.txt");
const EX3: &str = include_str!("../../personality/traces/dds6_ex3.txt");
const EX4: &str = include_str!("../../personality/traces/dds6_ex4.txt");
const EX5: &str = include_str!("../../personality/traces/dds6_ex5.txt");
const EX6: &str = include_str!("../../personality/traces/dds6_ex6.txt");
const EX7: &str = include_str!("../../personality/traces/dds6_ex7.txt");
const EX8: &str = include_str!("../../personality/traces/dds6_ex8.txt");

/// DDS6-EX1, §4.4.1, first example: profile position by SDO only (5 positionings); all 88 frames.
#[test]
fn dds6_ex1_profile_position_by_sdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX1, 88));
}

/// DDS6-EX2, §4.4.1, second example: PDO set-up by SDO, NMT start, RPDO2 (30Dh) controlword + target, event-driven TPDO2 (28Dh) statusword + position.
#[test]
fn dds6_ex2_profile_position_by_pdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX2, 48));
}

/// DDS6-EX3, §4.4.2, first example: profile velocity by SDO only.
#[test]
fn dds6_ex3_profile_velocity_by_sdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX3, 48));
}

/// DDS6-EX4, §4.4.2, second example: RPDO3 (40Dh) / TPDO3 (38Dh) with their default mappings.
#[test]
fn dds6_ex4_profile_velocity_by_pdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX4, 38));
}

/// DDS6-EX5, §4.4.3, first example: profile torque by SDO only (2310h:0Bh speed cap).
#[test]
fn dds6_ex5_profile_torque_by_sdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX5, 42));
}

/// DDS6-EX6, §4.4.3, second example: RPDO4/TPDO4 remapped by the CiA 301 procedure (invalidate, type, sub 0 = 0, entries, sub 0 = n, validate).
#[test]
fn dds6_ex6_profile_torque_by_pdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX6, 54));
}

/// DDS6-EX7, §4.4.4, first example: homing method 1 by SDO only (2810h input actions).
#[test]
fn dds6_ex7_homing_by_sdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX7, 38));
}

/// DDS6-EX8, §4.4.4, second example: homing by the default RPDO1 (20Dh) / TPDO1 (18Dh).
#[test]
fn dds6_ex8_homing_by_pdo() {
    let mut r = rig(node());
    play(&mut r, &trace(EX8, 32));
}
