#!/usr/bin/env python3
"""Write eds/generic.eds: every CiA 301 communication object the drivebus
stack implements plus the full CiA 402 object set of a servo drive with
every mode. Types, access and mappability follow CiA 301 / CiA 402; the
defaults are ours (docs/personalities.md lists the uncertain ones)."""

import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from tsv2eds import Obj, write_eds, U8, U16, U32, I8, I16, I32, VS, DOM  # noqa: E402

objs = {}


def e(name, t, acc, default=None, pdo=False, low=None, high=None):
    return {"raw": None, "sec": "", "type": t, "access": acc, "pdo": pdo, "default": default,
            "low": low, "high": high, "name": name}


def var(index, name, t, acc, default=None, pdo=False, low=None, high=None):
    o = Obj(index)
    o.name, o.code = name, 7
    o.subs[0] = e(name, t, acc, default, pdo, low, high)
    objs[index] = o


def arr(index, name, code, subs, n0=None, acc0="ro"):
    """subs: list of entry dicts for sub 1..n."""
    o = Obj(index)
    o.name, o.code = name, code
    o.subs[0] = e("Highest sub-index supported", U8, acc0, str(n0 if n0 is not None else len(subs)))
    for i, s in enumerate(subs, 1):
        o.subs[i] = s
    objs[index] = o


ARRAY, RECORD = 8, 9

# ---- CiA 301 communication objects (CiA 301 §7.5.2) ----
var(0x1000, "Device type", U32, "ro", "0x00020192")
var(0x1001, "Error register", U8, "ro", "0", pdo=True)
arr(0x1003, "Pre-defined error field", ARRAY,
    [e(f"Standard error field {i}", U32, "ro", "0") for i in range(1, 9)], n0=0, acc0="rw")
var(0x1005, "COB-ID SYNC message", U32, "rw", "0x00000080")
var(0x1006, "Communication cycle period", U32, "rw", "0")
var(0x1007, "Synchronous window length", U32, "rw", "0")
var(0x1008, "Manufacturer device name", VS, "const", "drivebus generic servo")
var(0x1009, "Manufacturer hardware version", VS, "const", "virtual")
var(0x100A, "Manufacturer software version", VS, "const", "0.1.0")
var(0x100C, "Guard time", U16, "rw", "0")
var(0x100D, "Life time factor", U8, "rw", "0")
arr(0x1010, "Store parameters", ARRAY, [e(n, U32, "rw", "1") for n in (
    "Save all parameters", "Save communication parameters", "Save application parameters",
    "Save manufacturer defined parameters")])
arr(0x1011, "Restore default parameters", ARRAY, [e(n, U32, "rw", "1") for n in (
    "Restore all default parameters", "Restore communication default parameters",
    "Restore application default parameters", "Restore manufacturer defined default parameters")])
var(0x1012, "COB-ID time stamp object", U32, "rw", "0x00000100")
var(0x1014, "COB-ID EMCY", U32, "rw", "$NODEID+0x80")
var(0x1015, "Inhibit time EMCY", U16, "rw", "0")
arr(0x1016, "Consumer heartbeat time", ARRAY, [e(f"Consumer heartbeat time {i}", U32, "rw", "0") for i in range(1, 5)])
var(0x1017, "Producer heartbeat time", U16, "rw", "0")
arr(0x1018, "Identity object", RECORD, [
    e("Vendor-ID", U32, "ro", "0x00000000"), e("Product code", U32, "ro", "0x00000402"),
    e("Revision number", U32, "ro", "0x00010000"), e("Serial number", U32, "ro", "0x00000001")])
var(0x1019, "Synchronous counter overflow value", U8, "rw", "0")
var(0x1021, "Store EDS", DOM, "ro")
var(0x1022, "Store format", U8, "ro", "0")
arr(0x1029, "Error behaviour", ARRAY, [e("Communication error", U8, "rw", "0"),
                                       e("Device profile or manufacturer error", U8, "rw", "0")])
