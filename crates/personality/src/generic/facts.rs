//! The generic CiA 402 servo: every mode, every service the stack offers.
//! Values come from CiA 301 and CiA 402-2, not from a vendor manual.

use crate::shared::{can, maps::*};
use crate::{EmcyEntry, ProfileInfo, Transport};

/// Generic servo facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "drivebus",
    vendor_id: Some(0), // no CiA vendor-ID assigned
    product_name: "drivebus generic CiA 402 servo",
    product_code: Some(0x402),
    revision: Some(0x0001_0000),
    device_type: 0x0002_0192, // CiA 402: profile 402, servo drive
    transport: Transport::Can,
    baud_rates_kbit: &[10, 20, 50, 125, 250, 500, 800, 1000],
    supported_drive_modes: 0x3ED, // pp pv tq hm ip csp csv cst (no vl objects)
    modes: &[1, 3, 4, 6, 7, 8, 9, 10],
    // CiA 402-2 homing methods (15, 16, 31, 32, 36 reserved)
    homing_methods: &[
        1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29,
        30, 33, 34, 35, 37,
    ],
    // CiA 402 pre-defined mappings (as the Kollmorgen drives)
    rpdo: [can(0x200, 0, CW), can(0x300, 0, CW_MODE), can(0x400, 0, CW_POS), can(0x500, 0, CW_VEL)],
    tpdo: [can(0x180, 0, SW), can(0x280, 0, SW_MODE), can(0x380, 0, SW_POS), can(0x480, 0, SW_VEL)],
    granularity: 1,
    max_mapped_entries: 64,
    dummy_mapping: true,
    emcy: EMCY,
    sdo_block: true,
    time: true,
    nmt_enter_preoperational: true,
    heartbeat_producer: true,
    heartbeat_consumers: 4,
    node_guarding: true,
    life_guarding: true,
    error_behaviour: true,
    emcy_inhibit: true,
    error_history: 8,
    lss: true,
    quirks: &[],
};

/// The CiA 301 communication codes the stack itself raises (CiA 301 §7.2.7.1).
static EMCY: &[EmcyEntry] = &[
    EmcyEntry { code: 0x0000, text: "Error reset or no error", detail: "" },
    EmcyEntry { code: 0x8110, text: "CAN overrun (objects lost)", detail: "" },
    EmcyEntry { code: 0x8120, text: "CAN in error passive mode", detail: "" },
    EmcyEntry { code: 0x8130, text: "Life guard error or heartbeat error", detail: "" },
    EmcyEntry { code: 0x8140, text: "Recovered from bus off", detail: "" },
    EmcyEntry { code: 0x8210, text: "PDO not processed due to length error", detail: "" },
    EmcyEntry { code: 0x8220, text: "PDO length exceeded", detail: "" },
    EmcyEntry { code: 0x8240, text: "Unexpected SYNC data length", detail: "" },
    EmcyEntry { code: 0x8250, text: "RPDO timeout", detail: "" },
];
