//! Replays of the SDO content of the Technosoft iPOS CoE programming manual
//! (seed002, P091.064.UM.0524). The drive is EtherCAT: its SDOs travel in
//! CoE mailboxes, with the CiA 301 SDO command layout but no CAN frames and
//! no node-ID. What is replayed here is that SDO content, carried as
//! CANopen expedited SDO frames to node-ID 1 (an arbitrary choice); the
//! frames and the confirmations are derived, the manual prints none.
//! Example ids follow `seed002-ipos-examples.md`.
//!
//! Not replayable (see manual_report.md): the EtherCAT state machine, sync
//! manager PDO assignment (1C12h/1C13h, which replaces the CiA 301 PDO
//! communication parameters), cyclic process data, FoE/EoE, TwinCAT GUI steps.

mod common;
mod manual;

use common::*;
use drivebus_node::{Identity, Node};
use drivebus_od::{Access, DataType, Object, SubObject, Value};
use manual::*;

use Access::{Ro, Rw, Wo};
use DataType::{Integer8, Integer16, Integer32, Unsigned8, Unsigned16, Unsigned32};

/// An iPOS4808 MY-CAT-STO (seed002 inventory / E15): device type
/// 0006_0192h, vendor-ID 1A3h, product code 27214121 (P027.214.E121),
/// revision "0100" (3031_3030h), serial "LE1158" (4C45_1158h), device
/// name "iPOS"; the application objects the examples write, with the tsv's
/// types, access and defaults.
fn node() -> Node {
    let ident =
        Identity { vendor_id: 0x1A3, product_code: 27_214_121, revision: 0x3031_3030, serial: 0x4C45_1158 };
    let mut cfg = drive_config(1, ident, "iPOS");
    cfg.device_type = 0x0006_0192;
    let mut n = Node::new(cfg);
    for (index, name, dt, acc, def) in [
        (0x2012, "Master resolution", Unsigned32, Rw, Value::U32(0x8000_0001)),
        (0x2019, "CAM table load address", Unsigned16, Rw, Value::U16(0)),
        (0x201A, "CAM table run address", Unsigned16, Rw, Value::U16(0x9E00)),
        (0x201B, "CAM offset", Unsigned32, Rw, Value::U32(0)),
        (0x201D, "External reference type", Unsigned16, Rw, Value::U16(0)),
        (0x2023, "Jerk time", Unsigned16, Rw, Value::U16(0)),
        (0x2060, "Software version of TML application", Unsigned32, Ro, Value::U32(0x322E_3156)),
        (0x2064, "Read/write configuration register", Unsigned32, Rw, Value::U32(0x84)),
        (0x2065, "Write data at address set in 2064h", Unsigned32, Wo, Value::U32(0)),
        (0x2067, "Write data at specified address", Unsigned32, Wo, Value::U32(0)),
        (0x2069, "Checksum configuration register", Unsigned32, Rw, Value::U32(0)),
        (0x206A, "Checksum read register", Unsigned16, Ro, Value::U16(0)),
        // FIXED32 (16.16) is carried as 32 bits.
        (0x206B, "CAM input scaling factor", Unsigned32, Rw, Value::U32(0x0001_0000)),
        (0x206C, "CAM output scaling factor", Unsigned32, Rw, Value::U32(0x0001_0000)),
        (0x2073, "Interpolated position buffer length", Unsigned16, Wo, Value::U16(7)),
        (0x2074, "Interpolated position buffer configuration", Unsigned16, Wo, Value::U16(0)),
        (0x2079, "Interpolated position initial position", Integer32, Rw, Value::I32(0)),
        (0x2089, "Synchronization test config", Integer16, Rw, Value::I16(0)),
        (0x6060, "Modes of operation", Integer8, Rw, Value::I8(0)),
        (0x6062, "Position demand value", Integer32, Ro, Value::I32(0)),
        (0x6064, "Position actual value", Integer32, Ro, Value::I32(0)),
        (0x6065, "Following error window", Unsigned32, Rw, Value::U32(0)),
        (0x6066, "Following error time out", Unsigned16, Rw, Value::U16(0)),
        (0x6071, "Target torque", Integer16, Rw, Value::I16(0)),
        (0x6075, "Motor rated current", Unsigned32, Rw, Value::U32(0)),
        (0x607A, "Target position", Integer32, Rw, Value::I32(0)),
        (0x607C, "Home offset", Integer32, Rw, Value::I32(0)),
        (0x6081, "Profile velocity", Unsigned32, Rw, Value::U32(0)),
        (0x6086, "Motion profile type", Integer16, Rw, Value::I16(0)),
        (0x6087, "Torque slope", Unsigned32, Rw, Value::U32(0)),
        (0x6098, "Homing method", Integer8, Rw, Value::I8(0)),
        (0x609A, "Homing acceleration", Unsigned32, Rw, Value::U32(0x199A)),
        (0x60B8, "Touch probe function", Unsigned16, Rw, Value::U16(0)),
        (0x60B9, "Touch probe status", Unsigned16, Ro, Value::U16(0)),
        (0x60BA, "Touch probe 1 positive edge", Integer32, Ro, Value::I32(0)),
        (0x60C0, "Interpolation sub mode select", Integer16, Rw, Value::I16(0)),
        (0x60FF, "Target velocity", Integer32, Rw, Value::I32(0)),
    ] {
        n.insert_object(pvar(index, name, dt, acc, def));
    }
    n.insert_object(
        Object::record(0x2013, "EGEAR multiplication factor")
            .with_sub(SubObject::new(1, "EGEAR ratio numerator", Integer16, Rw, Value::I16(1)))
            .with_sub(SubObject::new(2, "EGEAR ratio denominator", Unsigned16, Rw, Value::U16(1))),
    );
    n.insert_object(record(
        0x6093,
        "Position factor",
        &[(Unsigned32, Rw, true, Value::U32(1)), (Unsigned32, Rw, true, Value::U32(1))],
    ));
    n.insert_object(record(
        0x6099,
        "Homing speeds",
        &[(Unsigned32, Rw, true, Value::U32(0x0001_0000)), (Unsigned32, Rw, true, Value::U32(0x0001_0000))],
    ));
    n.insert_object(record(
        0x60C2,
        "Interpolation time period",
        &[(Unsigned8, Rw, true, Value::U8(1)), (Integer8, Rw, true, Value::I8(-3))],
    ));
    n.insert_object(record(
        0x60FE,
        "Digital outputs",
        &[(Unsigned32, Rw, true, Value::U32(0)), (Unsigned32, Rw, true, Value::U32(0))],
    ));
    n.insert_object(record(
        0x210E,
        "IP config for EoE",
        &[
            (Unsigned32, Rw, false, Value::U32(0)),
            (Unsigned32, Rw, false, Value::U32(0)),
            (Unsigned32, Rw, false, Value::U32(0)),
        ],
    ));
    n
}