arr(0x1200, "SDO server parameter", RECORD, [
    e("COB-ID client to server (rx)", U32, "ro", "$NODEID+0x600"),
    e("COB-ID server to client (tx)", U32, "ro", "$NODEID+0x580")])

RPDO_MAP = [[0x60400010], [0x60400010, 0x60600008], [0x60400010, 0x607A0020], [0x60400010, 0x60FF0020]]
TPDO_MAP = [[0x60410010], [0x60410010, 0x60610008], [0x60410010, 0x60640020], [0x60410010, 0x606C0020]]
for n in range(4):
    o = Obj(0x1400 + n)
    o.name, o.code = f"RPDO{n + 1} communication parameter", RECORD
    o.subs = {0: e("Highest sub-index supported", U8, "ro", "5"),
              1: e(f"COB-ID used by RPDO{n + 1}", U32, "rw", f"$NODEID+0x{0x200 + 0x100 * n:X}"),
              2: e("Transmission type", U8, "rw", "0xFF"),
              3: e("Inhibit time", U16, "rw", "0"),
              5: e("Event timer", U16, "rw", "0")}
    objs[o.index] = o
    maps = RPDO_MAP[n]
    arr(0x1600 + n, f"RPDO{n + 1} mapping parameter", RECORD,
        [e(f"Application object {i}", U32, "rw", f"0x{maps[i - 1]:08X}" if i <= len(maps) else "0x00000000")
         for i in range(1, 65)], n0=len(maps), acc0="rw")
for n in range(4):
    o = Obj(0x1800 + n)
    o.name, o.code = f"TPDO{n + 1} communication parameter", RECORD
    o.subs = {0: e("Highest sub-index supported", U8, "ro", "6"),
              1: e(f"COB-ID used by TPDO{n + 1}", U32, "rw", f"$NODEID+0x{0x180 + 0x100 * n:X}"),
              2: e("Transmission type", U8, "rw", "0xFF"),
              3: e("Inhibit time", U16, "rw", "0"),
              4: e("Reserved", U8, "rw", "0"),
              5: e("Event timer", U16, "rw", "0"),
              6: e("SYNC start value", U8, "rw", "0")}
    objs[o.index] = o
    maps = TPDO_MAP[n]
    arr(0x1A00 + n, f"TPDO{n + 1} mapping parameter", RECORD,
        [e(f"Application object {i}", U32, "rw", f"0x{maps[i - 1]:08X}" if i <= len(maps) else "0x00000000")
         for i in range(1, 65)], n0=len(maps), acc0="rw")
# Program download (CiA 302-3): one program.
arr(0x1F50, "Program data", ARRAY, [e("Program number 1", DOM, "rw")])
arr(0x1F51, "Program control", ARRAY, [e("Program number 1", U8, "rw", "0")])
arr(0x1F56, "Program software identification", ARRAY, [e("Program number 1", U32, "ro", "0")])

