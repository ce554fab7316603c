#!/usr/bin/env python3
"""Convert a manual's object table (shared/reference/seed00N-*-objects.tsv) to
a CiA 306 EDS, once. The committed .eds files are the product; this script
records how they were first produced and which choices it made.

    python3 tools/tsv2eds.py            # writes eds/<name>.eds and tools/choices-<name>.md

Per-drive facts the table does not hold (identity, baud rates, PDO counts,
dummy usage, granularity) and every hand decision live in tools/profiles.py.
Each decision is printed to the choices file with the manual section it
rests on; docs/personalities.md summarises them.
"""

import csv
import os
import re
import sys

sys.path.insert(0, os.path.dirname(__file__))
import profiles  # noqa: E402

REF = "/work/shared/reference"
HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "eds")

# CiA 301 data type indices.
U8, U16, U32, U64, U48 = 0x5, 0x6, 0x7, 0x1B, 0x19
I8, I16, I32, I64 = 0x2, 0x3, 0x4, 0x15
VS, OS, DOM, BOOL, R32 = 0x9, 0xA, 0xF, 0x1, 0x8

TYPE_WORDS = [
    (r"UNSIGNED8|USINT8|\bu8\b", U8),
    (r"UNSIGNED16|UINT16|\bu16\b|Unsigned 16", U16),
    (r"UNSIGNED32|ULONG32|\bu32\b", U32),
    (r"UNSIGNED48", U48),
    (r"UNSIGNED64", U64),
    (r"INTEGER8|\bi8\b", I8),
    (r"INTEGER16|\bi16\b", I16),
    (r"INTEGER32|FIXED32|\bi32\b", I32),
    (r"INTEGER64", I64),
    (r"VISIBLE_STRING|\bstr\b", VS),
    (r"OCTET_STRING", OS),
    (r"DOMAIN", DOM),
    (r"BOOLEAN", BOOL),
    (r"REAL32", R32),
]
TYPE_NAME = {U8: "UNSIGNED8", U16: "UNSIGNED16", U32: "UNSIGNED32", U48: "UNSIGNED48", U64: "UNSIGNED64",
             I8: "INTEGER8", I16: "INTEGER16", I32: "INTEGER32", I64: "INTEGER64", VS: "VISIBLE_STRING",
             OS: "OCTET_STRING", DOM: "DOMAIN", BOOL: "BOOLEAN", R32: "REAL32"}
RANGE = {U8: (0, 0xFF), U16: (0, 0xFFFF), U32: (0, 0xFFFFFFFF), U48: (0, 2**48 - 1), U64: (0, 2**64 - 1),
         I8: (-128, 127), I16: (-32768, 32767), I32: (-2**31, 2**31 - 1), I64: (-2**63, 2**63 - 1), BOOL: (0, 1)}

# CiA 301 / CiA 402 types our checker enforces (crates/eds/src/check.rs).
STANDARD = {
    (0x1000, 0): U32, (0x1001, 0): U8, (0x1002, 0): U32, (0x1005, 0): U32, (0x1006, 0): U32, (0x1007, 0): U32,
    (0x1008, 0): VS, (0x1009, 0): VS, (0x100A, 0): VS, (0x100C, 0): U16, (0x100D, 0): U8, (0x1012, 0): U32,
    (0x1014, 0): U32, (0x1015, 0): U16, (0x1017, 0): U16, (0x1019, 0): U8,
    (0x6040, 0): U16, (0x6041, 0): U16, (0x6060, 0): I8, (0x6061, 0): I8, (0x6064, 0): I32, (0x606C, 0): I32,
    (0x6071, 0): I16, (0x6077, 0): I16, (0x607A, 0): I32, (0x6098, 0): I8, (0x60FF, 0): I32, (0x6502, 0): U32,
}
STANDARD_ALL_SUBS = {0x1003: U32, 0x1010: U32, 0x1011: U32, 0x1016: U32, 0x1018: U32, 0x1029: U8}


