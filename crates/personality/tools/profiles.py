"""Per-drive facts and hand decisions for tsv2eds.py. Each override says why
and cites the manual section it rests on."""

U8, U16, U32, I8, I16, I32, VS, DOM = 0x5, 0x6, 0x7, 0x2, 0x3, 0x4, 0x9, 0xF

PROFILES = {
    "kc1": {
        "tsv": "seed000-kc1-objects.tsv",
        "manual": "Kollmorgen KC1 CAN-BUS Communication, edition J 05/2013, firmware 1.9",
        "description": "Kollmorgen KC1 servo drive, CANopen DS301/DS402 (drivebus personality)",
        "vendor": "Kollmorgen", "vendor_number": 0x6A,
        "product": "KC1", "product_number": 0x4D303036, "revision_number": 0x00140000,
        "baud": (125, 250, 500, 1000), "granularity": 8, "nr_rx": 4, "nr_tx": 4, "dummies": (),
        "overrides": {},
    },
    "akd": {
        "tsv": "seed001-akd-objects.tsv",
        "manual": "Kollmorgen AKD CAN-BUS Kommunikation, edition R 09/2016, firmware 1.15",
        "description": "Kollmorgen AKD servo drive, CANopen DS301/DS402 (drivebus personality)",
        "vendor": "Kollmorgen", "vendor_number": 0x6A,
        "product": "AKD", "product_number": 0x4D303036, "revision_number": 0x00140000,
        "baud": (125, 250, 500, 1000), "granularity": 8, "nr_rx": 4, "nr_tx": 4, "dummies": (),
        "overrides": {},
    },
    "ipos": {
        "tsv": "seed002-ipos-objects.tsv",
        "manual": "Technosoft iPOS CoE Programming, P091.064.UM.0524",
        "description": "Technosoft iPOS intelligent drive, CoE (CiA 301/402 over EtherCAT) (drivebus personality)",
        "vendor": "Technosoft S.A.", "vendor_number": 0x1A3,
        "product": "iPOS360x VX-CAT", "product_number": 28002021, "revision_number": 0x41303047,
        "baud": (125, 250, 500, 1000), "granularity": 8, "nr_rx": 4, "nr_tx": 4, "dummies": (2, 3, 4, 5, 6, 7),
        "overrides": {},
    },
    "ssd630": {
        "tsv": "seed003-ssd630-objects.tsv",
        "manual": "SSD Drives CANopen-630 product manual, V0904",
        "description": "SSD Drives 630 series servo drive, CANopen DS301/DS402 (drivebus personality)",
        "vendor": "SSD Drives GmbH", "vendor_number": None,
        "product": "631", "product_number": None, "revision_number": None,
        "baud": (20, 50, 125, 250, 500, 800, 1000), "granularity": 8, "nr_rx": 4, "nr_tx": 4, "dummies": (),
        "overrides": {},
    },
    "dds6": {
        "tsv": "seed004-dds6-objects.tsv",
        "manual": "LAM Technologies DDS6 CANopen DS301/DS402 user manual, HW 1.00 / FW 0.22",
        "description": "LAM Technologies DDS6 vector-controlled stepper drive, CANopen DS301/DS402 (drivebus personality)",
        "vendor": "LAM Technologies", "vendor_number": 0x30C,
        "product": "DDS6244", "product_number": 0x00624400, "revision_number": None,
        "baud": (10, 20, 50, 125, 250, 500, 1000), "granularity": 8, "nr_rx": 4, "nr_tx": 4, "dummies": (),
        "overrides": {},
    },
}


def ov(**kw):
    return kw


