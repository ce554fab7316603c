//! The tables. One line per object (or run of objects); sub-index 0 of an
//! ARRAY/RECORD is its count / highest sub-index.

use crate::{Access as A, DataType as T, Def, Kind, Profile, SubDef};

/// A VAR: `var!(profile, index, name, type, access, pdo)`.
macro_rules! var {
    ($p:ident, $i:expr, $n:expr, $t:ident, $a:ident, $pdo:expr) => {
        Def {
            first: $i,
            last: $i,
            name: $n,
            kind: Kind::Var,
            profile: Profile::$p,
            subs: &[SubDef { first: 0, last: 0, name: $n, data_type: T::$t, access: A::$a, pdo: $pdo }],
        }
    };
}

/// An ARRAY or RECORD (or a run of them, `first..last`): sub-index 0 is
/// added as `Highest sub-index supported` (UNSIGNED8, ro) unless `$zero` names it.
macro_rules! obj {
    ($p:ident, $k:ident, $i:expr, $j:expr, $n:expr, $zero:expr, $za:ident,
     [ $( ($f:expr, $l:expr, $sn:expr, $t:ident, $a:ident, $pdo:expr) ),* $(,)? ]) => {
        Def {
            first: $i,
            last: $j,
            name: $n,
            kind: Kind::$k,
            profile: Profile::$p,
            subs: &[
                SubDef { first: 0, last: 0, name: $zero, data_type: T::Unsigned8, access: A::$za, pdo: false },
                $( SubDef { first: $f, last: $l, name: $sn, data_type: T::$t, access: A::$a, pdo: $pdo } ),*
            ],
        }
    };
}

const HS: &str = "Highest sub-index supported";
const NE: &str = "Number of entries";

