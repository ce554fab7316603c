#!/usr/bin/env python3
"""Cross-check: python-canopen (the reference third-party client, see
shared/reference/transport-feasibility.md) reads every personality EDS and
each default mapping points at a PDO-mappable object.

    pip install canopen && python3 tools/check_canopen.py   # from crates/personality
"""
import os
import warnings

import canopen

EDS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "eds")

for n in ["kc1", "akd", "ipos", "ssd630", "dds6", "generic"]:
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        od = canopen.import_od(os.path.join(EDS, f"{n}.eds"), node_id=5)
    assert not w, (n, [str(x.message) for x in w])
    for m in list(range(0x1600, 0x1604)) + list(range(0x1A00, 0x1A04)):
        if m not in od:
            continue
        for s in range(1, od[m][0].default + 1):
            e = od[m][s].default
            obj = od[e >> 16]
            tgt = obj if isinstance(obj, canopen.objectdictionary.ODVariable) else obj[(e >> 8) & 0xFF]
            assert tgt.pdo_mappable, (n, hex(m), hex(e))
    print(f"{n}: {len(od)} entries (dummy types included), no warnings")