KC1_AKD_COMMON = {
    (0x1000, 0): ov(default="0x00020192", why="default: the table gives none but the value the drive reads (0x00020192) is written", sec="KC1 7.2.1.1 / AKD 6.2.1.1"),
    (0x1008, 0): ov(default="M006", why="default: device name is 4 ASCII chars 'Yzzz' (voltage class + current); the manual's own example 'M006' written", sec="KC1 7.2.1.7, 7.2.1.17 / AKD 6.2.1.7, 6.2.1.18"),
    (0x1018, 2): ov(default="0x4D303036", why="default: product code is 4 ASCII chars, e.g. 'M006'; byte order not stated, 'M' in the most significant byte chosen (reads as 4D 30 30 36)", sec="KC1 7.2.1.17 / AKD 6.2.1.18"),
    (0x1018, 3): ov(default="0x00140000", why="default: revision high word = CANopen version, the manual's example 0x00140000 (version 0.20) written", sec="KC1 7.2.1.17 / AKD 6.2.1.18"),
    (0x100E, 0): ov(name="COB-ID node guarding", access="ro", why="object only listed as '(100E)' in the COB-ID table; kept read-only with 700h+node (pre-v4 DS301 object, our NMT service does not use it)", sec="KC1 6.2 / AKD 5.2"),
    (0x2100, 0): ov(name="Dummy mapping placeholder", type=U32, access="rw", pdo=True, why="referenced only as the 4-byte dummy of the shared-RPDO example (mapping 21000020h); UNSIGNED32 rw RPDO-mappable written", sec="KC1 8.2.2.1 / AKD 7.2.2.1"),
    (0x35D9, 0): ov(name="MT.CNTL (as referenced by FBUS.PARAM05 bit 6)", type=U32, access="rw", why="referenced only; the appendix lists MT.CNTL elsewhere (35AFh/35B9h); UNSIGNED32 rw written so the reference resolves", sec="KC1 5.4 / AKD 3.4"),
    (0x6099, 1): ov(default="36000", why="default 'equivalent of 60 rpm': 60 rpm = 1 rev/s = 36000 velocity units (36000 position units per revolution, velocity units = units/s, example 9)", sec="KC1 7.10.2.3 / AKD 6.10.2.3"),
    # Power-on values the tables leave empty: the EDS states what the drive
    # starts with (src/kc1/mod.rs; DriveConfig::servo on the small servo).
    (0x606D, 0): ov(default="20000", why="no default given; drivebus's working value 20000 velocity units (0.56 rev/s) written", sec="KC1 8.1.4 / AKD 7.1.5"),
    (0x606E, 0): ov(default="10", why="no default given; drivebus's working value 10 ms written", sec="KC1 8.1.4 / AKD 7.1.5"),
    (0x6092, 1): ov(default="36000", why="default: table gives 1 (the DS402 generic default) but the manual's own defaults need a sub-revolution unit: 6099h:1 'equivalent of 60 rpm' with :2 '1/8 (AKD: 50 %) of sub 1' and the 65535 speed limit example 9 shows are integers only at 36000 units per revolution (example 9: 8CA0h = one revolution); 36000 (feed per motor revolution) written", sec="KC1 7.5.3.3, 7.10.2.3, example 9 / AKD 6.5.3.3, 6.10.2.3"),
    (0x6072, 0): ov(default="4000", why="no default given; drivebus's working value 4000 per mille (the motor's peak / rated current) written", sec="KC1 8.1.4 / AKD 7.1.5"),
}

for _i, _n in ((0x3501, "DRV.ACC"), (0x3522, "DRV.DEC"), (0x3502, "HOME.ACC")):
    KC1_AKD_COMMON[(_i, 0)] = ov(default="36000000", why=f"no default given; {_n} is the drive's own ramp that 6083h/6084h/609Ah = 0 select, drivebus's working value 36000000 units/s² (1000 rev/s² at 36000 units per revolution) written", sec="KC1 7.11.2.4, 7.11.2.5, 7.10.2.4, 8.1.3 / AKD 6.11.2.4, 6.11.2.5, 6.10.2.4, 7.1.4")