def standard_type(index, sub):
    if index in STANDARD_ALL_SUBS:
        return U8 if sub == 0 else STANDARD_ALL_SUBS[index]
    if (index, sub) in STANDARD:
        return STANDARD[(index, sub)]
    if 0x1400 <= index <= 0x15FF:
        return {0: U8, 1: U32, 2: U8, 3: U16, 5: U16}.get(sub)
    if 0x1800 <= index <= 0x19FF:
        return {0: U8, 1: U32, 2: U8, 3: U16, 4: U8, 5: U16, 6: U8}.get(sub)
    if 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF:
        return U8 if sub == 0 else U32
    if 0x1200 <= index <= 0x12FF:
        return {0: U8, 1: U32, 2: U32, 3: U8}.get(sub)
    return None


def preferred_access(index, sub):
    """Where a manual contradicts itself on access, the CiA 301/402 reading."""
    if 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF:
        return "rw"  # mapping sub 0 must be writable to remap (CiA 301 §7.5.2.36)
    if 0x1800 <= index <= 0x19FF and sub == 4:
        return "rw"  # reserved/compatibility entry, writable in CiA 301
    return {
        0x1014: "rw", 0x100C: "rw", 0x100D: "rw", 0x6040: "rw", 0x6041: "ro", 0x6063: "ro",
        0x6064: "ro", 0x60B2: "rw", 0x60B9: "ro", 0x60BA: "ro", 0x60BB: "ro", 0x60BC: "ro", 0x60BD: "ro",
    }.get(index)


def q(text):
    """A short quote of a table cell for the decision log (facts, not prose)."""
    t = re.sub(r"\s+", " ", text.strip())
    return repr(t if len(t) <= 40 else t[:37] + "...")


class Log:
    def __init__(self):
        self.lines = []

    def __call__(self, index, sub, msg, sections):
        where = f"{index:04X}h" + (f" sub {sub}" if sub is not None else "")
        self.lines.append(f"| {where} | {msg} | {sections} |")


def parse_type(text):
    """(type, is_container, alternatives_mentioned)."""
    t = text.strip()
    container = bool(re.match(r"(ARRAY|RECORD|STRUCT)", t))
    best = None
    for pat, dt in TYPE_WORDS:
        m = re.search(pat, t)
        if m and (best is None or m.start() < best[0]):
            best = (m.start(), dt)
    n_found = sum(1 for pat, _ in TYPE_WORDS if re.search(pat, t))
    return (best[1] if best else None), container, n_found > 1


def parse_access(text):
    t = text.strip().lower()
    m = re.search(r"\b(rww|rwr|rw|ro|wo|const)\b", t)
    acc = m.group(1) if m else None
    contradicts = "/" in t and len(set(re.findall(r"\b(rww|rwr|rw|ro|wo|const|not writable)\b", t))) > 1
    return acc, contradicts


def parse_pdo(text):
    t = text.strip().lower()
    if not t or t in ("no", "-", "—"):
        return False
    return bool(re.match(r"(yes|possible|rpdo|tpdo|ja|\(ch)", t))


NUM = r"-?(?:0x[0-9A-Fa-f]+|[0-9A-Fa-f]+h\b|\d+)"


def num(tok):
    tok = tok.strip()
    neg = tok.startswith("-")
    if neg:
        tok = tok[1:]
    if tok.lower().startswith("0x"):
        v = int(tok, 16)
    elif tok.lower().endswith("h"):
        v = int(tok[:-1], 16)
    else:
        v = int(tok)
    return -v if neg else v


