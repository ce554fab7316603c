//! The EtherCAT facts of the Technosoft iPOS twin (*iPOS CoE Programming*,
//! P091.064.UM.0524). Identity numbers and names come from the
//! personality's `ProfileInfo`; everything here is what the ESI adds.
//!
//! # Firmware: FA00G, revision "A00G"
//!
//! The ESI revision is the firmware ID in ASCII (§1.5.4.6). The twin's
//! dictionary (`ipos.eds`) holds objects of the newest firmware line the
//! manual describes: 2112h (TML priority, FA0xx), 2113h–2115h (ASR4,
//! FA00G/FA02G), the CiA 402-2 factor group and profile torque
//! (F515K/FA00x); FoE needs F515F or FA0xx. The oldest firmware with all of
//! them is FA00G; its ID, by the rule that gives "515J" for F515J and
//! "A00A" for the FA0xx FoE password (§17.4.7), is "A00G" = 0x41303047.
//! Newer firmware works with an older ESI (§1.5.4.6), not the reverse, so
//! an older revision would hide objects the twin serves.

use crate::check::CheckOptions;
use crate::description::{
    ALL_STATES, CoeDetails, DcOpMode, DeviceFacts, Eeprom, Mailbox, MailboxArea, MailboxTimeouts, PREOP,
    StateRule, SyncSignal, default_config_area, free_run,
};

/// The firmware the twin emulates.
pub const FIRMWARE: &str = "FA00G";

/// Its revision number: "A00G" in ASCII, most significant byte first.
pub const REVISION: u32 = u32::from_be_bytes(*b"A00G");

/// The iPOS twin's facts, given its identity from the personality
/// (`ProfileInfo`: vendor ID 1A3h §4.8.6, product code §1.5.4.6).
///
/// * Mailboxes of 512 bytes at 0x1000/0x1200: ethercrab 0.7.1 needs at
///   least 394 for the twin's 190 objects (`drivebus-coe` docs), and FoE
///   firmware downloads go faster with large ones. The same mailbox serves
///   BOOT (§3.1, F515F+).
/// * CoE with SDO Information, PDO assignment and configuration (§2.4:
///   1C12h/1C13h and the mapping objects are written by SDO) and complete
///   access (the `drivebus-coe` server offers it); FoE (§17.4); no EoE: the
///   emulation does not tunnel Ethernet, although 210Dh/210Eh exist.
/// * 1C12h/1C13h are writable only in PRE-OP (§2.3.10, §2.3.11).
/// * DC: free run, or SYNC0 at the master's cycle (§3.2: the SYNC0 period
///   is the 1 ms slow loop or a multiple; its falling edge is the
///   reference). The manual gives no shift time, so none is preset.
/// * Mailbox response timeout 20 s: §17.4.7 asks for 20000 ms, the time
///   the drive takes to erase its flash during an FoE download.
pub fn facts(vendor_id: u32, vendor_name: &str, product_code: u32, product: &str) -> DeviceFacts {
    let mut f = DeviceFacts::new(vendor_id, vendor_name, product_code, REVISION, product);
    let mbx = MailboxArea { rx_offset: 0x1000, rx_size: 512, tx_offset: 0x1200, tx_size: 512 };
    f.name = format!("Technosoft {product} (drivebus twin, firmware {FIRMWARE})");
    f.group_type = "TechnosoftDrives".into();
    f.group_name = "Technosoft intelligent drives".into();
    f.mailbox_timeouts = Some(MailboxTimeouts { request_ms: 100, response_ms: 20_000 });
    f.mailbox_area = Some(mbx);
    f.mailbox = Some(Mailbox {
        data_link_layer: true,
        coe: Some(CoeDetails {
            sdo_info: true,
            pdo_assign: true,
            pdo_config: true,
            pdo_upload: false,
            complete_access: true,
        }),
        foe: true,
        eoe: false,
    });
    f.dc = vec![
        free_run(),
        DcOpMode {
            name: "DC".into(),
            desc: "DC-Synchron (SYNC0)".into(),
            assign_activate: 0x0300,
            sync0: Some(SyncSignal { cycle_ns: 0, factor: 1, shift_ns: 0 }),
            sync1: None,
        },
    ];
    f.eeprom = Eeprom { byte_size: 2048, config: default_config_area(), bootstrap: Some(mbx) };
    f.state_rules = vec![
        StateRule { index: 0x1C12, sub: None, read: ALL_STATES, write: PREOP },
        StateRule { index: 0x1C13, sub: None, read: ALL_STATES, write: PREOP },
    ];
    f
}

/// What the iPOS needs of its dictionary on EtherCAT: every mapping object
/// takes 8 entries (§2.4) of at most 64 bits in all (§1.6.3.1); 1C12h and
/// 1C13h take one entry per mapping object (§2.3.10, §2.3.11, examples
/// E10/E11 write sub 3 and sub 4).
pub fn check_options() -> CheckOptions {
    CheckOptions {
        mapping_entries: Some(8),
        max_pdo_bits: Some(64),
        state_rules: facts(0, "", 0, "").state_rules,
        ..CheckOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn revision_is_the_firmware_id() {
        assert_eq!(Ok(REVISION), crate::firmware_revision(FIRMWARE));
        assert_eq!(REVISION, 0x4130_3047);
        assert_eq!(crate::revision_firmware(REVISION).as_deref(), Some("A00G"));
        let f = facts(0x1A3, "Technosoft S.A.", 28_002_021, "iPOS360x VX-CAT");
        assert_eq!(f.revision, REVISION);
        assert!(f.mailbox.is_some_and(|m| m.foe && !m.eoe));
        assert_eq!(check_options().state_rules.len(), 2);
    }
}
