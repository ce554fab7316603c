//! Kollmorgen AKD, *AKD CAN-BUS Kommunikation*, edition R 09/2016, firmware 1.15.

use crate::shared::{can, maps::*};
use crate::{ProfileInfo, Quirk, Transport};

/// AKD facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "Kollmorgen",
    vendor_id: Some(0x6A), // §6.2.1.18
    product_name: "AKD",
    product_code: Some(0x4D30_3036), // §6.2.1.18: 4 ASCII chars, example "M006" (byte order our choice)
    revision: Some(0x0014_0000),     // §6.2.1.18: example CANopen version 0.20
    device_type: 0x0002_0192,        // §6.2.1.1
    transport: Transport::Can,
    baud_rates_kbit: &[125, 250, 500, 1000], // §3.2.2, §4.2 (plus auto-baud)
    supported_drive_modes: 0xE5,             // §6.2.3.10: tq and the negative modes not shown
    modes: &[-3, -2, -1, 1, 3, 4, 6, 7, 8],  // §6.4.2.4: -3 gearing, -2 analog velocity, -1 analog current
    // §6.10: manufacturer methods -7..-3 (edition R), standard methods as the KC1
    homing_methods: &[-7, -6, -5, -4, -3, 1, 2, 8, 12, 17, 18, 24, 28, 33, 34, 35],
    // §6.3.1.3, COB-IDs §5.2, transmission type 255 §6.3.1.1
    rpdo: [can(0x200, 0, CW), can(0x300, 0, CW_MODE), can(0x400, 0, CW_POS), can(0x500, 0, CW_VEL)],
    // §6.3.2.3, §6.3.2.1
    tpdo: [can(0x180, 0, SW), can(0x280, 0, SW_MODE), can(0x380, 0, SW_POS), can(0x480, 0, SW_VEL)],
    granularity: 8,                  // §6.3: byte-wise mapping only
    max_mapped_entries: 8,           // §6.3.1.2
    dummy_mapping: false,            // §7.2.2.1: 2100h placeholder instead
    emcy: super::emcy::EMCY,         // §6.1
    sdo_block: false,                // §5.4.5
    time: false,                     // §5.4.3: TIME not supported, although 1012h exists (§6.2.1.14)
    nmt_enter_preoperational: false, // §5.4.1
    heartbeat_producer: true,        // §6.2.1.17
    heartbeat_consumers: 1,          // §6.2.1.16
    node_guarding: true,             // §5.4.7
    life_guarding: true,             // §6.2.1.10-11
    error_behaviour: false,          // no 1029h; FAULTxxx.ACTION objects instead
    emcy_inhibit: false,             // 1015h absent
    error_history: 10,               // §6.2.1.4 (plus 2012h/2013h fault history)
    lss: false,                      // not mentioned
    quirks: QUIRKS,
};

static QUIRKS: &[Quirk] = &[
    Quirk {
        id: "6502-omits-tq",
        section: "§6.2.3.10, §6.4.2.4",
        what: "6502h reads E5h: no tq bit, negative modes not shown",
    },
    Quirk {
        id: "no-nmt-enter-preop",
        section: "§5.4.1",
        what: "NMT cs 80h is not in the supported command list",
    },
    Quirk {
        id: "time-object-without-service",
        section: "§5.4.3, §6.2.1.14",
        what: "1012h exists but TIME is not supported",
    },
    Quirk {
        id: "dummy-object-2100h",
        section: "§7.2.2.1",
        what: "2100h sub 0 (32 bit) is the mapping placeholder",
    },
    Quirk {
        id: "tpdo-change-masks",
        section: "§6.2.2.7",
        what: "2014h–2017h mask which TPDO bits trigger an event transmission",
    },
    Quirk {
        id: "only-operation-enabled-setpoints",
        section: "§7.1.2",
        what: "objects marked 'ja*' (6071h, 60FFh, 60B1h, 60B2h, 60C1h:01 ...) act only in Operation Enabled",
    },
    Quirk {
        id: "warnings-send-emcy",
        section: "§3.4, §5.4.4",
        what: "warnings send EMCY unless FBUS.PARAM05 bit 11 is set",
    },
    Quirk {
        id: "emcy-reset-after-each",
        section: "§5.4.4",
        what: "every EMCY is followed by a second EMCY 0000h with the remaining error register",
    },
    Quirk {
        id: "emcy-category-byte",
        section: "§5.4.4",
        what: "EMCY byte 3 is an undefined 'category' (examples 01h)",
    },
    Quirk {
        id: "quick-stop-option-only",
        section: "§6.4",
        what: "605Ah exists (1, 2, 5, 6; default 2); 605Bh–605Eh do not",
    },
    Quirk {
        id: "homing-minus4-dir",
        section: "§6.10",
        what: "methods -4 and -3 are both printed with HOME.DIR 0; -4 taken as the positive direction",
    },
    Quirk {
        id: "606c-pdo-in-rpm",
        section: "§6.6",
        what: "606Ch is in user units over SDO but in rpm over PDO",
    },
    Quirk {
        id: "guarding-timeout-stops",
        section: "§5.4.7",
        what: "guarding/heartbeat timeout raises F129 (EMCY 8130h) and stops the axis",
    },
    Quirk {
        id: "bus-off-f702",
        section: "§4.3",
        what: "bus-off is reported as F702 (EMCY FF01h) and disables the power stage",
    },
];