# ---- CiA 402 (CiA 402-2 object dictionary) ----
var(0x6007, "Abort connection option code", I16, "rw", "1", low="0", high="3")
var(0x603F, "Error code", U16, "ro", "0", pdo=True)
var(0x6040, "Controlword", U16, "rww", "0", pdo=True)
var(0x6041, "Statusword", U16, "ro", "0", pdo=True)
var(0x605A, "Quick stop option code", I16, "rw", "2", low="0", high="8")
var(0x605B, "Shutdown option code", I16, "rw", "0", low="-1", high="1")
var(0x605C, "Disable operation option code", I16, "rw", "1", low="-1", high="1")
var(0x605D, "Halt option code", I16, "rw", "1", low="1", high="4")
var(0x605E, "Fault reaction option code", I16, "rw", "2", low="0", high="4")
var(0x6060, "Modes of operation", I8, "rw", "0", pdo=True)
var(0x6061, "Modes of operation display", I8, "ro", "0", pdo=True)
var(0x6062, "Position demand value", I32, "ro", "0", pdo=True)
var(0x6063, "Position actual internal value", I32, "ro", "0", pdo=True)
var(0x6064, "Position actual value", I32, "ro", "0", pdo=True)
var(0x6065, "Following error window", U32, "rw", "0x00002710", pdo=True)
var(0x6066, "Following error time out", U16, "rw", "0x000A", pdo=True)
var(0x6067, "Position window", U32, "rw", "0x0000000A", pdo=True)
var(0x6068, "Position window time", U16, "rw", "0", pdo=True)
var(0x606B, "Velocity demand value", I32, "ro", "0", pdo=True)
var(0x606C, "Velocity actual value", I32, "ro", "0", pdo=True)
var(0x606D, "Velocity window", U16, "rw", "0x000A", pdo=True)
var(0x606E, "Velocity window time", U16, "rw", "0", pdo=True)
var(0x606F, "Velocity threshold", U16, "rw", "0x000A", pdo=True)
var(0x6070, "Velocity threshold time", U16, "rw", "0", pdo=True)
var(0x6071, "Target torque", I16, "rww", "0", pdo=True)
var(0x6072, "Max torque", U16, "rw", "0x0BB8", pdo=True)
var(0x6073, "Max current", U16, "rw", "0x0BB8", pdo=True)
var(0x6074, "Torque demand", I16, "ro", "0", pdo=True)
var(0x6075, "Motor rated current", U32, "rw", "0x000003E8")
var(0x6076, "Motor rated torque", U32, "rw", "0x000003E8")
var(0x6077, "Torque actual value", I16, "ro", "0", pdo=True)
var(0x6078, "Current actual value", I16, "ro", "0", pdo=True)
# mV: the small servo's 320 V bus (DriveParams::servo_small).
var(0x6079, "DC link circuit voltage", U32, "ro", "0x0004E200", pdo=True)
var(0x607A, "Target position", I32, "rww", "0", pdo=True)
arr(0x607B, "Position range limit", ARRAY, [e("Min position range limit", I32, "rw", "-2147483648", True),
                                            e("Max position range limit", I32, "rw", "2147483647", True)])
var(0x607C, "Home offset", I32, "rw", "0", pdo=True)
arr(0x607D, "Software position limit", ARRAY, [e("Min position limit", I32, "rw", "-2147483648", True),
                                               e("Max position limit", I32, "rw", "2147483647", True)])
var(0x607E, "Polarity", U8, "rw", "0", pdo=True)
var(0x607F, "Max profile velocity", U32, "rw", "0x7FFFFFFF", pdo=True)
var(0x6080, "Max motor speed", U32, "rw", "0x00001770", pdo=True)
var(0x6081, "Profile velocity", U32, "rw", "0x000003E8", pdo=True)
var(0x6082, "End velocity", U32, "rw", "0", pdo=True)
var(0x6083, "Profile acceleration", U32, "rw", "0x00002710", pdo=True)
var(0x6084, "Profile deceleration", U32, "rw", "0x00002710", pdo=True)
var(0x6085, "Quick stop deceleration", U32, "rw", "0x000186A0", pdo=True)
var(0x6086, "Motion profile type", I16, "rw", "0", pdo=True)
var(0x6087, "Torque slope", U32, "rw", "0x000003E8", pdo=True)
var(0x6088, "Torque profile type", I16, "rw", "0", pdo=True)
for idx, name, s1, s2 in ((0x608F, "Position encoder resolution", "Encoder increments", "Motor revolutions"),
                          (0x6090, "Velocity encoder resolution", "Encoder increments per second", "Motor revolutions per second"),
                          (0x6091, "Gear ratio", "Motor shaft revolutions", "Driving shaft revolutions"),
                          (0x6092, "Feed constant", "Feed", "Driving shaft revolutions"),
                          (0x6096, "Velocity factor", "Numerator", "Divisor"),
                          (0x6097, "Acceleration factor", "Numerator", "Divisor")):
    first = "0x00001000" if idx in (0x608F, 0x6090) else "0x00000001"
    arr(idx, name, ARRAY, [e(s1, U32, "rw", first), e(s2, U32, "rw", "0x00000001")])