def parse_default(text, dt, mapping=False):
    """Returns an EDS value text or None."""
    t = text.strip()
    if mapping:
        m = re.match(r"([0-9A-Fa-f]{8})\b", t)
        if m:
            return f"0x{int(m.group(1), 16):08X}"
    if not t:
        return None
    low = t.lower()
    if re.match(r"(no|none|—|-|n/a|not given|read:)(\b|$|;| )", low) and not re.match(r"-\d", t):
        return None
    if re.search(r"node[- ]?id|\+ ?id\b|\bid\b", low):
        m = re.search(r"(0x[0-9A-Fa-f]+|[0-9A-Fa-f]+h)\b", t)
        if m:
            base = num(m.group(1))
            if re.search(r"disabled|bit ?31 ?= ?1", low) and base < 0x80000000:
                base |= 0x80000000
            return f"$NODEID+0x{base:X}"
        return None
    if dt == VS:
        m = re.search(r'"([^"]*)"', t)
        if m:
            return m.group(1)
        m = re.match(r"([A-Za-z0-9_.]+)\s*$", t)
        return m.group(1) if m else None
    m = re.match(r"2\^(\d+)", t)
    if m:
        return str(2 ** int(m.group(1)))
    m8 = re.match(r"([0-9A-Fa-f]{8})\b", t)
    if m8 and dt in (U32, I32):
        v = int(m8.group(1), 16)
        if dt == I32 and v >= 2 ** 31:
            v -= 2 ** 32
        return f"0x{v:08X}" if dt == U32 else str(v)
    m = re.match(r"\+?(" + NUM + ")", t)
    if not m or re.match(r"\s*(/|%|\*)", t[m.end():]):
        return None
    v = num(m.group(1))
    hexed = m.group(1).lower().startswith("0x") or m.group(1).lower().endswith("h")
    if hexed and dt in (I8, I16, I32, I64):
        bits = {I8: 8, I16: 16, I32: 32, I64: 64}[dt]
        if v >= 2 ** (bits - 1) and v < 2 ** bits:
            v -= 2 ** bits
            hexed = False
    if dt in RANGE:
        lo, hi = RANGE[dt]
        if not lo <= v <= hi:
            return None
    if hexed:
        width = {U8: 2, U16: 4, U32: 8}.get(dt, 0)
        return f"0x{v:0{width}X}" if v >= 0 else str(v)
    return str(v)


def parse_limits(text, dt):
    if dt not in RANGE:
        return None
    m = re.match(rf"\s*({NUM})\s*(?:to|\.\.\.?|…)\s*\+?({NUM})\s*(?:$|[;,( ])", text)
    if not m:
        m = re.match(rf"\s*min\.? ({NUM}),? max\.? ({NUM})\s*(?:$|[;,( ])", text)
    if not m or re.match(r"\s*,\s*-?\d", text[m.end(2):]):
        return None
    lo, hi = num(m.group(1)), num(m.group(2))
    rlo, rhi = RANGE[dt]
    if not (rlo <= lo <= rhi and rlo <= hi <= rhi and lo <= hi):
        return None
    return lo, hi


def value_of(text, dt):
    if text is None:
        return None
    t = text.replace("$NODEID+", "")
    try:
        return num(t)
    except ValueError:
        return None


def clean_name(name):
    n = name.strip()
    n = re.sub(r"\s*\((?:[^()]*§[^()]*|[^()]*as printed[^()]*|[^()]*printed[^()]*|[^()]*manual sub[^()]*|[^()]*not in the[^()]*|[^()]*lost[^()]*)\)", "", n)
    n = n.split(";")[0]
    n = re.sub(r"\s+", " ", n).strip().rstrip(".").strip()
    while n.count("(") > n.count(")"):
        n = n[: n.rfind("(")].rstrip()
    if len(n) > 80:
        n = n[:77].rstrip() + "..."
    return n or "Reserved"


def split_name(name):
    for sep in (" / ", ": "):
        if sep in name:
            a, b = name.split(sep, 1)
            return a, b
    return None, name


def expand_ranges(rows):
    out = []
    for r in rows:
        idx = r[0]
        m = re.fullmatch(r"([0-9A-Fa-f]{4})-([0-9A-Fa-f]{4})", idx)
        if not m:
            out.append(r)
            continue
        a, b = int(m.group(1), 16), int(m.group(2), 16)
        for i in range(a, b + 1):
            rr = list(r)
            rr[0] = f"{i:04X}"
            k = i - a
            if a == 0x4100:
                rr[2] = f"Variable {k}"
            elif a == 0x5000:
                rr[2] = f"BIAS program line {k // 2} part {k % 2 + 1}"
            elif a == 0x3000:
                rr[2] = f"Profile memory point {k // 2} " + ("position" if k % 2 == 0 else "IP factor")
            elif a == 0x5C10 and r[1] == "00":
                rr[2] = f"CAM profile {k} definitions: number of entries"
            out.append(rr)
    return out


class Obj:
    def __init__(self, index):
        self.index = index
        self.name = None
        self.code = None  # 7 VAR, 8 ARRAY, 9 RECORD
        self.elem_type = None
        self.subs = {}  # sub -> dict


