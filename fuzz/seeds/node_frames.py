#!/usr/bin/env python3
"""Seeds for the node_frames fuzz target from the manuals' traces.

Reads the master-to-drive frames of every worked example in
../shared/reference/seed*-examples.md (the KC1, AKD, iPOS, SSD 630 and
DDS6 manuals' CAN traffic), re-addresses them to the fuzz target's node
(node-ID 5) and writes one seed per example into seeds/node_frames/ in the
target's record format: CAN-ID (2 bytes, little-endian), flags (bit 0
extended, bit 1 remote, bits 2-7 time step in 100 us), DLC, 8 data bytes.

Run from fuzz/: python3 seeds/node_frames.py [REFERENCE_DIR]
"""
import pathlib
import re
import sys

NODE = 5
HEX2 = re.compile(r"^[0-9A-Fa-f]{2}$")
COB = re.compile(r"^[0-7][0-9A-Fa-f]{2}$")


def readdress(cob, data):
    """Moves a frame of the pre-defined connection set to node NODE."""
    if cob == 0x000 and len(data) >= 2 and data[1] != 0:
        data = [data[0], NODE] + data[2:]
    elif cob == 0x080 or cob == 0x7E5:
        pass
    elif 0x180 <= cob <= 0x77F and cob & 0x7F:
        cob = (cob & 0x780) | NODE
    return cob, data


def master_frame(cob):
    """Frames a master sends: NMT, SYNC, RPDOs, SDO requests, LSS."""
    return cob in (0x000, 0x080, 0x7E5) or 0x200 <= cob <= 0x57F or 0x600 <= cob <= 0x67F


def data_cell(cells):
    """The longest cell of 1..8 hex bytes (a table may print a row twice)."""
    best = []
    for c in cells:
        toks = c.split()
        if toks and len(toks) <= 8 and all(HEX2.match(t) for t in toks) and len(toks) >= len(best):
            best = [int(t, 16) for t in toks]
    return best


def frame(line):
    """(COB-ID, data) of a master-to-drive row of a trace, else None."""
    if line.lstrip().startswith("|"):
        cells = [c.strip().strip("`").strip() for c in line.split("|")]
        at = next((i for i, c in enumerate(cells) if "→" in c or "M->D" in c), None)
        if at is None:
            return None
        # "| → | 601 | …" (SSD 630, DDS6) or "| 601 | SDO req (M->D) | …" (AKD).
        look = cells[at + 1 :] if "→" in cells[at] else cells[:at]
        cob = next((int(c, 16) for c in look if COB.match(c)), None)
        return None if cob is None else (cob, data_cell(cells[at + 1 :]))
    if "M->D" not in line:
        return None
    rest = line.split("M->D", 1)[1].split()
    if len(rest) < 2 or not COB.match(rest[0]):
        return None
    data = []
    for t in rest[2:]:
        if not HEX2.match(t) or len(data) == 8:
            break
        data.append(int(t, 16))
    return int(rest[0], 16), data


def main():
    here = pathlib.Path(__file__).resolve().parent
    # shared/ sits beside the project's checkout (or beside its worktrees' folder).
    ref = next(
        (p / "shared" / "reference" for p in here.parents if (p / "shared" / "reference").is_dir()),
        None,
    )
    ref = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ref
    if ref is None:
        sys.exit("no shared/reference found; pass its path")
    out = here / "node_frames"
    out.mkdir(exist_ok=True)
    n = 0
    for f in sorted(ref.glob("seed*-examples.md")):
        drive = f.name.split("-")[1]
        example, records = None, []

        def flush():
            nonlocal n
            if example is not None and records:
                (out / f"{drive}-{example:02d}").write_bytes(b"".join(records))
                n += 1

        for line in f.read_text(encoding="utf-8").splitlines():
            if line.startswith("## "):
                # Each second-level section is one example (or none).
                flush()
                example, records = (0 if example is None else example + 1), []
                continue
            fr = frame(line)
            if fr is None or not master_frame(fr[0]):
                continue
            cob, data = readdress(*fr)
            # 1 ms between frames (flags bits 2-7: 10 x 100 us).
            records.append(bytes([cob & 0xFF, cob >> 8, 10 << 2, len(data)]) + bytes(data + [0] * (8 - len(data))))
        flush()
    print(f"{n} seeds in {out}")


if __name__ == "__main__":
    main()