var(0x6098, "Homing method", I8, "rw", "0", pdo=True)
arr(0x6099, "Homing speeds", ARRAY, [e("Speed during search for switch", U32, "rw", "0x000003E8", True),
                                     e("Speed during search for zero", U32, "rw", "0x00000064", True)])
var(0x609A, "Homing acceleration", U32, "rw", "0x00002710", pdo=True)
for idx, name in ((0x60A8, "SI unit position"), (0x60A9, "SI unit velocity"),
                  (0x60AA, "SI unit acceleration"), (0x60AB, "SI unit jerk")):
    var(idx, name, U32, "rw", "0")
var(0x60B0, "Position offset", I32, "rw", "0", pdo=True)
var(0x60B1, "Velocity offset", I32, "rw", "0", pdo=True)
var(0x60B2, "Torque offset", I16, "rw", "0", pdo=True)
var(0x60B8, "Touch probe function", U16, "rw", "0", pdo=True)
var(0x60B9, "Touch probe status", U16, "ro", "0", pdo=True)
var(0x60BA, "Touch probe 1 positive edge", I32, "ro", "0", pdo=True)
var(0x60BB, "Touch probe 1 negative edge", I32, "ro", "0", pdo=True)
var(0x60BC, "Touch probe 2 positive edge", I32, "ro", "0", pdo=True)
var(0x60BD, "Touch probe 2 negative edge", I32, "ro", "0", pdo=True)
var(0x60C0, "Interpolation sub mode select", I16, "rw", "0")
# Sub 1 the position; subs 2 (velocity) and 3 (segment time, ms) for the
# PT (60C0h = -1) and PVT (-2) sub-modes the generic drive offers.
arr(0x60C1, "Interpolation data record", ARRAY, [e("Interpolation data record 1", I32, "rww", "0", True),
                                                 e("Interpolation data record 2", I32, "rww", "0", True),
                                                 e("Interpolation data record 3", I32, "rww", "0", True)])
o = Obj(0x60C2)
o.name, o.code = "Interpolation time period", RECORD
o.subs = {0: e("Highest sub-index supported", U8, "ro", "2"),
          1: e("Interpolation time period value", U8, "rw", "1"),
          2: e("Interpolation time index", I8, "rw", "-3", low="-128", high="63")}
objs[0x60C2] = o
arr(0x60C3, "Interpolation sync definition", ARRAY, [e("Synchronize on group", U8, "rw", "0"),
                                                     e("ip sync every n event", U8, "rw", "1")])
o = Obj(0x60C4)
o.name, o.code = "Interpolation data configuration", RECORD
o.subs = {0: e("Highest sub-index supported", U8, "ro", "6"),
          1: e("Maximum buffer size", U32, "ro", "0x00000001"),
          2: e("Actual buffer size", U32, "rw", "0x00000001"),
          3: e("Buffer organization", U8, "rw", "0"),
          4: e("Buffer position", U16, "rw", "0"),
          5: e("Size of data record", U8, "wo", "1"),
          6: e("Buffer clear", U8, "wo", "0")}
objs[0x60C4] = o
var(0x60C5, "Max acceleration", U32, "rw", "0x7FFFFFFF", pdo=True)
var(0x60C6, "Max deceleration", U32, "rw", "0x7FFFFFFF", pdo=True)
METHODS = list(range(1, 15)) + list(range(17, 31)) + [33, 34, 35, 37]
arr(0x60E3, "Supported homing methods", ARRAY, [e(f"Supported homing method {i}", I8, "ro", str(m))
                                                for i, m in enumerate(METHODS, 1)])
var(0x60F4, "Following error actual value", I32, "ro", "0", pdo=True)
var(0x60FD, "Digital inputs", U32, "ro", "0", pdo=True)
arr(0x60FE, "Digital outputs", ARRAY, [e("Physical outputs", U32, "rw", "0", True),
                                       e("Bit mask", U32, "rw", "0", True)])