def build(name, cfg):
    log = Log()
    path = f"{REF}/{cfg['tsv']}"
    rows = [r for r in csv.reader(open(path, encoding="utf-8"), delimiter="\t")][1:]
    rows = expand_ranges(rows)
    objs = {}
    for r in rows:
        r = (r + [""] * 9)[:9]
        idx_t, sub_t, nm, ty, acc, pdo, dflt, rng, sec = r
        if not re.fullmatch(r"[0-9A-Fa-f]{4}", idx_t.strip()):
            log(0, None, f"row skipped: index {idx_t!r}", sec)
            continue
        index = int(idx_t, 16)
        o = objs.setdefault(index, Obj(index))
        dt, container, alt = parse_type(ty)
        if sub_t.strip() == "":
            o.name = clean_name(nm)
            o.code = 9 if ("RECORD" in ty or "STRUCT" in ty) else 8
            o.elem_type = dt
            if "appendix: RECORD" in ty:
                log(index, None, f"object code: table gives {q(ty)}; ARRAY kept (CiA 301 defines an ARRAY)", sec)
                o.code = 8
            continue
        sub = int(sub_t, 16)
        e = {"raw": r, "sec": sec}
        if dt is None:
            dt = o.elem_type
        std = standard_type(index, sub)
        if alt:
            log(index, sub, f"type: table gives {q(ty)}; {TYPE_NAME.get(std or dt)} chosen", sec)
        if std is not None and dt != std:
            if dt is not None and not alt:
                log(index, sub, f"type: table gives {q(ty)}; {TYPE_NAME[std]} (CiA 301/402) chosen", sec)
            dt = std
        if dt is None and ("(bits 0..15)" in ty or ty.strip() == "(16-bit)"):
            dt = U16
            log(index, sub, f"type: table gives {q(ty)}; UNSIGNED16 (a 16-bit field) assumed", sec)
        elif dt is None and "(bits 0..7)" in ty:
            dt = U8
            log(index, sub, f"type: table gives {q(ty)}; UNSIGNED8 (an 8-bit field) assumed", sec)
        if dt is None:
            dt = U8 if sub == 0 and index >= 0x1000 and any(k == index for k in objs) and o.code else U32
            log(index, sub, f"type: table gives {q(ty)}; {TYPE_NAME[dt]} assumed", sec)
        e["type"] = dt
        a, contra = parse_access(acc)
        if a is None:
            a = "ro" if sub == 0 and o.code else "rw"
            log(index, sub, f"access: table gives {q(acc)}; {a} assumed (a sub 0 of an ARRAY/RECORD: ro)", sec)
            e["access_assumed"] = True
        elif contra:
            pref = preferred_access(index, sub)
            if pref:
                a = pref
                log(index, sub, f"access: table gives {q(acc)}; {a} chosen (CiA 301/402 meaning of the object)", sec)
            else:
                log(index, sub, f"access: table gives {q(acc)}; {a} chosen (first source)", sec)
        e["access"] = a
        e["pdo"] = parse_pdo(pdo)
        is_map = (0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF) and sub > 0
        e["default"] = parse_default(dflt, dt, is_map)
        if dflt.strip() and e["default"] is None and dflt.strip() not in ("-", "—") and not re.match(r"(no|none)\b", dflt.strip().lower()):
            log(index, sub, f"default: {q(dflt)} is not a value; none written", sec)
        lim = parse_limits(rng, dt)
        e["low"] = e["high"] = None
        if lim:
            v = value_of(e["default"], dt)
            if v is None and e["default"] is None and not lim[0] <= 0 <= lim[1]:
                e["default"] = str(lim[0]) if lim[0] < 10 else f"0x{lim[0]:X}"
                log(index, sub, f"default: none given, range {lim[0]}..{lim[1]}; the low limit written as default", sec)
                v = lim[0]
            if v is not None and not lim[0] <= v <= lim[1]:
                log(index, sub, f"limits: the range column's first span ({lim[0]}..{lim[1]}) excludes the default {e['default']}; no limits written", sec)
            else:
                e["low"], e["high"] = (str(x) if x < 0 or x < 10 else f"0x{x:X}" for x in lim)
        e["name"] = nm
        o.subs[sub] = e

    # Hand decisions and objects the table lacks.
    for (index, sub), ov in cfg.get("overrides", {}).items():
        ov = dict(ov)
        o = objs.setdefault(index, Obj(index))
        if ov.pop("if_missing", False) and sub in o.subs:
            continue
        why = ov.pop("why", None)
        if "obj_name" in ov:
            o.name = ov.pop("obj_name")
        if "code" in ov:
            o.code = ov.pop("code")
        e = o.subs.setdefault(sub, {"raw": None, "sec": "", "type": U32, "access": "rw", "pdo": False,
                                    "default": None, "low": None, "high": None, "name": ""})
        e.update(ov)
        if why:
            log(index, sub, why, ov.get("sec", ""))
    for index in cfg.get("remove", []):
        objs.pop(index, None)
    for index, sub in cfg.get("remove_subs", []):
        objs[index].subs.pop(sub, None)

    # Finish objects: names, object codes, sub 0.
    for index, o in objs.items():
        subs = o.subs
        if o.code is None and list(subs) == [0] and index not in cfg.get("force_record", ()):
            o.code = 7
        if o.code is None:
            if 0x1400 <= index <= 0x1BFF or index in (0x1018, 0x1200):
                o.code = 9
            else:
                types = {e["type"] for s, e in subs.items() if s > 0}
                o.code = 8 if len(types) == 1 else 9
        if 0x1400 <= index <= 0x1BFF or index == 0x1018:
            o.code = 9
        if o.code == 7:
            e = subs[0]
            o.name = o.name or clean_name(e["name"])
            continue
        first = subs.get(0) or subs[min(subs)]
        if o.name is None:
            n = first["name"]
            if " / " in n:
                n = n.split(" / ", 1)[0]
            elif ": " in n:
                n = n.split(": ", 1)[0]
            o.name = clean_name(n)
        slash = all(" / " in e["name"] for e in subs.values() if e["raw"])
        colon_prefixes = {e["name"].split(": ", 1)[0] for e in subs.values() if e["raw"] and ": " in e["name"]}
        colon = len(colon_prefixes) == 1 and sum(1 for e in subs.values() if e["raw"]) > 1 and all(
            ": " in e["name"] for e in subs.values() if e["raw"])
        for s, e in subs.items():
            n = e["name"]
            if " / " in n and slash:
                n = n.split(" / ", 1)[1]
            elif colon and ": " in n:
                n = n.split(": ", 1)[1]
            elif s == 0 and re.search(r": (number|Number)", n):
                n = n.split(": ", 1)[1]
            e["name"] = clean_name(n)
        if 0 not in subs:
            hi = max(subs)
            subs[0] = {"raw": None, "sec": "", "type": U8, "access": "ro", "pdo": False, "default": str(hi),
                       "low": None, "high": None, "name": "Highest sub-index supported"}
        s0 = subs[0]
        if s0.get("access_assumed"):
            s0["access"] = "ro"
        if s0["default"] is None:
            s0["default"] = "0" if index == 0x1003 else str(max(subs))
        if s0["type"] != U8:
            log(index, 0, f"sub 0 type {TYPE_NAME.get(s0['type'])} in the table; UNSIGNED8 (CiA 301 §7.4.3) written", s0["sec"])
            s0["type"] = U8
            s0["low"] = s0["high"] = None

    return objs, log