KC1_AKD_COMMON[(0x6063, 0)] = ov(default="0", why="default: the table prints 2^20 ('as printed'), the increments of one turn (PRBASE 20, §7.8.2.1), not a position; the drive starts at 0 increments (what the running drive reads)", sec="KC1 7.8.2.1 / AKD 6.8.2.1")

PROFILES["kc1"]["overrides"] = dict(KC1_AKD_COMMON)
PROFILES["kc1"]["overrides"].update({
    (0x60C2, 2): ov(type=I8, default="-3", why="type/default: table gives INTEGER16 default 1 (as printed); the §8.2 example writes FDh (-3) with a 1-byte SDO and CiA 402 defines INTEGER8: INTEGER8, default -3 (1 ms) chosen", sec="7.9.2.3; 8.1.4"),
    (0x6099, 2): ov(default="4500", why="default '1/8 of sub 1': 36000 / 8 = 4500 written", sec="7.10.2.3"),
    (0x35B9, 1): ov(type=I32, why="type not given; INTEGER32 as the AKD appendix lists MT.CNTL (35B9h)", sec="7.11.2.1"),
})
PROFILES["akd"]["overrides"] = dict(KC1_AKD_COMMON)
PROFILES["akd"]["overrides"].update({
    (0x6099, 2): ov(default="18000", why="default '50 % of sub 1': 36000 / 2 = 18000 written", sec="6.10.2.3"),
    (0x6087, 0): ov(default="10000", why="no default given ('-'); drivebus's working value 10000 per mille/s written (above the ~2385 minimum)", sec="6.7.2.6; 7.1.5"),
    (0x60C1, 0): ov(default="3", why="sub 0 = 1 in the body (linear interpolation only) but the appendix of this edition lists subs 2 and 3 (the PVT record removed in edition M): the firmware's dictionary still has them, so they are kept as values the linear interpolation ignores, and sub 0 = 3 is the highest sub-index", sec="6.9.2.2; 7.1.5; 9 (edition M)"),
})
PROFILES["ipos"]["overrides"] = {
    (0x1000, 0): ov(default="0x00060192", why="default: table prints '60192' meaning hex; 0x00060192 written", sec="4.8.1"),
    (0x1018, 0): ov(default="4", why="sub 0: printed default 1 but subs 1..4 are described (range 1..4); 4 written", sec="4.8.6"),
    (0x1018, 2): ov(default="28002021", why="product code 'product dependent'; the decimal code of the iPOS360x VX-CAT example written", sec="1.5.4.6; 4.8.6"),
    (0x1018, 3): ov(default="0x41303047", why="revision: table default 0x30313030 ('0100') overridden by the firmware ID in ASCII, 'A00G' = 0x41303047 (the FA00G firmware the twin emulates), so 1018h:03, the SII and the ESI revision agree (the ESI revision is the firmware ID, 1.5.4.6)", sec="1.5.4.6; 4.8.6"),
    (0x1009, 0): ov(access="const", why="listed only in Appendix A without attributes; const like 1008h/100Ah", sec="Appendix A"),
    (0x1802, 1): ov(name="COB-ID used by TPDO3", access="rw", default="$NODEID+0x80000380", why="mentioned only ('disabled by setting bit 31'); CANopen-style COB-ID with bit 31 set written", sec="2.3.7"),
    (0x1803, 1): ov(name="COB-ID used by TPDO4", access="rw", default="$NODEID+0x80000480", why="mentioned only ('disabled by setting bit 31'); CANopen-style COB-ID with bit 31 set written", sec="2.3.8"),
}
PROFILES["ipos"]["overrides"].update({
    (i, 0): ov(default=v, why=f"no default given ('-'); drivebus's working value {v}: {what}", sec=sec)
    for i, v, what, sec in (
        (0x6065, "2000", "one motor revolution (2000 increments)", "7.2.10"),
        (0x6066, "50", "50 control loop periods (ms)", "7.2.11"),
        (0x6067, "10", "10 increments", "7.2.12"),
        (0x606D, "0xFFFF", "the widest window", "10.2.4"),
        (0x606E, "10", "10 ms", "10.2.5"),
        (0x606F, "0xFFFF", "the highest threshold", "10.2.6"),
        (0x6081, "0x00210000", "33.0 IU (990 rpm at 2000 increments per revolution)", "7.2.2"),
        (0x6083, "0x00010000", "1.0 IU", "7.2.3"),
        (0x6085, "0x00040000", "4.0 IU", "7.2.4"),
    )
})
# The iPOS on CAN (drivebus serves the CoE drive on CAN too): the CiA 301
# objects the CAN services answer with, which the CoE manual has no reason
# to list (EtherCAT has no COB-IDs): 1005h/1006h (SYNC), 1014h (EMCY), the
# PDO communication records 1400h-1403h/1800h-1803h. Valid exactly where
# the PDO is assigned in 1C12h/1C13h (§2.3.7, §2.3.8: "disabled by setting
# bit 31"), so the CAN and the EtherCAT view of the defaults agree.
CAN_ONLY = "CAN only (the CoE manual lists no COB-IDs)"
for (i, name, default) in ((0x1005, "COB-ID SYNC message", "0x00000080"),
                           (0x1006, "Communication cycle period", "0"),
                           (0x1014, "COB-ID EMCY", "$NODEID+0x80")):
    PROFILES["ipos"]["overrides"][(i, 0)] = ov(name=name, type=U32, access="rw", default=default,
                                               why=f"{name}: the object the CAN service answers with; CiA 301 type and default", sec=CAN_ONLY)
