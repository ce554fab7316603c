//! SSD Drives 630 series, *CANopen-630* product manual, modification V0904.

use crate::shared::{can, maps::*};
use crate::{ProfileInfo, Quirk, Transport};

/// SSD 630 facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "SSD Drives GmbH",
    vendor_id: None, // §11: 1018h sub 1 exists, value not given
    product_name: "631",
    product_code: None,
    revision: None,
    device_type: 0x0002_0192, // §14.3 example (92 01 02 00)
    transport: Transport::Can,
    baud_rates_kbit: &[20, 50, 125, 250, 500, 800, 1000], // §1.2.1
    supported_drive_modes: 0x67, // value not given (§4, §12); derived from the modes below
    modes: &[1, 2, 3, 6, 7],     // §10 (pp at power-on), §12 vl objects, §14.15 pv, §14.10 hm, §14.12 ip
    // §12 6098h: the drive's own homing modes 0..23 are written as -24..-1; 0 = no homing
    homing_methods: &[
        -24, -23, -22, -21, -20, -19, -18, -17, -16, -15, -14, -13, -12, -11, -10, -9, -8, -7, -6, -5, -4,
        -3, -2, -1,
    ],
    // §7: PDO1/PDO2 enabled, PDO3/PDO4 disabled (bit 31), type 255
    rpdo: [
        can(0x200, 0, CW),
        can(0x300, 0, CW_MODE),
        can(0x8000_0400, 0, CW_POS),
        can(0x8000_0500, 0, &[0x6040_0010, 0x6081_0020]),
    ],
    tpdo: [
        can(0x180, 0, SW),
        can(0x280, 0, SW_MODE),
        can(0x8000_0380, 0, SW_POS),
        can(0x8000_0480, 0, SW_VEL),
    ],
    granularity: 8,                 // §7: 60FDh may be mapped as a 16-bit half
    max_mapped_entries: 8,          // §7
    dummy_mapping: false,           // not mentioned
    emcy: super::emcy::EMCY,        // §9 Table 1
    sdo_block: false,               // §3, §5: expedited and segmented
    time: false,                    // not mentioned
    nmt_enter_preoperational: true, // §6: cs 128
    heartbeat_producer: false,      // §8: node guarding only
    heartbeat_consumers: 0,
    node_guarding: true,  // §8
    life_guarding: false, // §8: 100Ch/100Dh are not evaluated
    error_behaviour: false,
    emcy_inhibit: true, // §4: 1015h
    error_history: 8,   // §9
    lss: false,
    quirks: QUIRKS,
};

static QUIRKS: &[Quirk] = &[
    Quirk {
        id: "node-guarding-only",
        section: "§8",
        what: "answers node guarding but never supervises the master: 100Ch/100Dh ignored, no heartbeat",
    },
    Quirk {
        id: "homing-negative-modes",
        section: "§12, §14.10",
        what: "6098h takes only -24..-1 (own modes 0..23) and 0; standard methods are not mentioned",
    },
    Quirk {
        id: "powers-up-in-pp",
        section: "§10",
        what: "after power-on 6060h/6061h = 1 (profile position)",
    },
    Quirk {
        id: "remote-needs-enable",
        section: "§10.2",
        what: "statusword bit 9 needs the hardware enable; without it Shutdown is refused",
    },
    Quirk {
        id: "unknown-index-06010000",
        section: "§14 example",
        what: "an unknown index is answered with abort 0601 0000h, not 0602 0000h",
    },
    Quirk {
        id: "emcy-no-error-firmware",
        section: "§9",
        what: "EMCY 0000h after initialisation carries the firmware version as ASCII in bytes 3–7",
    },
    Quirk { id: "1006-is-ip-cycle", section: "§14.13", what: "1006h (µs) sets the interpolation cycle" },
    Quirk {
        id: "60ff-zero-before-mode-change",
        section: "§14.15",
        what: "60FFh must be 0 before leaving profile velocity",
    },
    Quirk {
        id: "tt254-masks",
        section: "§7, §11",
        what: "transmission type 254 plus 2014h–2017h masks select which bits trigger a TPDO",
    },
    Quirk {
        id: "statusword-bit15-moving",
        section: "§14.9, §14.11",
        what: "statusword bit 15 is set while moving",
    },
    Quirk {
        id: "auto-operational-2018h",
        section: "§11",
        what: "2018h = 1 makes the node go operational by itself after power-on",
    },
    Quirk {
        id: "mode-objects-u16-in-tables",
        section: "§12",
        what: "6060h/6061h/6098h printed as UNSIGNED16 while examples use 1-byte access",
    },
];
