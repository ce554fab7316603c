#!/usr/bin/env python3
"""Writes eds/io16.eds: a CiA 401 generic I/O module with 16 digital
inputs, 16 digital outputs, 4 analog inputs and 2 analog outputs, CiA
401's pre-defined PDOs (TPDO1 digital inputs, TPDO2 analog inputs, RPDO1
digital outputs, RPDO2 analog outputs), heartbeat, LSS.

    python3 tools/io_eds.py   (in crates/cia401)
"""
from pathlib import Path

U8, U16, U32, I16, I32, BOOL = 0x5, 0x6, 0x7, 0x3, 0x4, 0x1
out = []


def var(index, name, dt, access, default, pdo=0, sub=None):
    head = f"[{index:04X}]" if sub is None else f"[{index:04X}sub{sub:X}]"
    out.append(f"{head}\nParameterName={name}\nObjectType=0x7\nDataType=0x{dt:04X}\n"
               f"AccessType={access}\nDefaultValue={default}\nPDOMapping={pdo}\n")


def array(index, name, dt, access, defaults, pdo=0, names=None):
    n = len(defaults)
    out.append(f"[{index:04X}]\nParameterName={name}\nObjectType=0x8\nSubNumber={n + 1}\n")
    var(index, "Highest sub-index supported", U8, "const", n, sub=0)
    for k, d in enumerate(defaults, start=1):
        var(index, names[k - 1] if names else f"{name} {k}", dt, access, d, pdo, sub=k)


def record(index, name, entries):
    out.append(f"[{index:04X}]\nParameterName={name}\nObjectType=0x9\nSubNumber={len(entries)}\n")
    for sub, (n, dt, acc, d) in enumerate(entries):
        var(index, n, dt, acc, d, sub=sub)


var(0x1000, "Device type", U32, "ro", "0x000F0191")
var(0x1001, "Error register", U8, "ro", 0)
var(0x1017, "Producer heartbeat time", U16, "rw", 0)
record(0x1018, "Identity object", [
    ("Highest sub-index supported", U8, "const", 4), ("Vendor-ID", U32, "ro", "0x00000000"),
    ("Product code", U32, "ro", "0x00000401"), ("Revision number", U32, "ro", "0x00010000"),
    ("Serial number", U32, "ro", "0x00000001")])
maps = {0x1600: ["0x62000108", "0x62000208"], 0x1601: ["0x64110110", "0x64110210"],
        0x1A00: ["0x60000108", "0x60000208"],
        0x1A01: ["0x64010110", "0x64010210", "0x64010310", "0x64010410"]}
for n, (comm, base) in enumerate([(0x1400, 0x200), (0x1401, 0x300)]):
    record(comm, f"RPDO{n + 1} communication parameter", [
        ("Highest sub-index supported", U8, "const", 2), ("COB-ID used by RPDO", U32, "rw", f"$NODEID+0x{base:X}"),
        ("Transmission type", U8, "rw", "0xFF")])
for n, (comm, base) in enumerate([(0x1800, 0x180), (0x1801, 0x280)]):
    record(comm, f"TPDO{n + 1} communication parameter", [
        ("Highest sub-index supported", U8, "const", 5), ("COB-ID used by TPDO", U32, "rw", f"$NODEID+0x{base:X}"),
        ("Transmission type", U8, "rw", "0xFF"), ("Inhibit time", U16, "rw", 0),
        ("Reserved", U8, "rw", 0), ("Event timer", U16, "rw", 0)])
for index, entries in maps.items():
    kind = "RPDO" if index < 0x1A00 else "TPDO"
    n = (index & 0xF) + 1
    out.append(f"[{index:04X}]\nParameterName={kind}{n} mapping parameter\nObjectType=0x9\nSubNumber={9}\n")
    var(index, "Number of mapped objects", U8, "rw", len(entries), sub=0)
    for k in range(1, 9):
        var(index, f"Mapped object {k}", U32, "rw", entries[k - 1] if k <= len(entries) else "0x00000000", sub=k)