def fmt_obj_sections(o):
    out = []

    def var(e, head):
        lines = list(head)
        lines.append(f"DataType=0x{e['type']:04X}")
        lines.append(f"AccessType={e['access']}")
        if e["default"] is not None:
            lines.append(f"DefaultValue={e['default']}")
        elif e["type"] in RANGE:
            lines.append("DefaultValue=0")
        else:
            lines.append("DefaultValue=")
        if e.get("low") is not None:
            lines.append(f"LowLimit={e['low']}")
        if e.get("high") is not None:
            lines.append(f"HighLimit={e['high']}")
        lines.append(f"PDOMapping={1 if e['pdo'] else 0}")
        return lines

    if o.code == 7:
        e = o.subs[0]
        code = "0x2" if e["type"] == DOM else "0x7"
        out.append((f"{o.index:04X}", var(e, [f"ParameterName={o.name}", f"ObjectType={code}"])))
        return out
    out.append((f"{o.index:04X}", [f"ParameterName={o.name}", f"ObjectType=0x{o.code:X}", f"SubNumber=0x{len(o.subs):X}"]))
    for s in sorted(o.subs):
        e = o.subs[s]
        out.append((f"{o.index:04X}sub{s:X}", var(e, [f"ParameterName={e['name']}", "ObjectType=0x7"])))
    return out


