//! Kollmorgen KC1, *KC1 CAN-BUS Communication*, edition J 05/2013, firmware 1.9.

use crate::shared::{can, maps::*};
use crate::{ProfileInfo, Quirk, Transport};

/// KC1 facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "Kollmorgen",
    vendor_id: Some(0x6A), // §7.2.1.17
    product_name: "KC1",
    product_code: Some(0x4D30_3036), // §7.2.1.17: 4 ASCII chars, example "M006" (byte order our choice)
    revision: Some(0x0014_0000),     // §7.2.1.17: example CAN version 0.20
    device_type: 0x0002_0192,        // §7.2.1.1
    transport: Transport::Can,
    baud_rates_kbit: &[125, 250, 500, 1000], // §4.2.1 (plus auto-baud, FBUS.PARAM01 = 0)
    supported_drive_modes: 0xE5,             // §7.2.3.10: pp pv hm ip csp; tq bit missing
    modes: &[1, 3, 4, 6, 7, 8],              // §7.4.2.3
    homing_methods: &[1, 2, 8, 12, 17, 18, 24, 28, 33, 34, 35], // §7.10.2.2
    // §7.3.1.3 default RPDO mappings, COB-IDs §6.2, transmission type 255 §7.3.1.1
    rpdo: [can(0x200, 0, CW), can(0x300, 0, CW_MODE), can(0x400, 0, CW_POS), can(0x500, 0, CW_VEL)],
    // §7.3.2.3 default TPDO mappings, §7.3.2.1
    tpdo: [can(0x180, 0, SW), can(0x280, 0, SW_MODE), can(0x380, 0, SW_POS), can(0x480, 0, SW_VEL)],
    granularity: 8,                  // §7.3.1.2: byte-wise mapping only
    max_mapped_entries: 8,           // §7.3.1.2
    dummy_mapping: false,            // §8.2.2.1: 2100h is used instead of 0001h–0007h
    emcy: super::emcy::EMCY,         // §7.1
    sdo_block: false,                // §6.4.5: expedited and segmented only
    time: false,                     // §6.4.3
    nmt_enter_preoperational: false, // §6.4.1: cs 128 not listed
    heartbeat_producer: true,        // §7.2.1.16
    heartbeat_consumers: 1,          // §7.2.1.15
    node_guarding: true,             // §6.4.7
    life_guarding: true,             // §7.2.1.10-11: timeout → F129
    error_behaviour: false,          // no 1029h; fixed reactions (§6.4.7, §5.3)
    emcy_inhibit: false,             // 1015h absent from §8.1.2
    error_history: 10,               // §7.2.1.4
    lss: false,                      // not described
    quirks: QUIRKS,
};

static QUIRKS: &[Quirk] = &[
    Quirk {
        id: "6502-omits-tq",
        section: "§7.2.3.10, §7.4.2.3",
        what: "6502h reads E5h (no tq bit) although 6060h accepts 4",
    },
    Quirk {
        id: "no-nmt-enter-preop",
        section: "§6.4.1",
        what: "NMT cs 80h is not in the supported command list",
    },
    Quirk {
        id: "reset-node-resets-mapping",
        section: "§6.4.1",
        what: "reset node restores all communication and mapping parameters",
    },
    Quirk {
        id: "dummy-object-2100h",
        section: "§8.2.2.1",
        what: "2100h sub 0 (32 bit) is the mapping placeholder; standard dummies are not mentioned",
    },
    Quirk {
        id: "tpdo-change-masks",
        section: "§7.2.2.4",
        what: "2014h–2017h mask which TPDO bits trigger an event transmission",
    },
    Quirk {
        id: "606c-pdo-in-rpm",
        section: "§7.6.2.1",
        what: "606Ch is in user units over SDO but in rpm over PDO",
    },
    Quirk {
        id: "warnings-send-emcy",
        section: "§6.4.4, §7.4.2.2",
        what: "warnings (n-codes) send EMCY and set statusword bit 7 without a state change",
    },
    Quirk {
        id: "emcy-category-byte",
        section: "§6.4.4",
        what: "EMCY byte 3 is a 'category' (values undefined, examples 01h); bytes 4–7 are 0",
    },
    Quirk {
        id: "sdo-length-tolerant",
        section: "§8.2 examples",
        what: "the manual's own frames use wrong SDO sizes and short PDOs; the drive accepts them",
    },
    Quirk {
        id: "guarding-timeout-stops",
        section: "§6.4.7",
        what: "guarding/heartbeat timeout raises F129 (EMCY 8130h) and brakes to standstill",
    },
    Quirk {
        id: "bus-off-f702",
        section: "§5.3",
        what: "bus-off is reported as F702 (EMCY FF01h) and disables the output stage",
    },
    Quirk {
        id: "ascii-channel-2026h",
        section: "§7.2.2.6",
        what: "2026h sub 1/2 carry Telnet commands and answers, 4 characters per SDO",
    },
    Quirk { id: "node-id-0-is-1", section: "§6.2", what: "node-ID 0 from the switches is used as 1" },
    Quirk {
        id: "no-option-codes",
        section: "§7.4.2",
        what: "605Ah–605Eh do not exist; quick stop, halt and fault reactions are fixed",
    },
];