array(0x6000, "Read input 8-bit", U8, "ro", [0, 0], pdo=1, names=["Read input 1 to 8", "Read input 9 to 16"])
array(0x6002, "Polarity input 8-bit", U8, "rw", [0, 0])
var(0x6005, "Global interrupt enable digital 8-bit", BOOL, "rw", 1)
array(0x6006, "Interrupt mask any change 8-bit", U8, "rw", ["0xFF", "0xFF"])
array(0x6007, "Interrupt mask low-to-high 8-bit", U8, "rw", [0, 0])
array(0x6008, "Interrupt mask high-to-low 8-bit", U8, "rw", [0, 0])
array(0x6200, "Write output 8-bit", U8, "rw", [0, 0], pdo=1, names=["Write output 1 to 8", "Write output 9 to 16"])
array(0x6202, "Change polarity output 8-bit", U8, "rw", [0, 0])
array(0x6206, "Error mode output 8-bit", U8, "rw", ["0xFF", "0xFF"])
array(0x6207, "Error value output 8-bit", U8, "rw", [0, 0])
array(0x6208, "Filter mask output 8-bit", U8, "rw", ["0xFF", "0xFF"])
array(0x6401, "Read analogue input 16-bit", I16, "ro", [0] * 4, pdo=1)
array(0x6411, "Write analogue output 16-bit", I16, "rw", [0] * 2, pdo=1)
array(0x6421, "Analogue input interrupt trigger selection", U8, "rw", [7] * 4)
array(0x6422, "Analogue input interrupt source", U32, "ro", [0])
var(0x6423, "Analogue input global interrupt enable", BOOL, "rw", 0)
array(0x6424, "Analogue input interrupt upper limit integer", I32, "rw", [0] * 4)
array(0x6425, "Analogue input interrupt lower limit integer", I32, "rw", [0] * 4)
array(0x6426, "Analogue input interrupt delta unsigned", U32, "rw", [0] * 4)
array(0x6443, "Analogue output error mode", U8, "rw", [1] * 2)
array(0x6444, "Analogue output error value integer", I32, "rw", [0] * 2)

idx = sorted({int(s[1:5], 16) for s in out if s[5] == "]"})
head = """[FileInfo]
FileName=io16.eds
FileVersion=1
FileRevision=0
EDSVersion=4.0
Description=drivebus CiA 401 I/O module: 16 DI, 16 DO, 4 AI, 2 AO
CreationTime=12:00PM
CreationDate=11-29-2026
CreatedBy=drivebus (crates/cia401/tools/io_eds.py)
ModificationTime=12:00PM
ModificationDate=11-29-2026
ModifiedBy=drivebus

[DeviceInfo]
VendorName=drivebus
VendorNumber=0x00000000
ProductName=drivebus IO16
ProductNumber=0x00000401
RevisionNumber=0x00010000
OrderCode=IO16
BaudRate_10=1
BaudRate_20=1
BaudRate_50=1
BaudRate_125=1
BaudRate_250=1
BaudRate_500=1
BaudRate_800=1
BaudRate_1000=1
SimpleBootUpMaster=0
SimpleBootUpSlave=1
Granularity=8
DynamicChannelsSupported=0
GroupMessaging=0
NrOfRXPDO=2
NrOfTXPDO=2
LSS_Supported=1

[DummyUsage]
Dummy0001=0
Dummy0002=1
Dummy0003=1
Dummy0004=1
Dummy0005=1
Dummy0006=1
Dummy0007=1

"""
def listing(name, indices):
    s = f"[{name}]\nSupportedObjects={len(indices)}\n"
    return s + "".join(f"{k}=0x{i:04X}\n" for k, i in enumerate(indices, start=1)) + "\n"

mand = [i for i in idx if i in (0x1000, 0x1001, 0x1018)]
opt = [i for i in idx if i not in mand and not 0x2000 <= i < 0x6000]
text = head + listing("MandatoryObjects", mand) + listing("OptionalObjects", opt) + listing("ManufacturerObjects", []) + "\n".join(out)
Path(__file__).resolve().parent.parent.joinpath("eds", "io16.eds").write_text(text)