var(0x60FF, "Target velocity", I32, "rww", "0", pdo=True)
# pp, pv, tq, hm, ip, csp, csv, cst (bits 0, 2, 3, 5, 6, 7, 8, 9); no vl objects (6042h...) so no bit 1.
var(0x6502, "Supported drive modes", U32, "ro", "0x000003ED", pdo=True)

# Power-on values: CiA 402-2 gives no defaults for these, so the EDS states
# the working values the drive really starts with (DriveConfig::servo on
# DriveParams::servo_small: 0.001 degree position units, velocity limit of
# the motor 36 000 000 units/s, ramps of 10x/40x it, homing speeds 1/4 and
# 1/40 of 6081h; the generic behaviour's 16-record ip buffer). 607Bh/607Dh
# 0/0 = no limit (CiA 402-2: a range or limit whose min equals its max is
# not checked; drivebus treats 0/0 as "off").
WORKING = {
    (0x6065, 0): "0x00008CA0", (0x6066, 0): "0x0032", (0x6067, 0): "0x00000064",
    (0x6068, 0): "0x000A", (0x606D, 0): "0x4E20", (0x606E, 0): "0x000A",
    (0x606F, 0): "0x4E20", (0x6070, 0): "0x000A", (0x6072, 0): "0x0FA0",
    (0x6073, 0): "0x0FA0", (0x6075, 0): "0x00000640", (0x6076, 0): "0x00000280",
    (0x607B, 1): "0", (0x607B, 2): "0", (0x607D, 1): "0", (0x607D, 2): "0",
    (0x607F, 0): "0x02255100", (0x6080, 0): "0x02255100", (0x6081, 0): "0x0112A880",
    (0x6083, 0): "0x15752A00", (0x6084, 0): "0x15752A00", (0x6085, 0): "0x55D4A800",
    (0x6087, 0): "0x00002710", (0x608F, 1): "0x00100000", (0x6090, 1): "0x00100000",
    (0x6092, 1): "0x00057E40", (0x6099, 1): "0x0044AA20", (0x6099, 2): "0x0006DDD0",
    (0x609A, 0): "0x15752A00", (0x60A8, 0): "0xFD410000", (0x60A9, 0): "0xFD410300",
    (0x60AA, 0): "0xFD410357", (0x60C4, 1): "0x00000010", (0x60C4, 2): "0x00000010", (0x60C4, 5): "4",
    (0x60C4, 6): "1", (0x60C5, 0): "0xFFFFFFFF", (0x60C6, 0): "0xFFFFFFFF",
    (0x60FE, 2): "0xFFFF0000",
}
for (i, s), v in WORKING.items():
    objs[i].subs[s]["default"] = v
# 608Fh/6090h describe the encoder the generic servo's motor has (2^20
# counts per revolution): writable as CiA 402-2 has them, but only with the
# value of that encoder (another value would describe other hardware).
for i in (0x608F, 0x6090):
    for sub in (1, 2):
        objs[i].subs[sub]["low"] = objs[i].subs[sub]["high"] = objs[i].subs[sub]["default"]

cfg = {
    "product": "drivebus generic CiA 402 servo", "manual": "CiA 301 / CiA 402-2 (no vendor manual)",
    "tsv": "-", "description": "Generic CiA 402 servo drive with every mode, every CiA 301 service drivebus implements",
    "vendor": "drivebus", "vendor_number": 0, "product_number": 0x402, "revision_number": 0x00010000,
    "baud": (10, 20, 50, 125, 250, 500, 800, 1000), "granularity": 1, "nr_rx": 4, "nr_tx": 4,
    "dummies": (2, 3, 4, 5, 6, 7), "lss": 1,
    "header": "; Written from CiA 301 and CiA 402-2 (no vendor manual); uncertain defaults: docs/personalities.md",
}
write_eds("generic", cfg, objs)
print("generic", len(objs), "objects")