for n, (valid, base) in enumerate(((True, 0x200), (False, 0x300), (False, 0x400), (False, 0x500))):
    i = 0x1400 + n
    cob = f"$NODEID+0x{base:X}" if valid else f"$NODEID+0x{0x80000000 | base:X}"
    o = PROFILES["ipos"]["overrides"]
    o[(i, 0)] = ov(obj_name=f"RPDO{n + 1} communication parameter", name="Highest sub-index supported", type=U8,
                   access="ro", default="5", why=f"RPDO{n + 1} communication record: valid = assigned in 1C12h ({'yes' if valid else 'no'}, §2.3.10)", sec=CAN_ONLY)
    o[(i, 1)] = ov(name=f"COB-ID used by RPDO{n + 1}", type=U32, access="rw", default=cob, sec=CAN_ONLY)
    o[(i, 2)] = ov(name="Transmission type", type=U8, access="rw", default="0xFF", sec=CAN_ONLY)
    o[(i, 3)] = ov(name="Inhibit time (not used)", type=U16, access="rw", default="0", sec=CAN_ONLY)
    o[(i, 5)] = ov(name="Event timer (deadline)", type=U16, access="rw", default="0", sec=CAN_ONLY)
for n, (valid, base) in enumerate(((True, 0x180), (True, 0x280), (False, 0x380), (False, 0x480))):
    i = 0x1800 + n
    cob = f"$NODEID+0x{base:X}" if valid else f"$NODEID+0x{0x80000000 | base:X}"
    o = PROFILES["ipos"]["overrides"]
    o[(i, 0)] = ov(obj_name=f"TPDO{n + 1} communication parameter", name="Highest sub-index supported", type=U8,
                   access="ro", default="6", why=f"TPDO{n + 1} communication record: valid = assigned in 1C13h ({'yes' if valid else 'no'}, §2.3.11)", sec=CAN_ONLY)
    o[(i, 1)] = ov(name=f"COB-ID used by TPDO{n + 1}", type=U32, access="rw", default=cob, sec=CAN_ONLY)
    o[(i, 2)] = ov(name="Transmission type", type=U8, access="rw", default="0xFF", sec=CAN_ONLY)
    o[(i, 3)] = ov(name="Inhibit time", type=U16, access="rw", default="0", sec=CAN_ONLY)
    o[(i, 5)] = ov(name="Event timer", type=U16, access="rw", default="0", sec=CAN_ONLY)
    o[(i, 6)] = ov(name="SYNC start value", type=U8, access="rw", default="0", low="0", high="0xF0", sec=CAN_ONLY)
