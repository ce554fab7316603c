//! SSD 630 object 2018h "NMT operational state" (seed003, *CANopen-630*
//! manual §11: "0 = Standard NMT-Mode (Pre-operational) 1 = NMT state
//! (operational after power on)"; §6: without it the drive "switches then
//! automatically to operating state Pre-operational" and PDOs need the
//! master's Start Remote Node).
//!
//! Power-on is a new node built on the storage the old one saved to with
//! 1010h:1 "save" (§11 store signatures).

mod replay_rig;

use drivebus_node::{MemoryStorage, NmtState, Slot, Storage};
use drivebus_personality::{PersonalityDevice, Profile};
use replay_rig::*;

/// Boot-up and the §9 "no error" EMCY with the firmware tag "V819d".
const BOOT: [&str; 2] = ["701#00", "081#00 00 00 56 38 31 39 64"];

/// A 630 (node 1) that wrote `value` to 2018h and, if `store`, saved all
/// parameters; returns its storage, as a power cycle keeps it.
fn configured(value: u8, store: bool) -> MemoryStorage {
    let (mut r, _) = Rig::new(Profile::Ssd630, 1);
    r.exchange(&format!("601#2B 18 20 00 {value:02X} 00 00 00"), &["581#60 18 20 00 00 00 00 00"]);
    if store {
        r.exchange("601#23 10 10 01 73 61 76 65", &["581#60 10 10 01 00 00 00 00"]);
    }
    let pn = r.pn_mut();
    let mut copy = MemoryStorage::new();
    for slot in [Slot::Communication, Slot::Application, Slot::Manufacturer, Slot::Lss] {
        if let Ok(Some(img)) = pn.node.storage_mut().load(slot) {
            copy.save(slot, &img).unwrap();
        }
    }
    copy
}

/// Power on with `storage`: the frames of the boot and the rig.
fn power_on(storage: MemoryStorage) -> (Rig, Vec<drivebus_can::Frame>) {
    let pn: PersonalityDevice = Profile::Ssd630.build_with_storage(1, Box::new(storage)).unwrap();
    Rig::with(pn)
}

/// Operational: node guarding answers 05h (toggle 0, §8), and RPDO1
/// (controlword, §7 "1. Receive PDO") is taken: Shutdown makes the
/// statusword 0231h (§10.2 Ready to switch on), which TPDO1 and TPDO2
/// (with 6061h = 1, profile position after power-on, §10) send.
fn assert_operational(r: &mut Rig) {
    assert_eq!(r.node().nmt_state(), NmtState::Operational);
    r.exchange("701#R1", &["701#05"]);
    r.exchange_ms("201#06 00", 10, &["181#31 02", "281#31 02 01"]);
}

/// Pre-operational: guarding answers 7Fh; "only the SDO services are
/// active" (§6), so the RPDO changes nothing and no TPDO goes out.
fn assert_pre_operational(r: &mut Rig) {
    assert_eq!(r.node().nmt_state(), NmtState::PreOperational);
    r.exchange("701#R1", &["701#7F"]);
    r.exchange_ms("201#00 00", 10, &[]);
    let before = r.read_u32(1, 0x6041, 0);
    r.exchange_ms("201#06 00", 10, &[]);
    assert_eq!(r.read_u32(1, 0x6041, 0), before, "RPDO1 not taken");
}

#[test]
fn stored_2018h_1_goes_operational_after_power_on() {
    let (mut r, boot) = power_on(configured(1, true));
    // Boot-up and EMCY first, then operational: the event-driven TPDO1
    // (statusword) and TPDO2 (statusword, 6061h) go out (§7 defaults).
    let mut expected = frs(&BOOT);
    expected.extend(frs(&["181#40 02", "281#40 02 01"]));
    assert_eq!(boot, expected);
    assert_eq!(r.read_u32(1, 0x2018, 0), 1);
    assert_operational(&mut r);
}

#[test]
fn stored_2018h_0_stays_pre_operational() {
    let (mut r, boot) = power_on(configured(0, true));
    assert_eq!(boot, frs(&BOOT));
    assert_pre_operational(&mut r);
    // The factory default is 0 as well.
    let (mut r, _) = Rig::new(Profile::Ssd630, 1);
    assert_eq!(r.read_u32(1, 0x2018, 0), 0);
    assert_pre_operational(&mut r);
}

#[test]
fn unsaved_2018h_is_lost_at_power_on() {
    let (mut r, _) = power_on(configured(1, false));
    assert_eq!(r.read_u32(1, 0x2018, 0), 0);
    assert_pre_operational(&mut r);
}

/// NMT Reset Node (§6 cs = 129) is the power-on reset of the application
/// (CiA 301 §7.3.2.1): the stored 2018h applies; Reset Communication
/// (cs = 130) is not a power-on and ends pre-operational as §6 describes.
#[test]
fn reset_node_applies_the_stored_value() {
    let (mut r, _) = power_on(configured(1, true));
    r.take();
    // §9 transition 0: the "no error" EMCY after the initialisation.
    r.exchange("000#81 01", &["701#00", "081#00 00 00 56 38 31 39 64", "181#40 02", "281#40 02 01"]);
    assert_operational(&mut r);
    r.exchange("000#82 01", &["701#00"]);
    assert_pre_operational(&mut r);
    // Written but not saved: Reset Node reloads the stored value.
    let (mut r, _) = Rig::new(Profile::Ssd630, 1);
    r.exchange("601#2B 18 20 00 01 00 00 00", &["581#60 18 20 00 00 00 00 00"]);
    r.exchange("000#81 01", &["701#00", "081#00 00 00 56 38 31 39 64"]);
    assert_eq!(r.read_u32(1, 0x2018, 0), 0);
    assert_pre_operational(&mut r);
}
