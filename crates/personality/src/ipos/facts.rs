//! Technosoft iPOS, *iPOS CoE Programming*, P091.064.UM.0524 (CiA 402 over EtherCAT).

use crate::shared::coe;
use crate::{ProfileInfo, Quirk, Transport};

/// iPOS facts.
pub static INFO: ProfileInfo = ProfileInfo {
    vendor_name: "Technosoft S.A.",
    vendor_id: Some(0x1A3), // §4.8.6
    product_name: "iPOS360x VX-CAT",
    product_code: Some(28_002_021), // §1.5.4.6: decimal label code of the iPOS360x VX-CAT
    // §1.5.4.6: the firmware ID in ASCII, "A00G" (FA00G), as the SII and
    // the ESI say; the §4.8.6 table default "0100" is overridden so the
    // three images agree (docs/personalities.md).
    revision: Some(0x4130_3047),
    device_type: 0x0006_0192, // §4.8.1
    transport: Transport::EtherCatCoe,
    // EtherCAT has none; served on CAN, the bit rates of Technosoft's CAN
    // drives (the CoE manual gives none; docs/personalities.md).
    baud_rates_kbit: &[125, 250, 500, 1000],
    supported_drive_modes: 0x001C_03E5, // §4.8.2: no tq, ECAM or EGEAR bit
    modes: &[-2, -1, 1, 3, 4, 6, 7, 8, 9, 10], // §4.2.3, §8 (tq from F515K), §11 (-1 gearing), §12 (-2 camming)
    // §6: -4..-1 mechanical-limit methods, 1..14, 17..30, 33..35
    homing_methods: &[
        -4, -3, -2, -1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25,
        26, 27, 28, 29, 30, 33, 34, 35,
    ],
    // §2.3: RxPDO1 is the only one assigned (1C12h:01 = 1600h)
    rpdo: [
        coe(true, &[0x6040_0010, 0x607A_0020]),
        coe(false, &[0x60FE_0120, 0x60FE_0220]),
        coe(false, &[0x6060_0008, 0x6071_0010]), // Appendix A lists 6040h + 607Ah instead
        coe(false, &[0x6081_0020, 0x6083_0020]),
    ],
    // §2.3: TxPDO1 and TxPDO2 assigned (1C13h:00 = 2)
    tpdo: [
        coe(true, &[0x6041_0010, 0x6064_0020, 0x6077_0010]),
        coe(true, &[0x60F4_0020, 0x60FD_0020]),
        coe(false, &[0x606C_0020]),
        coe(false, &[0x6061_0008]),
    ],
    granularity: 8,                  // §2.4: at most 8 one-byte objects
    max_mapped_entries: 8,           // §2.4, 64 bits per PDO (§1.6.3.1)
    dummy_mapping: true,             // §2.2.5: data types 0001h–0007h as RxPDO dummies (and 207Dh)
    emcy: super::emcy::EMCY,         // §3.1.3 Table 3.1.3
    sdo_block: false,                // CoE mailbox SDO; block transfer does not exist on EtherCAT
    time: false,                     // not described
    nmt_enter_preoperational: false, // EtherCAT state machine instead of NMT (§3.1)
    heartbeat_producer: false,       // not documented
    heartbeat_consumers: 0,
    node_guarding: false,
    life_guarding: false,
    error_behaviour: false,
    emcy_inhibit: false,
    error_history: 0, // 1003h not documented
    lss: false,
    quirks: QUIRKS,
};

static QUIRKS: &[Quirk] = &[
    Quirk {
        id: "ethercat-coe",
        section: "§1, §2.2",
        what: "objects are reached over the CoE mailbox; PDOs are assigned with 1C12h/1C13h",
    },
    Quirk {
        id: "6502-omits-tq-egear-ecam",
        section: "§4.8.2",
        what: "6502h = 001C03E5h lacks tq, ECAM and EGEAR although those modes work",
    },
    Quirk {
        id: "6061-after-enable",
        section: "§4.2.3",
        what: "6061h follows 6060h only once Operation Enabled is reached",
    },
    Quirk {
        id: "pdo-64-bit-limit",
        section: "§1.6.3.1",
        what: "a mapping over 64 bits is refused at re-initialisation with EMCY 8210h/8220h",
    },
    Quirk {
        id: "emcy-mask-2001h",
        section: "§3.1.3",
        what: "2000h bit changes send EMCY only if set in the 2001h mask",
    },
    Quirk { id: "home-switch-in0", section: "§6", what: "the home switch is always input IN0" },
    Quirk {
        id: "homing-threshold",
        section: "§6",
        what: "methods -1..-4 end on current above 207Bh for 207Ch; a threshold above the current limit never completes",
    },
    Quirk {
        id: "save-2076h",
        section: "§4.9.6",
        what: "no 1010h/1011h: writing 2076h saves the configuration, 2080h resets the drive",
    },
    Quirk {
        id: "1018-sub0-printed-1",
        section: "§4.8.6",
        what: "1018h sub 0 is printed as 1 although subs 1–4 exist",
    },
    Quirk {
        id: "rxpdo3-appendix-differs",
        section: "§2.3, Appendix A",
        what: "RxPDO3 default is 6060h + 6071h in §2.3 but 6040h + 607Ah in Appendix A",
    },
];