# §2.4: "sub-indexes (1-8)": every mapping record has 8 entries; the table
# lists only the default ones.
for i in (0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03):
    for k in range(1, 9):
        PROFILES["ipos"]["overrides"].setdefault((i, k), ov(name=f"Mapped object {k}", type=U32, access="rw", default="0x00000000",
                                                        if_missing=True, sec="2.4"))
    PROFILES["ipos"]["overrides"][(i, 8)]["why"] = "entries up to sub 8 added (§2.4: 'sub-indexes (1-8)'; the table lists the default ones)"
# The EtherCAT side (ETG.1000.6 sync managers), as the manual means it.
o = PROFILES["ipos"]["overrides"]
o[(0x2103, 0)] = ov(default="2000", why="Number of encoder counts per revolution: no default given; the emulated motor's 500-line encoder, 2000 counts (the examples' motor, 6.4, 7.3)", sec="4.9.16")
o[(0x2006, 0)] = ov(low=None, high=None, why="Call TML function: no limits written; the range 1..10 is the drive's own check, answered 0609 0030h (not 0609 0031h/0032h) as 18.2.2.1 says", sec="18.2.2.1")
o[(0x201A, 0)] = ov(default="0x9E00", why="CAM table run address: the table's default 9E00h is hexadecimal (a RAM address), not 9 x 10^0", sec="12.2.2")
o[(0x1C00, 4)] = ov(default="4", why="SM3 communication type: printed 3, but the value range of the same entry gives 4 = process data input, and ETG.1000.6 has SM3 inputs = 4", sec="2.3.9")
for i, first, n_pdo, kind in ((0x1C12, 0x1600, 4, "RxPDO"), (0x1C13, 0x1A00, 4, "TxPDO")):
    o[(i, 0)] = ov(access="rw", why=f"{i:04X}h:00: printed RO, but the text and every example (§2.4, E10, E11) write 0, the entries, then the count (in pre-operational)", sec="2.3.10; 2.3.11; 2.4")
    for k in range(1, n_pdo + 1):
        o.setdefault((i, k), ov(name=f"PDO Mapping object index of assigned {kind} ({k})", type=U16, access="rw", default="0x0000",
                                if_missing=True, sec="2.3.10; 2.3.11"))
    o[(i, n_pdo)]["why"] = f"{i:04X}h: entries up to sub {n_pdo}, one per {kind} (range 1-4; E10/E11 write sub {n_pdo}); the table lists the default ones"

# 60C1h X1/X2 "interpolated mode dependent (32-bit)": linear ip puts a
# signed target position in X1; CiA 402-2 types 60C1h INTEGER32.
for k in (1, 2):
    PROFILES["ipos"]["overrides"][(0x60C1, k)] = ov(type=I32, why="type: 'interpolated mode dependent (32-bit)'; X1 carries a signed position in linear ip; INTEGER32 (CiA 402-2) written", sec="9.2.2")