/// The CoE SDO downloads of one example as CiA 301 expedited downloads to
/// node 1: (index, sub, little-endian value of the object's size). Each must
/// be confirmed (`581 60 ..`) and stored.
fn downloads(r: &mut Rig, steps: &[(u16, u8, &[u8])]) {
    for (index, sub, data) in steps {
        Rig::assert_written(r.sdo_write(1, *index, *sub, data), 1, *index, *sub);
        let e = r.node().od().get(*index, *sub).expect("object");
        if e.access.readable() {
            assert_eq!(e.bytes(), *data, "{index:04X}:{sub} stored");
        }
    }
}

/// E05 (§1.6.1): profile position — 6060h := 1, 6081h := 0009_0000h by SDO
/// (the controlword / target steps are EtherCAT process data).
#[test]
fn ipos_e05_profile_position_sdos() {
    let mut r = rig(node());
    downloads(&mut r, &[(0x6060, 0, &[1]), (0x6081, 0, &0x0009_0000u32.to_le_bytes())]);
}

/// E12 (§3.2.2): 2089h := 7 (INTEGER16) shows SYNC0 / loop / processing on outputs.
#[test]
fn ipos_e12_sync_visualisation() {
    let mut r = rig(node());
    downloads(&mut r, &[(0x2089, 0, &7i16.to_le_bytes()), (0x2089, 0, &0i16.to_le_bytes())]);
}

/// E13 (§4.5.3.1): digital outputs value then mask.
#[test]
fn ipos_e13_digital_outputs() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[(0x60FE, 1, &0x0002_0000u32.to_le_bytes()), (0x60FE, 2, &0x0003_0000u32.to_le_bytes())],
    );
}

