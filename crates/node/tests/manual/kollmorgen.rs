//! The test bodies the Kollmorgen KC1 (seed000, `manual_kc1.rs`) and AKD
//! (seed001, `manual_akd.rs`) replays share: the two manuals print the same
//! examples (KC1 chapter 8 = AKD chapter 7), the AKD edition with other line
//! numbers and section numbers. Each function takes the trace and the frame
//! keys that differ; section citations stay in the callers' comments.

use super::{drive_config, kollmorgen_default_mappings, kollmorgen_objects, raw_emcy, replay, set};
use crate::common::trace::{Trace, every_2nd_and_3rd};
use crate::common::{Rig, fr, frs};
use drivebus_node::{Identity, Node};
use drivebus_od::Value;
use drivebus_pdo::PdoConfig;

/// A KC1 / AKD at node-ID `id`: device type 0002_0192h, vendor-ID 6Ah,
/// product code / device name "M006", revision 0014_0000h, byte-granular
/// PDOs with 8 entries, no block SDO, a 10-deep error history (1003h);
/// `software_version` (1009h) where the manual gives one.
pub fn kollmorgen_node(id: u8, software_version: Option<&str>) -> Node {
    let ident = Identity {
        vendor_id: 0x6A,
        product_code: u32::from_le_bytes(*b"M006"),
        revision: 0x0014_0000,
        serial: 1,
    };
    let mut cfg = drive_config(id, ident, "M006");
    if let Some(v) = software_version {
        cfg.software_version = Some(v.into());
    }
    cfg.pdo = PdoConfig::kollmorgen(id);
    // The drive has no RTR on TPDOs but acknowledges TPDO COB-IDs with bit 30
    // clear (bit ignored): `kollmorgen()` sets `rtr_supported = false` and
    // `ignore_rtr_bit = true`, pinned by `*_rtr_unsupported_*` in the callers.
    cfg.sdo.block_transfer = false;
    cfg.emcy_history = 10;
    let mut n = Node::new(cfg);
    // Application objects the examples read, write or map (seed000/seed001
    // tsv).
    kollmorgen_objects(&mut n);
    // Default mappings, all PDOs valid, type 255 (KC1 §7.3.1.3, §7.3.2.3;
    // AKD §6.3.1.3, §6.3.2.3).
    kollmorgen_default_mappings(&mut n, 0x60FF_0020);
    n
}

/// KC1 example 3 / AKD section 3 (the same frames): statusword read (0240h
/// set), shutdown and switch on by SDO; 0233h, the 402 state machine's
/// answer (issue 3), set as printed before frames 7–8.
pub fn state_machine_by_sdo(r: &mut Rig, t: &Trace) {
    set(r, 0x6041, 0, Value::U16(0x0240));
    replay(r, &t.steps(1, 6));
    set(r, 0x6041, 0, Value::U16(0x0233));
    replay(r, &t.steps(7, 8));
}

/// KC1 example 10 / AKD section 10: the ASCII channel 2026h. Frames 1–6 as
/// printed; for 7–16 the test sets each reply chunk (the command
/// interpreter is the drive's, issue 4): the 4 data bytes of the printed
/// reply.
pub fn ascii_channel(r: &mut Rig, t: &Trace) {
    replay(r, &t.steps(1, 6));
    for (req, resp) in t.steps(7, 16) {
        let chunk = String::from_utf8(fr(resp[0]).data()[4..].to_vec()).unwrap();
        set(r, 0x2026, 2, Value::Str(chunk));
        r.exchange(req, resp);
    }
}

/// KC1 example 11 / AKD section 11, after the set-up: position 1234h,
/// statusword 0237h and 1002h 4403_0000h set; NMT start (not printed; PDOs
/// need operational; what goes out on entering it is not asserted); then
/// the SYNC `sync` and the pattern of its comment on 183h/283h.
pub fn sync_every_nth(r: &mut Rig, t: &Trace, sync: u32) {
    set(r, 0x6064, 0, Value::I32(0x1234));
    set(r, 0x6041, 0, Value::U16(0x0237));
    set(r, 0x1002, 0, Value::U32(0x4403_0000));
    r.send("000#01 03");
    r.take();
    let sync = t.frame(sync);
    let tpdo1 = "183#34 12 00 00";
    let tpdo2 = "283#37 02 00 00 03 44";
    for (sync, tpdos) in every_2nd_and_3rd(sync, tpdo1, tpdo2) {
        r.exchange(sync, &tpdos);
    }
}

/// The EMCY frames of node 1 through the raw path (register without the
/// generic bit, a drive value: personality, issue 4): code 4310h, register
/// 08h, category 01h → `fault`; the reset with register 08h → `reset_08`,
/// with 88h (other errors pending) → `reset_88`.
pub fn emcy_frames(r: &mut Rig, fault: &str, reset_08: &str, reset_88: &str) {
    raw_emcy(r, 0x4310, 0x08, [0x01, 0, 0, 0, 0]);
    assert_eq!(r.take(), frs(&[fault]));
    raw_emcy(r, 0x0000, 0x08, [0; 5]);
    assert_eq!(r.take(), frs(&[reset_08]));
    raw_emcy(r, 0x0000, 0x88, [0; 5]);
    assert_eq!(r.take(), frs(&[reset_88]));
}

/// KC1 example 12 / AKD section 13, axis 1: NMT start `nmt` (what goes out
/// on entering operational is not printed, not asserted), the controlwords
/// `cws` by RPDO1 (the TPDO1 state answers are issue 3): 6040h ends at 001Fh.
pub fn ip_axis1_enable(r: &mut Rig, t: &Trace, nmt: u32, cws: (u32, u32)) {
    r.send(t.frame(nmt));
    r.take();
    for (cw, _) in t.steps(cws.0, cws.1) {
        r.exchange(cw, &[]);
    }
    assert_eq!(r.node().od().get_value(0x6040, 0), Some(Value::U16(0x001F)));
}

/// The ip set-point at the SYNC (RPDO2 already sent): 6063h := `pos_6063`
/// and 1002h := 4403_0000h as printed, the SYNC `sync` answered by TPDO2
/// `tpdo2` (printed on 18xh, INCONSISTENT: on 28xh in the trace); then
/// 60C1h:1 is `setpoint`.
pub fn ip_tpdo2_at_sync(r: &mut Rig, t: &Trace, sync: u32, tpdo2: u32, pos_6063: i32, setpoint: i32) {
    set(r, 0x6063, 0, Value::I32(pos_6063));
    set(r, 0x1002, 0, Value::U32(0x4403_0000));
    r.exchange(t.frame(sync), &[t.frame(tpdo2)]);
    assert_eq!(r.node().od().get_value(0x60C1, 1), Some(Value::I32(setpoint)));
}
