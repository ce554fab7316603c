//! Replays of the Kollmorgen AKD CANopen manual's example frames (seed001,
//! edition R 09/2016) that exercise CiA 301 services. Sections follow
//! `seed001-akd-examples.md` (manual §6.3, §7.2.1.x, §7.2.2.1).
//!
//! Unlike the KC1 edition, the AKD examples invalidate a PDO (bit 31, with
//! bit 30) before remapping and re-validate it afterwards, so the CiA 301
//! §7.5.2.36 procedure is replayed as printed. Statusword values that the
//! CiA 402 state machine would produce (issue 3) are set where printed.

mod common;
mod manual;

use common::*;
use drivebus_node::{Identity, Node};
use drivebus_od::Value;
use drivebus_pdo::PdoConfig;
use manual::*;

/// An AKD (seed001 inventory): device type 0002_0192h (§6.2.1.1), vendor-ID
/// 6Ah, product code / device name 4 ASCII characters, revision 0014_0000h
/// (§6.2.1.18 example), byte-granular PDOs with 8 entries and the default
/// mappings of §6.3.1.3/§6.3.2.3, no block SDO.
fn node_id(id: u8) -> Node {
    let ident = Identity {
        vendor_id: 0x6A,
        product_code: u32::from_le_bytes(*b"M006"),
        revision: 0x0014_0000,
        serial: 1,
    };
    let mut cfg = drive_config(id, ident, "M006");
    cfg.pdo = PdoConfig::kollmorgen(id);
    // The drive has no RTR on TPDOs but acknowledges TPDO COB-IDs with bit 30
    // clear (bit ignored): `kollmorgen()` sets `rtr_supported = false` and
    // `ignore_rtr_bit = true`, pinned by `*_rtr_unsupported_*` below.
    cfg.sdo.block_transfer = false;
    cfg.emcy_history = 10;
    let mut n = Node::new(cfg);
    kollmorgen_objects(&mut n);
    kollmorgen_default_mappings(&mut n, 0x60FF_0020);
    n
}

fn node() -> Node {
    node_id(3)
}

/// §0: the store / restore signatures of §6.2.1.12/13 as SDO frames (derived
/// in the examples file from the printed payloads), and the 1000h value.
#[test]
fn akd_s0_store_restore_and_device_type() {
    let mut r = rig(node_id(1));
    replay(
        &mut r,
        &[
            ("601#40 00 10 00 00 00 00 00", &["581#43 00 10 00 92 01 02 00"]),
            ("601#40 18 10 03 00 00 00 00", &["581#43 18 10 03 00 00 14 00"]),
            ("601#23 10 10 01 73 61 76 65", &["581#60 10 10 01 00 00 00 00"]),
            ("601#23 11 10 01 6C 6F 61 64", &["581#60 11 10 01 00 00 00 00"]),
        ],
    );
}