PROFILES["ssd630"]["overrides"] = {
    (0x1008, 0): ov(default="631_402", why="device name of a 631 from the segmented-upload example", sec="14.7"),
    (0x1010, 1): ov(default="1", why="read value bit 0 = 1 (saves on command)", sec="7; 11"),
    (0x1011, 1): ov(default="1", why="read value bit 0 = 1 (restores on command); the 'load' signature bytes are misprinted (73h 61h 61h 64h), 0x64616F6C is what the node accepts", sec="7; 11"),
    (0x60C2, 2): ov(type=I8, default="-3", why="ip time index: table gives UNSIGNED8; CiA 402 defines INTEGER8 (negative exponents); INTEGER8 chosen. No default given; drivebus's working value -3 (with sub 1 = 1: 1 ms) written", sec="12"),
    (0x6502, 0): ov(default="0x00000067", why="value not given; derived from the evidenced modes pp, vl (6042h-6048h), pv, hm, ip = bits 0,1,2,5,6", sec="4; 12; 14"),
    (0x100B, 0): ov(default="$NODEID", why="node-ID: the drive reads its own node-ID (§14.6 reads 4 on node 4; the table's 1 is the lowest), $NODEID written", sec="4; 11; 14.6"),
    (0x6080, 1): ov(default="3000", why="no default given; the drive's power-on limit, 3000 min^-1 (= 607Fh), for both directions", sec="12"),
    (0x6080, 2): ov(default="3000", why="no default given; the drive's power-on limit, 3000 min^-1 (= 607Fh), for both directions", sec="12"),
}
# Power-on values the manual does not give (§4 and §12 list the objects
# without defaults): the EDS states what the drive starts with
# (src/ssd630/mod.rs adjust_drive_config; velocities in min^-1,
# accelerations in min^-1/s, positions in increments, 4096 per revolution).
for (i, s_), v, what in (
        ((0x6046, 2), "6000", "vl max amount = the motor's maximum speed in min^-1"),
        ((0x6048, 1), "6000", "vl acceleration delta speed (min^-1)"),
        ((0x6048, 2), "1", "vl acceleration delta time (s): 6000 min^-1 per second"),
        ((0x605A, 0), "2", "quick stop option code 2 (stop on the quick stop ramp, then switch on disabled; CiA 402-2)"),
        ((0x6065, 0), "4096", "following error window = one motor revolution (increments)"),
        ((0x6067, 0), "10", "position window (increments)"),
        ((0x607F, 0), "3000", "max profile velocity (min^-1)"),
        ((0x6081, 0), "1000", "profile velocity (min^-1), the value of the §14.9 example"),
        ((0x6083, 0), "10000", "profile acceleration (min^-1/s)"),
        ((0x6084, 0), "10000", "profile deceleration (min^-1/s)"),
        ((0x6085, 0), "30000", "quick stop deceleration (min^-1/s)"),
        ((0x6099, 1), "250", "homing speed 1 (min^-1) = 1/4 of 6081h"),
        ((0x6099, 2), "25", "homing speed 2 (min^-1) = 1/40 of 6081h (unused by the 630's own methods)"),
        ((0x60C2, 1), "1", "ip time units: 1 x 10^-3 s"),
        ((0x60C3, 2), "1", "ip sync every 1 event"),
        ((0x60FE, 2), "0xFFFF0000", "digital outputs bit mask: the manufacturer outputs (bits 16-31) may be set"),
):
    PROFILES["ssd630"]["overrides"][(i, s_)] = ov(default=v, why=f"no default given; drivebus's working value {v}: {what}", sec="4; 12")
# 6049h: printed as a second "6048h" in §4, no own entry in §12, which says
# deceleration = acceleration in velocity mode: a record like 6048h.
PROFILES["ssd630"]["overrides"].update({
    (0x6049, 0): ov(name="number of entries", type=U8, access="ro", default="2", code=9, obj_name="vl velocity deceleration",
                    why="§4 prints 6049h as a second '6048h' (VAR); §12: deceleration = acceleration in velocity mode, so a record like 6048h (sub 0 = 2)", sec="4; 12"),
    (0x6049, 1): ov(name="delta speed", type=U32, access="rw", default="6000", why="no default given; drivebus's working value 6000 min^-1 (as 6048h:1)", sec="4; 12"),
    (0x6049, 2): ov(name="delta time", type=U16, access="rw", default="1", why="no default given; drivebus's working value 1 s (as 6048h:2)", sec="4; 12"),
})
for i in range(0x2014, 0x2018):
    for s in (1, 2):
        PROFILES["ssd630"]["overrides"][(i, s)] = ov(default="0xFFFFFFFF", why="default 'all bits event-driven' = all mask bits set", sec="4; 11")
