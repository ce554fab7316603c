//! LAM Technologies DDS6, *Vector Controlled Stepper Motors Drives, CANopen
//! DS301, DS402* user manual, HW 1.00 / FW 0.22.

use crate::shared::can;
use crate::{ProfileInfo, Quirk, Transport};

/// DDS6 facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "LAM Technologies",
    vendor_id: Some(0x30C), // §6.3.16
    product_name: "DDS6244",
    product_code: Some(0x0062_4400), // §6.3.16: per model; DDS6244 chosen (encoder input, all modes)
    revision: None,                  // §6.3.16: layout given, value not
    device_type: 0x0044_0192,        // §6.3.1
    transport: Transport::Can,
    // §3.1, §3.2.2; 100 kbit/s has no CiA 306 BaudRate_ key and is left out of the EDS
    baud_rates_kbit: &[10, 20, 50, 100, 125, 250, 500, 1000],
    supported_drive_modes: 0x6D, // §6.5.37 (IDE screenshot): pp pv tq hm ip
    modes: &[1, 3, 4, 6, 7],     // §6.5.4; csp/csv/cst not in FW 0.22
    // §4.4.4, §6.5.30: 31 methods; 37 instead of 35
    homing_methods: &[
        1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29,
        30, 33, 34, 37,
    ],
    // §6.3.19–6.3.22: only PDO1 valid; RPDO4 maps 607Ah + 6081h as printed
    rpdo: [
        can(0x200, 0, &[0x6040_0010]),
        can(0x8000_0300, 0, &[0x6040_0010, 0x607A_0020]),
        can(0x8000_0400, 0, &[0x6040_0010, 0x60FF_0020]),
        can(0x8000_0500, 0, &[0x607A_0020, 0x6081_0020]),
    ],
    tpdo: [
        can(0x180, 0, &[0x6041_0010]),
        can(0x8000_0280, 100, &[0x6041_0010, 0x6064_0020]),
        can(0x8000_0380, 100, &[0x6041_0010, 0x606C_0020]),
        can(0x8000_0480, 0, &[]),
    ],
    granularity: 8,                 // not stated; byte mapping in every example
    max_mapped_entries: 8,          // §6.3.21/22: sub 1..8
    dummy_mapping: false,           // not mentioned
    emcy: super::emcy::EMCY,        // §5
    sdo_block: false,               // not mentioned (expedited only in the examples)
    time: false,                    // not mentioned
    nmt_enter_preoperational: true, // §6.1: IDE NMT panel lists every service
    heartbeat_producer: true,       // §6.3.15
    heartbeat_consumers: 4,         // §6.3.14 (sub 0 printed 2, four entries described)
    node_guarding: true,            // §6.3.6-7
    life_guarding: true,            // §6.3.6-7: loss → EMCY 8130h
    error_behaviour: true,          // §6.3.17: 1029h:01
    emcy_inhibit: true,             // §6.3.13: 1015h in 0.1 ms
    error_history: 10,              // §6.3.3
    lss: false,                     // not mentioned
    quirks: QUIRKS,
};

static QUIRKS: &[Quirk] = &[
    Quirk {
        id: "tpdo-ff-statusword-change",
        section: "§6.3.21",
        what: "TPDO transmission type FFh sends on a statusword change, not on any mapped change",
    },
    Quirk {
        id: "nmt-while-enabled-82c2",
        section: "§5",
        what: "NMT stop / reset while the motor is enabled raises EMCY 82C2h (class 4: quick stop then fault)",
    },
    Quirk {
        id: "store-refused-when-enabled",
        section: "§4.2, §6.3.10",
        what: "1010h/1011h abort while the motor is enabled or NMT is operational",
    },
    Quirk {
        id: "fault-reset-di2",
        section: "§6.4.8",
        what: "a falling edge on DI2 resets faults by default (2810h:02 = 0502h)",
    },
    Quirk {
        id: "homing-37-not-35",
        section: "§4.4.4",
        what: "homing at the current position is method 37; 35 is not offered",
    },
    Quirk {
        id: "error-classes",
        section: "§5",
        what: "EMCY reaction by class: 0 warning, 2 quick stop, 4 quick stop + fault, 6 disable + fault, 8 power cycle",
    },
    Quirk {
        id: "emcy-subcode", section: "§5", what: "EMCY bytes 3–7 carry a 16-bit sub-code (e.g. 0103h)"
    },
    Quirk {
        id: "tq-needs-encoder",
        section: "§4.4.3",
        what: "profile torque needs closed loop with encoder, else EMCY 63A0h sub-code 0701h",
    },
    Quirk {
        id: "sync-guard-3080h",
        section: "§4.4.5, §6.4",
        what: "3080h supervises the SYNC period and raises EMCY 82B2h",
    },
    Quirk {
        id: "1016-sub0-printed-2",
        section: "§6.3.14",
        what: "1016h sub 0 is printed 02h with four consumer entries",
    },
    Quirk {
        id: "statusword-bits-while-disabled",
        section: "§4.4",
        what: "bits 9, 10 (and 12/13 in some modes) are set in Switch on disabled",
    },
];
