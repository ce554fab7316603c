"""`drivebus eds dcf`: a running node's dictionary as a DCF (its values as
`ParameterValue`, `[DeviceComissioning]`) passes Lely's `dcfchk` (dcf-tools
2.4.2, warnings as errors) and our own checker, for every profile, with
its EDS (`--eds`) and without one (the CiA 301/402 standard objects). The
values in the file are the drive's: a value changed by SDO before the dump
shows up in it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import EDS_DIR, run_cli
from test_lely import BUS_NODES, PROFILES, dcfchk, our_check


def dump(url: str, node: int, out: Path, *extra) -> str:
    r = run_cli("--bus", url, "--node", node, *extra, "eds", "dcf", "--out", out, timeout=300)
    assert r.returncode == 0 and out.stat().st_size > 0, f"eds dcf node {node}: {r.stderr}"
    return out.read_text()


@pytest.mark.limit(600)
def test_dcf_of_every_running_drive_passes_dcfchk(serve, tmp_path):
    s = serve(*[f"{p}:{BUS_NODES[p]}" for p in PROFILES])
    for p in PROFILES:
        node = BUS_NODES[p]
        # A value the drive holds, not its EDS default: the heartbeat time,
        # or TPDO1's event timer where the drive has no 1017h (iPOS).
        for index, sub, section_name in (("1017", "0", "[1017]"), ("1800", "5", "[1800sub5]")):
            w = run_cli("--bus", s.url, "--node", node, "sdo", "write", index, sub, "1234")
            if w.returncode == 0:
                break
        assert w.returncode == 0, f"{p}: neither 1017h nor 1800h:05 writable: {w.stderr}"
        for name, extra in (("eds", ("--eds", EDS_DIR / f"{p}.eds")), ("std", ())):
            out = tmp_path / f"{p}-{name}.dcf"
            text = dump(s.url, node, out, *extra)
            assert "[DeviceComissioning]" in text and f"NodeID=0x{node:02X}" in text, f"{p} {name}"
            section = text.split(section_name, 1)[1].split("\n[", 1)[0]
            assert "ParameterValue=0x04D2" in section, f"{p} {name}: {index}h is not the drive's value:\n{section}"
            dcfchk(out, node)
            our_check(out)
