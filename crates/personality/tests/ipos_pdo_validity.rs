//! The iPOS on CAN: which PDOs are valid after power-on. The iPOS manual
//! (seed002, *iPOS CoE Programming*) is written for EtherCAT, where a PDO
//! is used when the Sync Manager assigns it; drivebus carries the drive on
//! CAN, where a PDO is used when its COB-ID is valid (CiA 301 §7.5.2.35/37:
//! bit 31 = 0). The assignment becomes the COB-ID's validity:
//!
//! * §2.3.10 1C12h default: sub 0 = 1, sub 1 = 1600h → only RPDO1 valid;
//! * §2.3.11 1C13h default: sub 0 = 2, 1A00h and 1A01h → TPDO1 and 2 valid;
//! * §2.3.7 / §2.3.8: "By default, this PDO [TPDO3/TPDO4] is disabled with
//!   object 1802h/1803h Sub-index 01 by setting Bit31 to 1".
//!
//! The identifiers are CiA 301's pre-defined connection set (§7.3.5):
//! RPDO 200h/300h/400h/500h, TPDO 180h/280h/380h/480h + node-ID.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::*;

const NODE: u8 = 4;

#[test]
fn unassigned_pdos_are_invalid_on_can() {
    let (mut r, _) = Rig::new(Profile::Ipos, NODE);
    let id = u32::from(NODE);
    for (n, valid) in [true, false, false, false].into_iter().enumerate() {
        let cob = r.read_u32(NODE, 0x1400 + n as u16, 1);
        let base = 0x200 + 0x100 * n as u32;
        assert_eq!(cob & 0x7FF, base + id, "RPDO{} identifier", n + 1);
        assert_eq!(cob & 0x8000_0000 == 0, valid, "RPDO{} validity (§2.3.10): {cob:08X}h", n + 1);
    }
    for (n, valid) in [true, true, false, false].into_iter().enumerate() {
        let cob = r.read_u32(NODE, 0x1800 + n as u16, 1);
        let base = 0x180 + 0x100 * n as u32;
        assert_eq!(cob & 0x7FF, base + id, "TPDO{} identifier", n + 1);
        assert_eq!(
            cob & 0x8000_0000 == 0,
            valid,
            "TPDO{} validity (§2.3.7/§2.3.8/§2.3.11): {cob:08X}h",
            n + 1
        );
    }
    // The invalid ones are the defaults (1011h restore brings them back):
    // their values equal the dictionary defaults.
    let od = r.node().od();
    for index in [0x1401u16, 0x1402, 0x1403, 0x1802, 0x1803] {
        let s = od.get(index, 1).unwrap();
        assert_eq!(s.bytes(), s.default.as_slice(), "{index:04X}h:1 default");
    }
}

/// An invalid RPDO is not received: RPDO2 (60FEh:1/2 digital outputs,
/// §2.3.2) sent on 300h + node-ID changes nothing until it is made valid.
#[test]
fn invalid_rpdo2_is_ignored_until_validated() {
    let (mut r, _) = Rig::new(Profile::Ipos, NODE);
    r.send("000#01 04");
    r.take();
    let before = r.read_u32(NODE, 0x60FE, 1);
    let rpdo2 = "304#00 00 01 00 00 00 01 00";
    r.send(rpdo2);
    r.run_ms(2);
    assert_eq!(r.read_u32(NODE, 0x60FE, 1), before);
    // Made valid (bit 31 cleared), the same frame is taken.
    Rig::assert_written(r.sdo_write(NODE, 0x1401, 1, &[0x04, 0x03, 0, 0]), NODE, 0x1401, 1);
    r.send(rpdo2);
    r.run_ms(2);
    assert_eq!(r.read_u32(NODE, 0x60FE, 1), 0x0001_0000);
}