/// E14 (§4.7.3): step-loss detection window and time.
#[test]
fn ipos_e14_step_loss_detection() {
    let mut r = rig(node());
    // Printed "6056h" in the text: TYPO (examples file) for 6065h.
    downloads(&mut r, &[(0x6065, 0, &1000u32.to_le_bytes()), (0x6066, 0, &20u16.to_le_bytes())]);
}

/// E15 (§4.8.5/4.8.6): reading 2060h and the identity object, as expedited
/// 4-byte uploads with the values the manual decodes.
#[test]
fn ipos_e15_identity_and_version_reads() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("601#40 60 20 00 00 00 00 00", &["581#43 60 20 00 56 31 2E 32"]),
            ("601#40 18 10 01 00 00 00 00", &["581#43 18 10 01 A3 01 00 00"]),
            ("601#40 18 10 02 00 00 00 00", &["581#43 18 10 02 29 41 9F 01"]),
            ("601#40 18 10 03 00 00 00 00", &["581#43 18 10 03 30 30 31 30"]),
            ("601#40 18 10 04 00 00 00 00", &["581#43 18 10 04 58 11 45 4C"]),
            ("601#40 00 10 00 00 00 00 00", &["581#43 00 10 00 92 01 06 00"]),
        ],
    );
}

/// E16 (§5.1.10.1): position factor in radians.
#[test]
fn ipos_e16_position_factor() {
    let mut r = rig(node());
    downloads(&mut r, &[(0x6093, 1, &u32::MAX.to_le_bytes()), (0x6093, 2, &13_493_038u32.to_le_bytes())]);
}

/// E18 (§6.4): homing method 18 parameters. The final 6064h upload
/// ("2000 ± a few counts") is the motion's result (issue 3).
#[test]
fn ipos_e18_homing_parameters() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            (0x6099, 2, &0x0005_0000u32.to_le_bytes()),
            (0x6099, 1, &0x0014_0000u32.to_le_bytes()),
            (0x609A, 0, &0x0000_028Fu32.to_le_bytes()),
            (0x607C, 0, &0x0000_07D0i32.to_le_bytes()),
            (0x6098, 0, &[0x12]),
        ],
    );
}

/// E19–E22 (§7.3.1–7.3.4): profile position SDOs (trapezoidal and S-curve).
#[test]
fn ipos_e19_e22_profile_position_sdos() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            // E19
            (0x6081, 0, &0x0010_AAACu32.to_le_bytes()),
            (0x607A, 0, &0x0006_1A80i32.to_le_bytes()),
            // E20
            (0x6081, 0, &0x0010_AAACu32.to_le_bytes()),
            (0x607A, 0, &0x0000_7D00i32.to_le_bytes()),
            // E21
            (0x6086, 0, &3i16.to_le_bytes()),
            (0x6081, 0, &0x000F_0000u32.to_le_bytes()),
            (0x2023, 0, &0x1F4Bu16.to_le_bytes()),
            // E22
            (0x6086, 0, &3i16.to_le_bytes()),
            (0x6081, 0, &0x0005_0000u32.to_le_bytes()),
            (0x2023, 0, &0x013Bu16.to_le_bytes()),
        ],
    );
}

/// E23 (§8.3): torque profile SDOs.
#[test]
fn ipos_e23_torque_profile() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            (0x6075, 0, &0x03E8u32.to_le_bytes()),
            (0x6087, 0, &0x03E8u32.to_le_bytes()),
            (0x6071, 0, &0x01F4i16.to_le_bytes()),
            (0x6071, 0, &(-1200i16).to_le_bytes()),
        ],
    );
}

/// E26–E28 (§9.4): PT / PVT set-up SDOs (the 1602h mapping with 1C12h
/// assignment and the points in RxPDO3 are EtherCAT process data).
#[test]
fn ipos_e26_e28_pt_pvt_setup() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            // E26 PT
            (0x60C0, 0, &0i16.to_le_bytes()),
            (0x2073, 0, &0x000Cu16.to_le_bytes()),
            (0x2074, 0, &0xA001u16.to_le_bytes()),
            (0x2079, 0, &0x3E8i32.to_le_bytes()),
            // E27 PVT absolute
            (0x60C0, 0, &(-1i16).to_le_bytes()),
            (0x2073, 0, &0x000Fu16.to_le_bytes()),
            (0x2074, 0, &0xB001u16.to_le_bytes()),
            // E28 PVT relative
            (0x60C0, 0, &(-1i16).to_le_bytes()),
            (0x2073, 0, &0x000Cu16.to_le_bytes()),
            (0x2074, 0, &0xA001u16.to_le_bytes()),
        ],
    );
}