/// §6.3 (section 1): free mapping of TPDO1, node 1 — requests only in print;
/// the confirmations are CiA 301's.
#[test]
fn akd_s1_free_mapping_of_tpdo1() {
    let mut r = rig(node_id(1));
    replay(
        &mut r,
        &[
            ("601#23 00 18 01 81 01 00 C0", &["581#60 00 18 01 00 00 00 00"]),
            ("601#2F 00 1A 00 00 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
            ("601#23 00 1A 01 10 00 41 60", &["581#60 00 1A 01 00 00 00 00"]),
            ("601#23 00 1A 02 20 00 02 10", &["581#60 00 1A 02 00 00 00 00"]),
            ("601#2F 00 1A 00 02 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
        ],
    );
    assert_eq!(r.node().od().get_u32(0x1800, 1), Some(0xC000_0181));
}

/// §7.2.1.2 (section 3): state machine by SDO.
#[test]
fn akd_s3_state_machine_by_sdo() {
    let mut r = rig(node());
    set(&mut r, 0x6041, 0, Value::U16(0x0240));
    // 3a prints data bytes `40 00 00 00` in the read request: reserved, ignored.
    replay(
        &mut r,
        &[
            ("603#40 41 60 00 40 00 00 00", &["583#4B 41 60 00 40 02 00 00"]),
            ("603#2B 40 60 00 06 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
            ("603#2B 40 60 00 07 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
        ],
    );
    set(&mut r, 0x6041, 0, Value::U16(0x0233));
    // 3c prints the request's data as "—": sent as 00.
    r.exchange("603#40 41 60 00 00 00 00 00", &["583#4B 41 60 00 33 02 00 00"]);
}

const ENABLE_BY_SDO: &[Step<'static>] = &[
    ("603#2B 40 60 00 06 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
    ("603#2B 40 60 00 07 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
    ("603#2B 40 60 00 0F 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
];

const HALT: Step<'static> = ("603#2B 40 60 00 0F 01 00 00", &["583#60 40 60 00 00 00 00 00"]);

/// §7.2.1.3 (section 4): jog by SDO.
#[test]
fn akd_s4_jog_mode_by_sdo() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 03 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#23 FF 60 00 00 00 00 00", &["583#60 FF 60 00 00 00 00 00"]),
        ],
    );
    replay(&mut r, ENABLE_BY_SDO);
    replay(&mut r, &[("603#23 FF 60 00 00 41 00 00", &["583#60 FF 60 00 00 00 00 00"]), HALT]);
}

/// §7.2.1.4 (section 5): torque by SDO.
#[test]
fn akd_s5_torque_mode_by_sdo() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 04 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#2B 71 60 00 00 00 00 00", &["583#60 71 60 00 00 00 00 00"]),
        ],
    );
    replay(&mut r, ENABLE_BY_SDO);
    replay(&mut r, &[("603#2B 71 60 00 90 01 00 00", &["583#60 71 60 00 00 00 00 00"]), HALT]);
}

/// Disable TPDO2..4 and RPDO2..4 of node 3 (sections 6 and 7).
const DISABLE_OTHER_PDOS: &[Step<'static>] = &[
    ("603#23 01 18 01 83 02 00 C0", &["583#60 01 18 01 00 00 00 00"]),
    ("603#23 02 18 01 83 03 00 C0", &["583#60 02 18 01 00 00 00 00"]),
    ("603#23 03 18 01 83 04 00 C0", &["583#60 03 18 01 00 00 00 00"]),
    ("603#23 01 14 01 03 03 00 C0", &["583#60 01 14 01 00 00 00 00"]),
    ("603#23 02 14 01 03 04 00 C0", &["583#60 02 14 01 00 00 00 00"]),
    ("603#23 03 14 01 03 05 00 C0", &["583#60 03 14 01 00 00 00 00"]),
];

/// §7.2.1.5 (section 6): jog by PDO — RPDO1 → 60FFh, TPDO1 → 6064h + 606Ch
/// on every SYNC.
#[test]
fn akd_s6_jog_mode_by_pdo() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 03 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#23 00 14 01 03 02 00 C0", &["583#60 00 14 01 00 00 00 00"]),
            ("603#2F 00 16 00 00 00 00 00", &["583#60 00 16 00 00 00 00 00"]),
            ("603#23 00 16 01 20 00 FF 60", &["583#60 00 16 01 00 00 00 00"]),
            ("603#2F 00 16 00 01 00 00 00", &["583#60 00 16 00 00 00 00 00"]),
            ("603#23 00 14 01 03 02 00 00", &["583#60 00 14 01 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 C0", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 1A 00 00 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 1A 01 20 00 64 60", &["583#60 00 1A 01 00 00 00 00"]),
            ("603#23 00 1A 02 20 00 6C 60", &["583#60 00 1A 02 00 00 00 00"]),
            ("603#2F 00 1A 00 02 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            // Re-enabled with bit 30 clear (RTR allowed) although the AKD has no RTR.
            ("603#23 00 18 01 83 01 00 00", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 18 02 01 00 00 00", &["583#60 00 18 02 00 00 00 00"]),
        ],
    );
    replay(&mut r, DISABLE_OTHER_PDOS);
    r.exchange("000#01 03", &[]);
    replay(&mut r, ENABLE_BY_SDO);
    r.exchange("203#00 40 00 00", &[]);
    assert_eq!(r.node().od().get_value(0x60FF, 0), Some(Value::I32(0x4000)));
    set(&mut r, 0x6064, 0, Value::I32(0x0001_45FE));
    set(&mut r, 0x606C, 0, Value::I32(0x001A_ABA6));
    replay(&mut r, &[("080#", &["183#FE 45 01 00 A6 AB 1A 00"]), HALT]);
}

/// §7.2.1.6 (section 7): torque by PDO — RPDO1 → 6071h, TPDO1 → 6077h on SYNC.
#[test]
fn akd_s7_torque_mode_by_pdo() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 04 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#23 00 14 01 03 02 00 C0", &["583#60 00 14 01 00 00 00 00"]),
            ("603#2F 00 16 00 00 00 00 00", &["583#60 00 16 00 00 00 00 00"]),
            ("603#23 00 16 01 10 00 71 60", &["583#60 00 16 01 00 00 00 00"]),
            ("603#2F 00 16 00 01 00 00 00", &["583#60 00 16 00 00 00 00 00"]),
            ("603#23 00 14 01 03 02 00 00", &["583#60 00 14 01 00 00 00 00"]),
            // TYPO (examples file, line 5645): printed 0xC0000383; TPDO1 is 183h.
            ("603#23 00 18 01 83 01 00 C0", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 1A 00 00 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 1A 01 10 00 77 60", &["583#60 00 1A 01 00 00 00 00"]),
            ("603#2F 00 1A 00 01 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            // TYPO (examples file, line 5653): printed 0x00000383.
            ("603#23 00 18 01 83 01 00 00", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 18 02 01 00 00 00", &["583#60 00 18 02 00 00 00 00"]),
        ],
    );
    replay(&mut r, DISABLE_OTHER_PDOS);
    r.exchange("000#01 03", &[]);
    replay(&mut r, ENABLE_BY_SDO);
    r.exchange("203#12 02", &[]);
    assert_eq!(r.node().od().get_value(0x6071, 0), Some(Value::I16(530)));
    set(&mut r, 0x6077, 0, Value::I16(537));
    replay(&mut r, &[("080#", &["183#19 02"]), HALT]);
}

/// §7.2.1.7 (section 8): boot-up (`703 00`, checked by the rig), homing
/// parameters and start by SDO. The last statusword response is printed
/// incomplete (`60` only) and is not replayed.
#[test]
fn akd_s8_homing_by_sdo() {
    let mut r = rig(node());
    set(&mut r, 0x6041, 0, Value::U16(0x0240));
    replay(
        &mut r,
        &[
            ("603#40 41 60 00 00 00 00 00", &["583#4B 41 60 00 40 02 00 00"]),
            ("603#23 99 60 01 10 27 00 00", &["583#60 99 60 01 00 00 00 00"]),
            ("603#23 99 60 02 88 13 00 00", &["583#60 99 60 02 00 00 00 00"]),
            ("603#23 9A 60 00 10 27 00 00", &["583#60 9A 60 00 00 00 00 00"]),
            ("603#23 7C 60 00 A8 61 00 00", &["583#60 7C 60 00 00 00 00 00"]),
            ("603#2F 60 60 00 06 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#40 41 60 00 00 00 00 00", &["583#4B 41 60 00 40 02 00 00"]),
        ],
    );
    replay(&mut r, ENABLE_BY_SDO);
    set(&mut r, 0x6041, 0, Value::U16(0x0237));
    replay(
        &mut r,
        &[
            ("603#40 41 60 00 00 00 00 00", &["583#4B 41 60 00 37 02 00 00"]),
            ("603#2B 40 60 00 1F 00 00 00", &["583#60 40 60 00 00 00 00 00"]),
            ("603#40 41 60 00 00 00 00 00", &["583#4B 41 60 00 37 02 00 00"]),
        ],
    );
}

/// §7.2.1.8 (section 9): profile position — PDO set-up (9a–9e), NMT start
/// with the event-driven TPDO1 (9f), the SDO downloads of 9g/9i, RPDO1 (9h,
/// 9k), RPDO2 + SYNC → TPDO2 (9j). The TPDO1 statusword frames after
/// controlwords and the 6099h:1 abort (a limit of the drive's scaling) need
/// the 402 drive (issue 3/4).
#[test]
fn akd_s9_profile_position() {
    let mut r = rig(node());
    // Lines 5758/5775/5792 carry 01 in byte 7 beyond a 1-byte payload (n = 3): ignored.
    replay(
        &mut r,
        &[
            ("603#23 01 14 01 03 03 00 C0", &["583#60 01 14 01 00 00 00 00"]),
            ("603#2F 01 16 00 00 00 00 01", &["583#60 01 16 00 00 00 00 00"]),
            ("603#23 01 16 01 20 00 7A 60", &["583#60 01 16 01 00 00 00 00"]),
            ("603#23 01 16 02 20 00 81 60", &["583#60 01 16 02 00 00 00 00"]),
            ("603#2F 01 16 00 02 00 00 00", &["583#60 01 16 00 00 00 00 00"]),
            ("603#23 01 14 01 03 03 00 00", &["583#60 01 14 01 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 C0", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 1A 00 00 00 00 01", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 1A 01 10 00 41 60", &["583#60 00 1A 01 00 00 00 00"]),
            ("603#2F 00 1A 00 01 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 00", &["583#60 00 18 01 00 00 00 00"]),
            // TYPO (examples file, line 5790): printed 0xC0000383; TPDO2 is 283h.
            ("603#23 01 18 01 83 02 00 C0", &["583#60 01 18 01 00 00 00 00"]),
            ("603#2F 01 1A 00 00 00 00 01", &["583#60 01 1A 00 00 00 00 00"]),
            ("603#23 01 1A 01 20 00 64 60", &["583#60 01 1A 01 00 00 00 00"]),
            ("603#23 01 1A 02 20 00 6C 60", &["583#60 01 1A 02 00 00 00 00"]),
            ("603#2F 01 1A 00 02 00 00 00", &["583#60 01 1A 00 00 00 00 00"]),
            // TYPO (examples file, line 5800): printed 0x00000383.
            ("603#23 01 18 01 83 02 00 00", &["583#60 01 18 01 00 00 00 00"]),
            ("603#2F 01 18 02 01 00 00 00", &["583#60 01 18 02 00 00 00 00"]),
            ("603#23 02 18 01 83 03 00 C0", &["583#60 02 18 01 00 00 00 00"]),
            ("603#23 03 18 01 83 04 00 C0", &["583#60 03 18 01 00 00 00 00"]),
            ("603#23 02 14 01 03 04 00 C0", &["583#60 02 14 01 00 00 00 00"]),
            ("603#23 03 14 01 03 05 00 C0", &["583#60 03 14 01 00 00 00 00"]),
            // 9e: "6092h" in the text, 6093h in the bytes: replayed as printed.
            ("603#23 93 60 01 00 00 10 00", &["583#60 93 60 01 00 00 00 00"]),
            ("603#23 93 60 02 A0 8C 00 00", &["583#60 93 60 02 00 00 00 00"]),
        ],
    );
    // 9f: NMT start; TPDO1 (event-driven) sends the statusword at once.
    set(&mut r, 0x6041, 0, Value::U16(0x0240));
    r.exchange("000#01 03", &["183#40 02"]);
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 06 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#2F 98 60 00 0C 00 00 00", &["583#60 98 60 00 00 00 00 00"]),
        ],
    );
    replay(&mut r, ENABLE_BY_SDO);
    r.exchange("603#2B 40 60 00 1F 00 00 00", &["583#60 40 60 00 00 00 00 00"]);
    // 9h: controlword by RPDO1 (default mapping 6040h).
    r.exchange("203#0F 00", &[]);
    assert_eq!(r.node().od().get_value(0x6040, 0), Some(Value::U16(0x000F)));
    replay(
        &mut r,
        &[
            ("603#2F 60 60 00 01 00 00 00", &["583#60 60 60 00 00 00 00 00"]),
            ("603#23 83 60 00 32 00 00 00", &["583#60 83 60 00 00 00 00 00"]),
            ("603#23 84 60 00 32 00 00 00", &["583#60 84 60 00 00 00 00 00"]),
            ("303#A0 8C 00 00 20 4E 00 00", &[]),
        ],
    );
    assert_eq!(r.node().od().get_value(0x607A, 0), Some(Value::I32(36_000)));
    assert_eq!(r.node().od().get_value(0x6081, 0), Some(Value::U32(20_000)));
    // 9j: TPDO2 printed with 4 of its 8 bytes (6064h + 606Ch): position
    // checked, velocity 0.
    set(&mut r, 0x6064, 0, Value::I32(-1861));
    set(&mut r, 0x606C, 0, Value::I32(0));
    r.exchange("080#", &["283#BB F8 FF FF 00 00 00 00"]);
    // 9k: new set-point by RPDO1 (the TPDO1 acknowledges are issue 3).
    r.exchange("203#1F 00", &[]);
    assert_eq!(r.node().od().get_value(0x6040, 0), Some(Value::U16(0x001F)));
    r.exchange("203#0F 00", &[]);
    set(&mut r, 0x6064, 0, Value::I32(-878));
    r.exchange("080#", &["283#92 FC FF FF 00 00 00 00"]);
}

/// §7.2.1.9 (section 10): ASCII channel 2026h, node 1; the reply chunks are
/// the drive's interpreter's (issue 4) and set by the test.
#[test]
fn akd_s10_ascii_channel() {
    let mut r = rig(node_id(1));
    replay(
        &mut r,
        &[
            ("601#23 26 20 01 44 52 56 2E", &["581#60 26 20 01 00 00 00 00"]),
            ("601#23 26 20 01 46 41 55 4C", &["581#60 26 20 01 00 00 00 00"]),
            ("601#23 26 20 01 54 53 0D 0A", &["581#60 26 20 01 00 00 00 00"]),
        ],
    );
    // TYPO (examples file, lines 5932/5934): "cdiv" and "f\n\r\n" in print.
    for (chunk, resp) in [
        (">No ", "581#43 26 20 02 3E 4E 6F 20"),
        ("faul", "581#43 26 20 02 66 61 75 6C"),
        ("ts a", "581#43 26 20 02 74 73 20 61"),
        ("ctiv", "581#43 26 20 02 63 74 69 76"),
        ("e\n\r\n", "581#43 26 20 02 65 0A 0D 0A"),
    ] {
        set(&mut r, 0x2026, 2, Value::Str(chunk.into()));
        r.exchange("601#40 26 20 02 00 00 00 00", &[resp]);
    }
}

/// §7.2.1.10 (section 11): TPDO1 (6064h) every 2nd SYNC, TPDO2 (6041h +
/// 1002h) every 3rd SYNC; RPDO2 → 607Ah + 6081h.
#[test]
fn akd_s11_sync_every_nth() {
    let mut r = rig(node());
    replay(
        &mut r,
        &[
            ("603#23 01 14 01 03 03 00 C0", &["583#60 01 14 01 00 00 00 00"]),
            ("603#2F 01 16 00 00 00 00 00", &["583#60 01 16 00 00 00 00 00"]),
            ("603#23 01 16 01 20 00 7A 60", &["583#60 01 16 01 00 00 00 00"]),
            ("603#23 01 16 02 20 00 81 60", &["583#60 01 16 02 00 00 00 00"]),
            ("603#2F 01 16 00 02 00 00 00", &["583#60 01 16 00 00 00 00 00"]),
            ("603#23 01 14 01 03 03 00 00", &["583#60 01 14 01 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 C0", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 1A 00 00 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 1A 01 20 00 64 60", &["583#60 00 1A 01 00 00 00 00"]),
            ("603#2F 00 1A 00 01 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#2F 00 18 02 02 00 00 00", &["583#60 00 18 02 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 00", &["583#60 00 18 01 00 00 00 00"]),
            // TYPO (examples file, line 5972): printed 0xC0000383; TPDO2 is 283h.
            ("603#23 01 18 01 83 02 00 C0", &["583#60 01 18 01 00 00 00 00"]),
            ("603#2F 01 1A 00 00 00 00 00", &["583#60 01 1A 00 00 00 00 00"]),
            ("603#23 01 1A 01 10 00 41 60", &["583#60 01 1A 01 00 00 00 00"]),
            ("603#23 01 1A 02 20 00 02 10", &["583#60 01 1A 02 00 00 00 00"]),
            // TYPO (examples file, line 5981): printed index 1601h; 1A01h meant.
            ("603#2F 01 1A 00 02 00 00 00", &["583#60 01 1A 00 00 00 00 00"]),
            ("603#2F 01 18 02 03 00 00 00", &["583#60 01 18 02 00 00 00 00"]),
            // TYPO (examples file, line 5985): printed `23 00 18 01 83 03 00 00`;
            // "enable TPDO2" is 1801h := 283h.
            ("603#23 01 18 01 83 02 00 00", &["583#60 01 18 01 00 00 00 00"]),
        ],
    );
    // TPDO3/4 are still valid and event-driven: they go out when the node
    // becomes operational (no NMT start is printed; PDOs need it).
    set(&mut r, 0x6064, 0, Value::I32(0x1234));
    set(&mut r, 0x6041, 0, Value::U16(0x0237));
    set(&mut r, 0x1002, 0, Value::U32(0x4403_0000));
    r.send("000#01 03");
    r.take();
    // The comment names 181/281 (node 1); node 3 uses 183/283.
    let tpdo1 = "183#34 12 00 00";
    let tpdo2 = "283#37 02 00 00 03 44";
    replay(
        &mut r,
        &[
            ("080#", &[]),
            ("080#", &[tpdo1]),
            ("080#", &[tpdo2]),
            ("080#", &[tpdo1]),
            ("080#", &[]),
            ("080#", &[tpdo1, tpdo2]),
        ],
    );
}

/// Sections 11b and 13k: EMCY frames of node 1. The registers printed (08h,
/// 88h) lack the generic bit CiA 301 sets with any error: a drive value, sent
/// through the raw path (personality, issue 4); the frames check COB-ID and
/// layout. 11b prints 7 bytes (category column lost): read as 13k's 8 bytes.
#[test]
fn akd_s11_s13_emcy_frames() {
    let mut r = rig(node_id(1));
    raw_emcy(&mut r, 0x4310, 0x08, [0x01, 0, 0, 0, 0]);
    assert_eq!(r.take(), frs(&["081#10 43 08 01 00 00 00 00"]));
    raw_emcy(&mut r, 0x0000, 0x08, [0; 5]);
    assert_eq!(r.take(), frs(&["081#00 00 08 00 00 00 00 00"]));
    raw_emcy(&mut r, 0x0000, 0x88, [0; 5]);
    assert_eq!(r.take(), frs(&["081#00 00 88 00 00 00 00 00"]));
}

/// §7.2.2.1 (section 13), axis 1 (node 1): RPDO2 → 60C1h:1 + dummy 2100h,
/// TPDO2 → 6063h + 1002h, both on every SYNC; TPDO3/4 off; IP mode, period.
#[test]
fn akd_s13_ip_axis1() {
    let mut r = rig(node_id(1));
    replay(
        &mut r,
        &[
            ("601#23 01 14 01 01 03 00 C0", &["581#60 01 14 01 00 00 00 00"]),
            ("601#2F 01 16 00 00 00 00 00", &["581#60 01 16 00 00 00 00 00"]),
            ("601#23 01 16 01 20 01 C1 60", &["581#60 01 16 01 00 00 00 00"]),
            ("601#23 01 16 02 20 00 00 21", &["581#60 01 16 02 00 00 00 00"]),
            ("601#2F 01 16 00 02 00 00 00", &["581#60 01 16 00 00 00 00 00"]),
            ("601#23 01 14 01 01 03 00 00", &["581#60 01 14 01 00 00 00 00"]),
            // TYPO (examples file, lines 6076/6086): printed 0xC0000381 /
            // 0x00000381; TPDO2 of node 1 is 281h.
            ("601#23 01 18 01 81 02 00 C0", &["581#60 01 18 01 00 00 00 00"]),
            ("601#2F 01 1A 00 00 00 00 00", &["581#60 01 1A 00 00 00 00 00"]),
            ("601#23 01 1A 01 20 00 63 60", &["581#60 01 1A 01 00 00 00 00"]),
            ("601#23 01 1A 02 20 00 02 10", &["581#60 01 1A 02 00 00 00 00"]),
            ("601#2F 01 1A 00 02 00 00 00", &["581#60 01 1A 00 00 00 00 00"]),
            ("601#23 01 18 01 81 02 00 00", &["581#60 01 18 01 00 00 00 00"]),
            ("601#2F 01 14 02 01 00 00 00", &["581#60 01 14 02 00 00 00 00"]),
            ("601#2F 01 18 02 01 00 00 00", &["581#60 01 18 02 00 00 00 00"]),
            ("601#23 02 18 01 81 03 00 C0", &["581#60 02 18 01 00 00 00 00"]),
            ("601#23 03 18 01 81 04 00 C0", &["581#60 03 18 01 00 00 00 00"]),
            ("601#2F 60 60 00 07 00 00 00", &["581#60 60 60 00 00 00 00 00"]),
            ("601#2F C2 60 01 01 00 00 00", &["581#60 C2 60 01 00 00 00 00"]),
            ("601#2F C2 60 02 FD 00 00 00", &["581#60 C2 60 02 00 00 00 00"]),
        ],
    );
    // 13h: NMT start of node 1. The event-driven TPDO1 goes out on entering
    // operational (as printed in 9f); 13h prints no frame: not asserted.
    r.send("000#01 01");
    r.take();
    // 13i: controlwords by RPDO1 (the TPDO1 state answers are issue 3).
    for cw in ["201#06 00", "201#07 00", "201#0F 00", "201#1F 00"] {
        r.exchange(cw, &[]);
    }
    assert_eq!(r.node().od().get_value(0x6040, 0), Some(Value::U16(0x001F)));
    // 13j: the set-points are applied at the SYNC (synchronous RPDO2).
    r.exchange("301#F4 01 00 00 E8 03 00 00", &[]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(0)));
    set(&mut r, 0x6063, 0, Value::I32(0x123));
    set(&mut r, 0x1002, 0, Value::U32(0x4403_0000));
    // INCONSISTENT (examples file, line 6181): printed on 181h; TPDO2 is 281h.
    r.exchange("080#", &["281#23 01 00 00 00 00 03 44"]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(500)));
}

/// §7.2.2.1, axis 2 (node 2): RPDO2 on 301h with the set-point in bytes 4–7.
#[test]
fn akd_s13_ip_axis2() {
    let mut r = rig(node_id(2));
    replay(
        &mut r,
        &[
            ("602#23 01 14 01 02 03 00 C0", &["582#60 01 14 01 00 00 00 00"]),
            ("602#2F 01 16 00 00 00 00 00", &["582#60 01 16 00 00 00 00 00"]),
            // TYPO (examples file, lines 6059/6061): sub-indices swapped in print.
            ("602#23 01 16 01 20 00 00 21", &["582#60 01 16 01 00 00 00 00"]),
            ("602#23 01 16 02 20 01 C1 60", &["582#60 01 16 02 00 00 00 00"]),
            ("602#2F 01 16 00 02 00 00 00", &["582#60 01 16 00 00 00 00 00"]),
            // TYPO (examples file, line 6065): printed as 1601h sub 1.
            ("602#23 01 14 01 01 03 00 00", &["582#60 01 14 01 00 00 00 00"]),
            // TYPO (examples file, line 6067): printed 0x00000202; the goal is 301h
            // (the same value again, accepted while valid).
            ("602#23 01 14 01 01 03 00 00", &["582#60 01 14 01 00 00 00 00"]),
            ("602#2F 01 14 02 01 00 00 00", &["582#60 01 14 02 00 00 00 00"]),
            ("602#2F 01 18 02 01 00 00 00", &["582#60 01 18 02 00 00 00 00"]),
            ("602#2F 60 60 00 07 00 00 00", &["582#60 60 60 00 00 00 00 00"]),
        ],
    );
    // "The same procedure must be carried out for axis 2" (13c, 13e): TPDO2 →
    // 6063h + 1002h, TPDO3/4 off — not printed for node 2, done here so the
    // printed axis-2 answer of 13j can be checked.
    for (idx, sub, v) in
        [(0x1801u16, 1u8, 0xC000_0282u32), (0x1A01, 0, 0), (0x1A01, 1, 0x6063_0020), (0x1A01, 2, 0x1002_0020)]
    {
        let b = v.to_le_bytes();
        let data = if idx == 0x1A01 && sub == 0 { &b[..1] } else { &b[..] };
        Rig::assert_written(r.sdo_write(2, idx, sub, data), 2, idx, sub);
    }
    Rig::assert_written(r.sdo_write(2, 0x1A01, 0, &[2]), 2, 0x1A01, 0);
    for (idx, v) in [(0x1801u16, 0x282u32), (0x1802, 0xC000_0382), (0x1803, 0xC000_0482)] {
        Rig::assert_written(r.sdo_write(2, idx, 1, &v.to_le_bytes()), 2, idx, 1);
    }
    // 13h starts node 1 only (INCONSISTENT with "all axes"); node 2 started
    // here (its TPDO1 on entering operational is not printed, not asserted).
    r.send("000#01 02");
    r.take();
    r.exchange("301#F4 01 00 00 E8 03 00 00", &[]);
    set(&mut r, 0x6063, 0, Value::I32(0x2A5));
    set(&mut r, 0x1002, 0, Value::U32(0x4403_0000));
    // INCONSISTENT (examples file, line 6182): printed on 182h; TPDO2 is 282h.
    r.exchange("080#", &["282#A5 02 00 00 00 00 03 44"]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(1000)));
}

/// §7.2.1.5 lines 5585–5596 on an AKD configured as documented, without RTR
/// on TPDOs: the drive acknowledges re-enabling TPDO1 as 0x0000_0183 (bit 30
/// clear, "RTR not supported" either way, inventory B.4).
#[test]
fn akd_rtr_unsupported_tpdo_cob_id_with_bit30_clear() {
    let mut cfg = node().config().clone();
    cfg.pdo.rtr_supported = false;
    let mut n = Node::new(cfg);
    kollmorgen_objects(&mut n);
    kollmorgen_default_mappings(&mut n, 0x60FF_0020);
    let mut r = rig(n);
    replay(
        &mut r,
        &[
            ("603#23 00 18 01 83 01 00 C0", &["583#60 00 18 01 00 00 00 00"]),
            ("603#2F 00 1A 00 00 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 1A 01 20 00 64 60", &["583#60 00 1A 01 00 00 00 00"]),
            ("603#23 00 1A 02 20 00 6C 60", &["583#60 00 1A 02 00 00 00 00"]),
            ("603#2F 00 1A 00 02 00 00 00", &["583#60 00 1A 00 00 00 00 00"]),
            ("603#23 00 18 01 83 01 00 00", &["583#60 00 18 01 00 00 00 00"]),
        ],
    );
}