/// Every standard object, ascending by index, runs not overlapping.
pub(crate) static DEFS: &[Def] = &[
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
    // ---- CiA 402-2 ----
    var!(Cia402, 0x6007, "Abort connection option code", Integer16, Rw, true),
    var!(Cia402, 0x603F, "Error code", Unsigned16, Ro, true),
    var!(Cia402, 0x6040, "Controlword", Unsigned16, Rw, true),
    var!(Cia402, 0x6041, "Statusword", Unsigned16, Ro, true),
    var!(Cia402, 0x6042, "vl target velocity", Integer16, Rw, true),
    var!(Cia402, 0x6043, "vl velocity demand", Integer16, Ro, true),
    var!(Cia402, 0x6044, "vl velocity actual value", Integer16, Ro, true),
    obj!(
        Cia402,
        Array,
        0x6046,
        0x6046,
        "vl velocity min max amount",
        NE,
        Ro,
        [
            (1, 1, "vl velocity min amount", Unsigned32, Rw, true),
            (2, 2, "vl velocity max amount", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6047,
        0x6047,
        "vl velocity min max",
        NE,
        Ro,
        [
            (1, 1, "vl velocity min pos", Unsigned32, Rw, true),
            (2, 2, "vl velocity max pos", Unsigned32, Rw, true),
            (3, 3, "vl velocity min neg", Unsigned32, Rw, true),
            (4, 4, "vl velocity max neg", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Record,
        0x6048,
        0x6048,
        "vl velocity acceleration",
        NE,
        Ro,
        [(1, 1, "Delta speed", Unsigned32, Rw, true), (2, 2, "Delta time", Unsigned16, Rw, true),]
    ),
    obj!(
        Cia402,
        Record,
        0x6049,
        0x6049,
        "vl velocity deceleration",
        NE,
        Ro,
        [(1, 1, "Delta speed", Unsigned32, Rw, true), (2, 2, "Delta time", Unsigned16, Rw, true),]
    ),
    obj!(
        Cia402,
        Record,
        0x604A,
        0x604A,
        "vl velocity quick stop",
        NE,
        Ro,
        [(1, 1, "Delta speed", Unsigned32, Rw, true), (2, 2, "Delta time", Unsigned16, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x604B,
        0x604B,
        "vl set-point factor",
        NE,
        Ro,
        [
            (1, 1, "vl set-point factor numerator", Integer16, Rw, false),
            (2, 2, "vl set-point factor denominator", Integer16, Rw, false),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x604C,
        0x604C,
        "vl dimension factor",
        NE,
        Ro,
        [
            (1, 1, "vl dimension factor numerator", Integer32, Rw, false),
            (2, 2, "vl dimension factor denominator", Integer32, Rw, false),
        ]
    ),
    var!(Cia402, 0x604D, "vl pole number", Unsigned8, Rw, false),
    var!(Cia402, 0x604E, "vl velocity reference", Unsigned32, Rw, true),
    var!(Cia402, 0x604F, "vl ramp function time", Unsigned32, Rw, true),
    var!(Cia402, 0x6050, "vl slow down time", Unsigned32, Rw, true),
    var!(Cia402, 0x6051, "vl quick stop time", Unsigned32, Rw, true),
    var!(Cia402, 0x6052, "vl nominal percentage", Integer16, Rw, true),
    var!(Cia402, 0x6053, "vl percentage demand", Integer16, Ro, true),
    var!(Cia402, 0x6054, "vl actual percentage", Integer16, Ro, true),
    var!(Cia402, 0x6055, "vl manipulated percentage", Integer16, Ro, true),
    obj!(
        Cia402,
        Array,
        0x6056,
        0x6056,
        "vl velocity motor min max amount",
        NE,
        Ro,
        [
            (1, 1, "vl velocity motor min amount", Unsigned32, Rw, true),
            (2, 2, "vl velocity motor max amount", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6057,
        0x6057,
        "vl velocity motor min max",
        NE,
        Ro,
        [
            (1, 1, "vl velocity motor min pos", Unsigned32, Rw, true),
            (2, 2, "vl velocity motor max pos", Unsigned32, Rw, true),
            (3, 3, "vl velocity motor min neg", Unsigned32, Rw, true),
            (4, 4, "vl velocity motor max neg", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6058,
        0x6058,
        "vl frequency motor min max amount",
        NE,
        Ro,
        [
            (1, 1, "vl frequency motor min amount", Unsigned32, Rw, true),
            (2, 2, "vl frequency motor max amount", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6059,
        0x6059,
        "vl frequency motor min max",
        NE,
        Ro,
        [
            (1, 1, "vl frequency motor min pos", Unsigned32, Rw, true),
            (2, 2, "vl frequency motor max pos", Unsigned32, Rw, true),
            (3, 3, "vl frequency motor min neg", Unsigned32, Rw, true),
            (4, 4, "vl frequency motor max neg", Unsigned32, Rw, true),
        ]
    ),
    var!(Cia402, 0x605A, "Quick stop option code", Integer16, Rw, false),
    var!(Cia402, 0x605B, "Shutdown option code", Integer16, Rw, false),
    var!(Cia402, 0x605C, "Disable operation option code", Integer16, Rw, false),
    var!(Cia402, 0x605D, "Halt option code", Integer16, Rw, false),
    var!(Cia402, 0x605E, "Fault reaction option code", Integer16, Rw, false),
    var!(Cia402, 0x6060, "Modes of operation", Integer8, Rw, true),
    var!(Cia402, 0x6061, "Modes of operation display", Integer8, Ro, true),
    var!(Cia402, 0x6062, "Position demand value", Integer32, Ro, true),
    var!(Cia402, 0x6063, "Position actual internal value", Integer32, Ro, true),
    var!(Cia402, 0x6064, "Position actual value", Integer32, Ro, true),
    var!(Cia402, 0x6065, "Following error window", Unsigned32, Rw, true),
    var!(Cia402, 0x6066, "Following error time out", Unsigned16, Rw, true),
    var!(Cia402, 0x6067, "Position window", Unsigned32, Rw, true),
    var!(Cia402, 0x6068, "Position window time", Unsigned16, Rw, true),
    var!(Cia402, 0x6069, "Velocity sensor actual value", Integer32, Ro, true),
    var!(Cia402, 0x606A, "Sensor selection code", Integer16, Rw, true),
    var!(Cia402, 0x606B, "Velocity demand value", Integer32, Ro, true),
    var!(Cia402, 0x606C, "Velocity actual value", Integer32, Ro, true),
    var!(Cia402, 0x606D, "Velocity window", Unsigned16, Rw, true),
    var!(Cia402, 0x606E, "Velocity window time", Unsigned16, Rw, true),
    var!(Cia402, 0x606F, "Velocity threshold", Unsigned16, Rw, true),
    var!(Cia402, 0x6070, "Velocity threshold time", Unsigned16, Rw, true),
    var!(Cia402, 0x6071, "Target torque", Integer16, Rw, true),
    var!(Cia402, 0x6072, "Max torque", Unsigned16, Rw, true),
    var!(Cia402, 0x6073, "Max current", Unsigned16, Rw, true),
    var!(Cia402, 0x6074, "Torque demand", Integer16, Ro, true),
    var!(Cia402, 0x6075, "Motor rated current", Unsigned32, Rw, true),
    var!(Cia402, 0x6076, "Motor rated torque", Unsigned32, Rw, true),
    var!(Cia402, 0x6077, "Torque actual value", Integer16, Ro, true),
    var!(Cia402, 0x6078, "Current actual value", Integer16, Ro, true),
    var!(Cia402, 0x6079, "DC link circuit voltage", Unsigned32, Ro, true),
    var!(Cia402, 0x607A, "Target position", Integer32, Rw, true),
    obj!(
        Cia402,
        Array,
        0x607B,
        0x607B,
        "Position range limit",
        HS,
        Ro,
        [
            (1, 1, "Min position range limit", Integer32, Rw, true),
            (2, 2, "Max position range limit", Integer32, Rw, true),
        ]
    ),
    var!(Cia402, 0x607C, "Home offset", Integer32, Rw, true),
    obj!(
        Cia402,
        Array,
        0x607D,
        0x607D,
        "Software position limit",
        HS,
        Ro,
        [
            (1, 1, "Min position limit", Integer32, Rw, true),
            (2, 2, "Max position limit", Integer32, Rw, true),
        ]
    ),
    var!(Cia402, 0x607E, "Polarity", Unsigned8, Rw, true),
    var!(Cia402, 0x607F, "Max profile velocity", Unsigned32, Rw, true),
    var!(Cia402, 0x6080, "Max motor speed", Unsigned32, Rw, true),
    var!(Cia402, 0x6081, "Profile velocity", Unsigned32, Rw, true),
    var!(Cia402, 0x6082, "End velocity", Unsigned32, Rw, true),
    var!(Cia402, 0x6083, "Profile acceleration", Unsigned32, Rw, true),
    var!(Cia402, 0x6084, "Profile deceleration", Unsigned32, Rw, true),
    var!(Cia402, 0x6085, "Quick stop deceleration", Unsigned32, Rw, true),
    var!(Cia402, 0x6086, "Motion profile type", Integer16, Rw, true),
    var!(Cia402, 0x6087, "Torque slope", Unsigned32, Rw, true),
    var!(Cia402, 0x6088, "Torque profile type", Integer16, Rw, true),
    var!(Cia402, 0x6089, "Position notation index", Integer8, Rw, false),
    var!(Cia402, 0x608A, "Position dimension index", Unsigned8, Rw, false),
    var!(Cia402, 0x608B, "Velocity notation index", Integer8, Rw, false),
    var!(Cia402, 0x608C, "Velocity dimension index", Unsigned8, Rw, false),
    var!(Cia402, 0x608D, "Acceleration notation index", Integer8, Rw, false),
    var!(Cia402, 0x608E, "Acceleration dimension index", Unsigned8, Rw, false),
    obj!(
        Cia402,
        Array,
        0x608F,
        0x608F,
        "Position encoder resolution",
        HS,
        Ro,
        [
            (1, 1, "Encoder increments", Unsigned32, Rw, true),
            (2, 2, "Motor revolutions", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6090,
        0x6090,
        "Velocity encoder resolution",
        HS,
        Ro,
        [
            (1, 1, "Encoder increments per second", Unsigned32, Rw, true),
            (2, 2, "Motor revolutions per second", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6091,
        0x6091,
        "Gear ratio",
        HS,
        Ro,
        [
            (1, 1, "Motor revolutions", Unsigned32, Rw, true),
            (2, 2, "Shaft revolutions", Unsigned32, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x6092,
        0x6092,
        "Feed constant",
        HS,
        Ro,
        [(1, 1, "Feed", Unsigned32, Rw, true), (2, 2, "Shaft revolutions", Unsigned32, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x6093,
        0x6093,
        "Position factor",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x6094,
        0x6094,
        "Velocity encoder factor",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x6095,
        0x6095,
        "Velocity factor 1",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x6096,
        0x6096,
        "Velocity factor",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    obj!(
        Cia402,
        Array,
        0x6097,
        0x6097,
        "Acceleration factor",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    var!(Cia402, 0x6098, "Homing method", Integer8, Rw, true),
    obj!(
        Cia402,
        Array,
        0x6099,
        0x6099,
        "Homing speeds",
        HS,
        Ro,
        [
            (1, 1, "Speed during search for switch", Unsigned32, Rw, true),
            (2, 2, "Speed during search for zero", Unsigned32, Rw, true),
        ]
    ),
    var!(Cia402, 0x609A, "Homing acceleration", Unsigned32, Rw, true),
    obj!(
        Cia402,
        Array,
        0x60A2,
        0x60A2,
        "Jerk factor",
        HS,
        Ro,
        [(1, 1, "Numerator", Unsigned32, Rw, true), (2, 2, "Divisor", Unsigned32, Rw, true),]
    ),
    var!(Cia402, 0x60A3, "Profile jerk use", Unsigned8, Rw, true),
    obj!(
        Cia402,
        Array,
        0x60A4,
        0x60A4,
        "Profile jerk",
        HS,
        Ro,
        [(1, 6, "Profile jerk {n}", Unsigned32, Rw, true)]
    ),
    var!(Cia402, 0x60A8, "SI unit position", Unsigned32, Rw, false),
    var!(Cia402, 0x60A9, "SI unit velocity", Unsigned32, Rw, false),
    var!(Cia402, 0x60AA, "SI unit acceleration", Unsigned32, Rw, false),
    var!(Cia402, 0x60AB, "SI unit jerk", Unsigned32, Rw, false),
    var!(Cia402, 0x60B0, "Position offset", Integer32, Rw, true),
    var!(Cia402, 0x60B1, "Velocity offset", Integer32, Rw, true),
    var!(Cia402, 0x60B2, "Torque offset", Integer16, Rw, true),
    var!(Cia402, 0x60B8, "Touch probe function", Unsigned16, Rw, true),
    var!(Cia402, 0x60B9, "Touch probe status", Unsigned16, Ro, true),
    var!(Cia402, 0x60BA, "Touch probe 1 positive edge", Integer32, Ro, true),
    var!(Cia402, 0x60BB, "Touch probe 1 negative edge", Integer32, Ro, true),
    var!(Cia402, 0x60BC, "Touch probe 2 positive edge", Integer32, Ro, true),
    var!(Cia402, 0x60BD, "Touch probe 2 negative edge", Integer32, Ro, true),
    var!(Cia402, 0x60C0, "Interpolation sub mode select", Integer16, Rw, true),
    obj!(
        Cia402,
        Array,
        0x60C1,
        0x60C1,
        "Interpolation data record",
        HS,
        Ro,
        [(1, 254, "Set-point {n}", Integer32, Rw, true)]
    ),
    obj!(
        Cia402,
        Record,
        0x60C2,
        0x60C2,
        "Interpolation time period",
        HS,
        Ro,
        [
            (1, 1, "Interpolation time period value", Unsigned8, Rw, true),
            (2, 2, "Interpolation time index", Integer8, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Array,
        0x60C3,
        0x60C3,
        "Interpolation sync definition",
        HS,
        Ro,
        [
            (1, 1, "Synchronize on group", Unsigned8, Rw, true),
            (2, 2, "ip sync every n event", Unsigned8, Rw, true),
        ]
    ),
    obj!(
        Cia402,
        Record,
        0x60C4,
        0x60C4,
        "Interpolation data configuration",
        HS,
        Ro,
        [
            (1, 1, "Maximum buffer size", Unsigned32, Ro, false),
            (2, 2, "Actual buffer size", Unsigned32, Rw, false),
            (3, 3, "Buffer organization", Unsigned8, Rw, false),
            (4, 4, "Buffer position", Unsigned16, Rw, false),
            (5, 5, "Size of data record", Unsigned8, Wo, false),
            (6, 6, "Buffer clear", Unsigned8, Wo, false),
        ]
    ),
    var!(Cia402, 0x60C5, "Max acceleration", Unsigned32, Rw, true),
    var!(Cia402, 0x60C6, "Max deceleration", Unsigned32, Rw, true),
    obj!(
        Cia402,
        Array,
        0x60D0,
        0x60D0,
        "Touch probe source",
        HS,
        Ro,
        [
            (1, 1, "Touch probe 1 source", Integer16, Rw, true),
            (2, 2, "Touch probe 2 source", Integer16, Rw, true),
        ]
    ),
    var!(Cia402, 0x60D5, "Touch probe 1 positive edge counter", Unsigned16, Ro, true),
    var!(Cia402, 0x60D6, "Touch probe 1 negative edge counter", Unsigned16, Ro, true),
    var!(Cia402, 0x60D7, "Touch probe 2 positive edge counter", Unsigned16, Ro, true),
    var!(Cia402, 0x60D8, "Touch probe 2 negative edge counter", Unsigned16, Ro, true),
    var!(Cia402, 0x60E0, "Positive torque limit value", Unsigned16, Rw, true),
    var!(Cia402, 0x60E1, "Negative torque limit value", Unsigned16, Rw, true),
    obj!(
        Cia402,
        Array,
        0x60E3,
        0x60E3,
        "Supported homing methods",
        HS,
        Ro,
        [(1, 254, "Homing method {n}", Integer8, Ro, false)]
    ),
    obj!(
        Cia402,
        Array,
        0x60E4,
        0x60E4,
        "Additional position actual values",
        HS,
        Ro,
        [(1, 254, "Position actual value {n}", Integer32, Ro, true)]
    ),
    obj!(
        Cia402,
        Array,
        0x60E5,
        0x60E5,
        "Additional velocity actual values",
        HS,
        Ro,
        [(1, 254, "Velocity actual value {n}", Integer32, Ro, true)]
    ),
    var!(Cia402, 0x60F2, "Positioning option code", Unsigned16, Rw, true),
    var!(Cia402, 0x60F4, "Following error actual value", Integer32, Ro, true),
    var!(Cia402, 0x60F8, "Max slippage", Integer32, Rw, true),
    var!(Cia402, 0x60FA, "Control effort", Integer32, Ro, true),
    var!(Cia402, 0x60FC, "Position demand internal value", Integer32, Ro, true),
    var!(Cia402, 0x60FD, "Digital inputs", Unsigned32, Ro, true),
    obj!(
        Cia402,
        Array,
        0x60FE,
        0x60FE,
        "Digital outputs",
        HS,
        Ro,
        [(1, 1, "Physical outputs", Unsigned32, Rw, true), (2, 2, "Bit mask", Unsigned32, Rw, true),]
    ),
    var!(Cia402, 0x60FF, "Target velocity", Integer32, Rw, true),
    var!(Cia402, 0x6402, "Motor type", Unsigned16, Rw, false),
    var!(Cia402, 0x6403, "Motor catalogue number", VisibleString, Rw, false),
    var!(Cia402, 0x6404, "Motor manufacturer", VisibleString, Rw, false),
    var!(Cia402, 0x6405, "HTTP motor catalogue address", VisibleString, Rw, false),
    var!(Cia402, 0x6406, "Motor calibration date", TimeOfDay, Rw, false),
    var!(Cia402, 0x6407, "Motor service period", Unsigned32, Rw, false),
    var!(Cia402, 0x6502, "Supported drive modes", Unsigned32, Ro, true),
    var!(Cia402, 0x6503, "Drive catalogue number", VisibleString, Ro, false),
    var!(Cia402, 0x6504, "Drive manufacturer", VisibleString, Ro, false),
    var!(Cia402, 0x6505, "HTTP drive catalogue address", VisibleString, Ro, false),
];