def write_eds(name, cfg, objs):
    lines = []

    def sec(title, kv):
        lines.append(f"[{title}]")
        lines.extend(kv)
        lines.append("")

    lines.append(f"; drivebus personality '{name}': {cfg['product']}")
    lines.append(cfg.get("header") or f"; Transcribed from {cfg['manual']} (object table {cfg['tsv']}); choices: docs/personalities.md")
    lines.append("")
    sec("FileInfo", [f"FileName={name}.eds", "FileVersion=1", "FileRevision=0", "EDSVersion=4.0",
                     f"Description={cfg['description']}", "CreationTime=12:00PM", "CreationDate=11-22-2026",
                     "CreatedBy=drivebus", "ModificationTime=12:00PM", "ModificationDate=11-22-2026",
                     "ModifiedBy=drivebus"])
    di = [f"VendorName={cfg['vendor']}"]
    if cfg.get("vendor_number") is not None:
        di.append(f"VendorNumber=0x{cfg['vendor_number']:08X}")
    di.append(f"ProductName={cfg['product']}")
    if cfg.get("product_number") is not None:
        di.append(f"ProductNumber=0x{cfg['product_number']:08X}")
    if cfg.get("revision_number") is not None:
        di.append(f"RevisionNumber=0x{cfg['revision_number']:08X}")
    di.append(f"OrderCode={cfg.get('order_code', '')}")
    for b in (10, 20, 50, 125, 250, 500, 800, 1000):
        di.append(f"BaudRate_{b}={1 if b in cfg['baud'] else 0}")
    di += ["SimpleBootUpMaster=0", "SimpleBootUpSlave=1", f"Granularity={cfg['granularity']}",
           "DynamicChannelsSupported=0", "GroupMessaging=0", f"NrOfRXPDO={cfg['nr_rx']}",
           f"NrOfTXPDO={cfg['nr_tx']}", f"LSS_Supported={cfg.get('lss', 0)}"]
    sec("DeviceInfo", di)
    sec("DummyUsage", [f"Dummy{i:04X}={1 if i in cfg.get('dummies', ()) else 0}" for i in range(1, 8)])
    comments = cfg.get("comments", [])
    sec("Comments", [f"Lines={len(comments)}"] + [f"Line{i + 1}={c}" for i, c in enumerate(comments)])
    mand = [i for i in (0x1000, 0x1001, 0x1018) if i in objs]
    opt = [i for i in sorted(objs) if i not in mand and not 0x2000 <= i <= 0x5FFF]
    man = [i for i in sorted(objs) if 0x2000 <= i <= 0x5FFF]
    for title, lst in (("MandatoryObjects", mand), ("OptionalObjects", opt), ("ManufacturerObjects", man)):
        sec(title, [f"SupportedObjects={len(lst)}"] + [f"{k + 1}=0x{i:04X}" for k, i in enumerate(lst)])
    # The data type entries of the dummy types (CiA 301 §7.4.7.1): DEFTYPE,
    # the size in bits, as the node's PDO service installs them. Not in any
    # object list (CiA 306 lists no data type objects there).
    bits = {1: 1, 2: 8, 3: 16, 4: 32, 5: 8, 6: 16, 7: 32}
    for t in sorted(cfg.get("dummies", ())):
        sec(f"{t:04X}", [f"ParameterName={TYPE_NAME[t]}", "ObjectType=0x5", "DataType=0x0007", "AccessType=const",
                         f"DefaultValue=0x{bits[t]:08X}", "PDOMapping=0"])
    for i in sorted(objs):
        for title, kv in fmt_obj_sections(objs[i]):
            sec(title, kv)
    with open(os.path.join(OUT, f"{name}.eds"), "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def main():
    only = sys.argv[1:]
    for name, cfg in profiles.PROFILES.items():
        if only and name not in only:
            continue
        objs, log = build(name, cfg)
        write_eds(name, cfg, objs)
        with open(os.path.join(HERE, f"choices-{name}.md"), "w", encoding="utf-8") as f:
            f.write(f"| object | choice | manual section(s) |\n|---|---|---|\n")
            f.write("\n".join(log.lines) + "\n")
        print(name, len(objs), "objects,", len(log.lines), "choices")


if __name__ == "__main__":
    main()