PROFILES["dds6"]["overrides"] = {
    (0x1008, 0): ov(default="DDS6244", why="device name: §6.3.5 gives no value; the model whose product code 1018h:02 reports (00624400h = DDS6244, §6.3.16 table) written", sec="6.3.5; 6.3.16"),
    (0x1016, 0): ov(default="4", why="sub 0 printed 02h but four consumer entries are described; 4 written", sec="6.3.14"),
    (0x1018, 2): ov(default="0x00624400", why="product code is per model; DDS6244 (digital + analog I/O + encoder, all modes incl. torque) chosen", sec="6.3.16"),
    (0x2310, 0): ov(type=U8, access="const", why="type/access lost in extraction; UNSIGNED8 const like the other sub 0s", sec="6.4.1"),
    (0x2310, 1): ov(type=U32, access="rw", why="type lost; LAM motor codes such as 330200101 need UNSIGNED32", sec="6.4.1; 4.1.1.1"),
    (0x2310, 3): ov(type=U16, access="rw", why="type lost; UNSIGNED16 like the neighbouring motor data", sec="6.4.1; 4.1.1.2"),
    (0x3210, 1): ov(access="ro", pdo=True, why="access lost; an input image is read-only (TPDO)", sec="6.4.14"),
    (0x3230, 1): ov(access="rw", pdo=True, why="access lost; output image written by the master", sec="6.4.15"),
    (0x3230, 2): ov(access="rw", why="access lost; set-output command written by the master", sec="6.4.15"),
    (0x3260, 1): ov(type=U16, access="rw", why="type/unit lost; UNSIGNED16 rw assumed", sec="6.4.18"),
    (0x3261, 1): ov(type=U16, access="rw", why="type/unit lost; UNSIGNED16 rw assumed", sec="6.4.19"),
    (0x3450, 1): ov(type=U16, access="rw", why="type lost; UNSIGNED16 rw (a time-out) assumed", sec="6.4.23"),
    (0x3470, 1): ov(access="rw", why="access lost; configuration bits, rw", sec="6.4.24"),
    (0x605E, 0): ov(type=I16, access="rw", default="2", why="only in the IDE screenshot (value 2); CiA 402 type INTEGER16", sec="6.1"),
}
for i in (0x1010, 0x1011):
    for s in (1, 2, 3, 4):
        PROFILES["dds6"]["overrides"][(i, s)] = ov(default="1", why="no read value given; 1 (= acts on command, CiA 301 §7.5.2.13/14) written", sec="6.3.10; 6.3.11")
for i in (0x3210, 0x3230, 0x3260, 0x3261, 0x3450, 0x3470):
    PROFILES["dds6"]["overrides"][(i, 0)] = ov(type=U8, access="const", why="sub 0 type/access lost; UNSIGNED8 const", sec="6.4")
PROFILES["dds6"]["overrides"][(0x2360, 0)] = ov(default="5", why="sub 0 printed 06h but five sub-indices are described; 5 written", sec="6.4.3")
PROFILES["dds6"]["overrides"][(0x2810, 0)] = ov(default="13", why="sub 0 printed 08h but sub-indices up to 0Dh are described; 13 written", sec="6.4.8")
PROFILES["dds6"]["overrides"][(0x6061, 0)] = ov(default="1", why="no default given; the display of the power-on mode 6060h = 1 (pp, §6.5.4)", sec="6.5.4; 6.5.5")
PROFILES["dds6"]["overrides"][(0x6087, 0)] = ov(default="10000", why="no default given; 10000 (1000 %/s) written, a 0 would never ramp", sec="6.5.29")
