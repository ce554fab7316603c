//! The tables. One line per object (or run of objects); sub-index 0 of an
//! ARRAY/RECORD is its count / highest sub-index. CiA 301 here, CiA 402 in
//! `table402.rs`.

use crate::{Access as A, DataType as T, Def, Kind, Standard, SubDef};

use crate::macros::HS;

/// The CiA 301 (and 302) objects, ascending by index, runs not overlapping.
pub(crate) static CIA301: &[Def] = &[
    // ---- CiA 301 §7.5.2 ----
    var!(Cia301, 0x1000, "Device type", Unsigned32, Ro, false),
    var!(Cia301, 0x1001, "Error register", Unsigned8, Ro, true),
    var!(Cia301, 0x1002, "Manufacturer status register", Unsigned32, Ro, true),
    obj!(
        Cia301,
        Array,
        0x1003,
        0x1003,
        "Pre-defined error field",
        "Number of errors",
        Rw,
        [(1, 254, "Standard error field", Unsigned32, Ro, false)]
    ),
    var!(Cia301, 0x1005, "COB-ID SYNC message", Unsigned32, Rw, false),
    var!(Cia301, 0x1006, "Communication cycle period", Unsigned32, Rw, false),
    var!(Cia301, 0x1007, "Synchronous window length", Unsigned32, Rw, false),
    var!(Cia301, 0x1008, "Manufacturer device name", VisibleString, Const, false),
    var!(Cia301, 0x1009, "Manufacturer hardware version", VisibleString, Const, false),
    var!(Cia301, 0x100A, "Manufacturer software version", VisibleString, Const, false),
    var!(Cia301, 0x100C, "Guard time", Unsigned16, Rw, false),
    var!(Cia301, 0x100D, "Life time factor", Unsigned8, Rw, false),
    obj!(
        Cia301,
        Array,
        0x1010,
        0x1010,
        "Store parameters",
        HS,
        Ro,
        [
            (1, 1, "Save all parameters", Unsigned32, Rw, false),
            (2, 2, "Save communication parameters", Unsigned32, Rw, false),
            (3, 3, "Save application parameters", Unsigned32, Rw, false),
            (4, 127, "Save manufacturer defined parameters {n}", Unsigned32, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Array,
        0x1011,
        0x1011,
        "Restore default parameters",
        HS,
        Ro,
        [
            (1, 1, "Restore all default parameters", Unsigned32, Rw, false),
            (2, 2, "Restore communication default parameters", Unsigned32, Rw, false),
            (3, 3, "Restore application default parameters", Unsigned32, Rw, false),
            (4, 127, "Restore manufacturer defined default parameters {n}", Unsigned32, Rw, false),
        ]
    ),
    var!(Cia301, 0x1012, "COB-ID time stamp object", Unsigned32, Rw, false),
    var!(Cia301, 0x1013, "High resolution time stamp", Unsigned32, Rw, true),
    var!(Cia301, 0x1014, "COB-ID EMCY", Unsigned32, Rw, false),
    var!(Cia301, 0x1015, "Inhibit time EMCY", Unsigned16, Rw, false),
    obj!(
        Cia301,
        Array,
        0x1016,
        0x1016,
        "Consumer heartbeat time",
        HS,
        Ro,
        [(1, 127, "Consumer heartbeat time {n}", Unsigned32, Rw, false)]
    ),
    var!(Cia301, 0x1017, "Producer heartbeat time", Unsigned16, Rw, false),
    obj!(
        Cia301,
        Record,
        0x1018,
        0x1018,
        "Identity object",
        HS,
        Ro,
        [
            (1, 1, "Vendor-ID", Unsigned32, Ro, false),
            (2, 2, "Product code", Unsigned32, Ro, false),
            (3, 3, "Revision number", Unsigned32, Ro, false),
            (4, 4, "Serial number", Unsigned32, Ro, false),
        ]
    ),
    var!(Cia301, 0x1019, "Synchronous counter overflow value", Unsigned8, Rw, false),
    obj!(
        Cia301,
        Array,
        0x1020,
        0x1020,
        "Verify configuration",
        HS,
        Ro,
        [
            (1, 1, "Configuration date", Unsigned32, Rw, false),
            (2, 2, "Configuration time", Unsigned32, Rw, false),
        ]
    ),
    var!(Cia301, 0x1021, "Store EDS", Domain, Ro, false),
    var!(Cia301, 0x1022, "Store format", Unsigned8, Ro, false),
    obj!(
        Cia301,
        Record,
        0x1023,
        0x1023,
        "OS command",
        HS,
        Ro,
        [
            (1, 1, "Command", OctetString, Rw, false),
            (2, 2, "Status", Unsigned8, Ro, false),
            (3, 3, "Reply", OctetString, Ro, false),
        ]
    ),
    var!(Cia301, 0x1024, "OS command mode", Unsigned8, Wo, false),
    obj!(
        Cia301,
        Record,
        0x1025,
        0x1025,
        "OS debugger interface",
        HS,
        Ro,
        [
            (1, 1, "Command", OctetString, Rw, false),
            (2, 2, "Status", Unsigned8, Ro, false),
            (3, 3, "Reply", OctetString, Ro, false),
        ]
    ),
    obj!(
        Cia301,
        Array,
        0x1026,
        0x1026,
        "OS prompt",
        HS,
        Ro,
        [
            (1, 1, "StdIn", Unsigned8, Wo, true),
            (2, 2, "StdOut", Unsigned8, Ro, true),
            (3, 3, "StdErr", Unsigned8, Ro, true),
        ]
    ),
    obj!(
        Cia301,
        Array,
        0x1027,
        0x1027,
        "Module list",
        "Number of connected modules",
        Ro,
        [(1, 254, "Module {n}", Unsigned16, Ro, false)]
    ),
    obj!(
        Cia301,
        Array,
        0x1028,
        0x1028,
        "Emergency consumer object",
        HS,
        Ro,
        [(1, 127, "Emergency consumer {n}", Unsigned32, Rw, false)]
    ),
    obj!(
        Cia301,
        Array,
        0x1029,
        0x1029,
        "Error behavior object",
        HS,
        Ro,
        [
            (1, 1, "Communication error", Unsigned8, Rw, false),
            (2, 254, "Error class {n}", Unsigned8, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1200,
        0x1200,
        "SDO server parameter 1",
        HS,
        Ro,
        [
            (1, 1, "COB-ID client to server (rx)", Unsigned32, Ro, false),
            (2, 2, "COB-ID server to client (tx)", Unsigned32, Ro, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1201,
        0x127F,
        "SDO server parameter {n}",
        HS,
        Ro,
        [
            (1, 1, "COB-ID client to server (rx)", Unsigned32, Rw, false),
            (2, 2, "COB-ID server to client (tx)", Unsigned32, Rw, false),
            (3, 3, "Node-ID of the SDO client", Unsigned8, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1280,
        0x12FF,
        "SDO client parameter {n}",
        HS,
        Ro,
        [
            (1, 1, "COB-ID client to server (tx)", Unsigned32, Rw, false),
            (2, 2, "COB-ID server to client (rx)", Unsigned32, Rw, false),
            (3, 3, "Node-ID of the SDO server", Unsigned8, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1400,
        0x15FF,
        "RPDO{n} communication parameter",
        HS,
        Ro,
        [
            (1, 1, "COB-ID used by RPDO", Unsigned32, Rw, false),
            (2, 2, "Transmission type", Unsigned8, Rw, false),
            (3, 3, "Inhibit time", Unsigned16, Rw, false),
            (4, 4, "Compatibility entry", Unsigned8, Rw, false),
            (5, 5, "Event timer", Unsigned16, Rw, false),
            (6, 6, "SYNC start value", Unsigned8, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1600,
        0x17FF,
        "RPDO{n} mapping parameter",
        "Number of mapped application objects in PDO",
        Rw,
        [(1, 64, "Application object {n}", Unsigned32, Rw, false)]
    ),
    obj!(
        Cia301,
        Record,
        0x1800,
        0x19FF,
        "TPDO{n} communication parameter",
        HS,
        Ro,
        [
            (1, 1, "COB-ID used by TPDO", Unsigned32, Rw, false),
            (2, 2, "Transmission type", Unsigned8, Rw, false),
            (3, 3, "Inhibit time", Unsigned16, Rw, false),
            (4, 4, "Compatibility entry", Unsigned8, Rw, false),
            (5, 5, "Event timer", Unsigned16, Rw, false),
            (6, 6, "SYNC start value", Unsigned8, Rw, false),
        ]
    ),
    obj!(
        Cia301,
        Record,
        0x1A00,
        0x1BFF,
        "TPDO{n} mapping parameter",
        "Number of mapped application objects in PDO",
        Rw,
        [(1, 64, "Application object {n}", Unsigned32, Rw, false)]
    ),
    // ---- CiA 302-3 program download, CiA 302-2 NMT start-up ----
    obj!(
        Cia301,
        Array,
        0x1F50,
        0x1F50,
        "Program data",
        HS,
        Ro,
        [(1, 254, "Program number {n}", Domain, Rw, false)]
    ),
    obj!(
        Cia301,
        Array,
        0x1F51,
        0x1F51,
        "Program control",
        HS,
        Ro,
        [(1, 254, "Program number {n}", Unsigned8, Rw, false)]
    ),
    obj!(
        Cia301,
        Array,
        0x1F56,
        0x1F56,
        "Program software identification",
        HS,
        Ro,
        [(1, 254, "Program number {n}", Unsigned32, Ro, false)]
    ),
    obj!(
        Cia301,
        Array,
        0x1F57,
        0x1F57,
        "Flash status identification",
        HS,
        Ro,
        [(1, 254, "Program number {n}", Unsigned32, Ro, false)]
    ),
    var!(Cia301, 0x1F80, "NMT startup", Unsigned32, Rw, false),
];