/// E29/E30 (§10.3): target velocity. E30's text computes 0200_0000h but
/// prints 0014_0000h; both are written as printed/computed.
#[test]
fn ipos_e29_e30_speed_profile() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[(0x60FF, 0, &0x0014_0000i32.to_le_bytes()), (0x60FF, 0, &0x0200_0000i32.to_le_bytes())],
    );
}

/// E31–E36 (§11): electronic gearing and camming SDOs.
#[test]
fn ipos_e31_e36_gearing_and_camming() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            // E31 / E32 gearing
            (0x201D, 0, &3u16.to_le_bytes()),
            (0x2012, 0, &0x07D0u32.to_le_bytes()),
            (0x2013, 1, &1i16.to_le_bytes()),
            (0x2013, 2, &1u16.to_le_bytes()),
            (0x201D, 0, &1u16.to_le_bytes()),
            // E34 CAM download via 2064h/2065h (load address 5638h)
            (0x2064, 0, &0x5638_0008u32.to_le_bytes()),
            (0x2065, 0, &0x0000_C400u32.to_le_bytes()),
            // E35 / E36 camming
            (0x201D, 0, &3u16.to_le_bytes()),
            (0x2019, 0, &0x5638u16.to_le_bytes()),
            (0x201A, 0, &0x97F6u16.to_le_bytes()),
            (0x2012, 0, &0x07D0u32.to_le_bytes()),
            (0x201B, 0, &0x1770u32.to_le_bytes()),
            (0x206B, 0, &1u32.to_le_bytes()),
            (0x206C, 0, &1u32.to_le_bytes()),
        ],
    );
}

/// E37 (§12): interpolation time period 4 × 10⁻³ s.
#[test]
fn ipos_e37_interpolation_time_period() {
    let mut r = rig(node());
    downloads(&mut r, &[(0x60C2, 1, &[4]), (0x60C2, 2, &[0xFD])]);
}

/// E41 (§13): touch probe. The 60B9h status values are the drive's
/// (preset as printed); 60BAh's value is not printed and not replayed.
#[test]
fn ipos_e41_touch_probe() {
    let mut r = rig(node());
    downloads(&mut r, &[(0x6081, 0, &0x0002_0000u32.to_le_bytes()), (0x60B8, 0, &0x0011u16.to_le_bytes())]);
    set(&mut r, 0x60B9, 0, Value::U16(0x0001));
    r.exchange("601#40 B9 60 00 00 00 00 00", &["581#4B B9 60 00 01 00 00 00"]);
    set(&mut r, 0x60B9, 0, Value::U16(0x0003));
    r.exchange("601#40 B9 60 00 00 00 00 00", &["581#4B B9 60 00 03 00 00 00"]);
}

/// E42–E44 (§14): memory access objects; 206Ah's checksum 2345h is the
/// drive's (preset as printed).
#[test]
fn ipos_e42_e44_memory_access() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            (0x2067, 0, &0x036A_1234u32.to_le_bytes()),
            (0x2064, 0, &0x5638_0008u32.to_le_bytes()),
            (0x2065, 0, &0x0000_C400u32.to_le_bytes()),
            (0x2065, 0, &0u32.to_le_bytes()),
            (0x2069, 0, &0x5EFF_5E06u32.to_le_bytes()),
        ],
    );
    set(&mut r, 0x206A, 0, Value::U16(0x2345));
    r.exchange("601#40 6A 20 00 00 00 00 00", &["581#4B 6A 20 00 45 23 00 00"]);
    downloads(
        &mut r,
        &[
            (0x2064, 0, &0x5E06_0009u32.to_le_bytes()),
            (0x2065, 0, &0x5678_1234u32.to_le_bytes()),
            (0x2065, 0, &0xCDEF_09ABu32.to_le_bytes()),
        ],
    );
}

/// E50 (§16): EoE IP configuration values in 210Eh (the EoE service itself
/// is EtherCAT-only).
#[test]
fn ipos_e50_eoe_ip_configuration_values() {
    let mut r = rig(node());
    downloads(
        &mut r,
        &[
            (0x210E, 1, &0x0C18_A8C0u32.to_le_bytes()),
            (0x210E, 2, &0x00FF_FFFFu32.to_le_bytes()),
            (0x210E, 3, &0x0B18_A8C0u32.to_le_bytes()),
        ],
    );
}
