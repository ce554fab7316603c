"""drivebus's EDS and DCF files against Lely's tools (dcf-tools 2.4.2,
pinned in requirements.txt): `dcfchk` (CiA 306 lint plus the device model
Lely's master builds from a file) and `dcfgen` (the master's DCF and the
concise configuration of every slave from a YAML bus description).

Every file a user gets from drivebus passes `dcfchk -n NODE`: the shipped
EDS of each profile, `eds export --profile`, `--eds FILE eds export` (also
of a DCF Lely wrote), and the EDS read off a running drive at 1021h. A bus
of all six profiles with a PDO configuration for every one goes through
`dcfgen`, and the concise DCFs it generates are accepted by the running
drives. Lely's warnings are errors here (`-W error::UserWarning`): a file
it only complains about fails the test. No Lely tool in the venv is a
failure, not a skip.
"""

from __future__ import annotations

import importlib.util
import shutil
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import EDS_DIR, connect, require_command, run_cli

PROFILES = ["kc1", "akd", "ipos", "ssd630", "dds6", "generic"]
# The node of each profile on the dcfgen bus (the master is node 1).
BUS_NODES = {p: n for n, p in enumerate(PROFILES, start=2)}


def _require_lely() -> None:
    for module in ("dcf", "dcfgen"):
        if importlib.util.find_spec(module) is None:
            pytest.fail(
                f"Lely dcf-tools missing from {sys.executable}: module {module!r} not found "
                "(tests/interop/run installs requirements.txt into the venv)"
            )


def lely(tool: str, *args, cwd=None) -> subprocess.CompletedProcess:
    """Runs a Lely tool with its warnings as errors."""
    _require_lely()
    module = {"dcfchk": "dcf.cli", "dcfgen": "dcfgen.cli"}[tool]
    # dcfgen imports pkg_resources, which warns that it is deprecated: about
    # Lely's code, not about our files.
    return subprocess.run(
        [sys.executable, "-W", "error::UserWarning", "-W", "ignore::DeprecationWarning", "-m", module, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
    )


def dcfchk(path: Path, node: int) -> None:
    r = lely("dcfchk", "-n", node, path)
    assert r.returncode == 0 and not r.stderr.strip(), (
        f"Lely dcfchk -n {node} {path}: exit {r.returncode}\n{r.stdout}\n{r.stderr}"
    )


def our_check(path: Path) -> str:
    """`drivebus eds check`: no error; returns the summary line."""
    r = run_cli("eds", "check", path)
    assert r.returncode == 0, f"drivebus eds check {path}: {r.returncode}\n{r.stdout}\n{r.stderr}"
    return r.stdout.strip().splitlines()[-1]


def export(*args, out: Path, timeout: float = 30.0) -> Path:
    require_command("eds", "export")
    r = run_cli(*args, "--out", out, timeout=timeout)
    assert r.returncode == 0 and out.stat().st_size > 0, f"drivebus {' '.join(map(str, args))}: {r.stderr}"
    return out


def test_lely_tools_are_installed():
    _require_lely()
    for tool in ("dcfchk", "dcfgen"):
        r = lely(tool, "--help")
        assert r.returncode == 0, f"{tool} --help: {r.stderr}"


@pytest.mark.parametrize("profile", PROFILES)
def test_shipped_eds_passes_dcfchk(profile):
    for node in (1, 5, 127):
        dcfchk(EDS_DIR / f"{profile}.eds", node)


@pytest.mark.parametrize("profile", PROFILES)
def test_exported_files_pass_dcfchk_and_our_checker(profile, tmp_path):
    shipped = EDS_DIR / f"{profile}.eds"
    exported = export("eds", "export", "--profile", profile, out=tmp_path / f"{profile}.eds")
    rewritten = export("--eds", shipped, "eds", "export", out=tmp_path / f"{profile}-rewritten.eds")
    want = our_check(shipped).split(": ", 1)[1]
    for f in (exported, rewritten):
        dcfchk(f, 5)
        assert our_check(f).endswith(want), f"{f}: our checker differs from the shipped file's: {want}"


# The SSD 630's EDS is 1.2 MB: ~170 000 SDO segments (it has no block
# transfer), half a minute on a debug build.
@pytest.mark.limit(600)
def test_eds_read_off_every_drive_passes_dcfchk(serve, tmp_path):
    drives = [f"{p}:{BUS_NODES[p]}" for p in PROFILES]
    s = serve(*drives, extra=("--eds-object",))
    for p in PROFILES:
        node = BUS_NODES[p]
        got = export(
            "--bus", s.url, "--node", node, "eds", "export", out=tmp_path / f"{p}-node{node}.eds", timeout=300
        )
        dcfchk(got, node)
        shipped = our_check(EDS_DIR / f"{p}.eds").split(": ", 1)[1]
        assert our_check(got).endswith(shipped), f"{p}: the served EDS checks unlike the shipped one"


def _bus_yaml(directory: Path) -> Path:
    """A bus of every profile (copies of the shipped EDS files), each with
    RPDO1 = controlword + target position and TPDO1 = statusword + position
    actual value, synchronous, COB-IDs from Lely's pre-defined set."""
    lines = [
        "master:",
        "  node_id: 1",
        "  baudrate: 500",
        "  sync_period: 1000",
        "  heartbeat_producer: 100",
    ]
    for p in PROFILES:
        shutil.copy(EDS_DIR / f"{p}.eds", directory / f"{p}.eds")
        lines += [
            f"{p}:",
            f"  dcf: {p}.eds",
            f"  node_id: {BUS_NODES[p]}",
            "  rpdo:",
            "    1: {enabled: true, cob_id: auto, transmission: 1, mapping: "
            "[{index: 0x6040, sub_index: 0}, {index: 0x607A, sub_index: 0}]}",
            "  tpdo:",
            "    1: {enabled: true, cob_id: auto, transmission: 1, mapping: "
            "[{index: 0x6041, sub_index: 0}, {index: 0x6064, sub_index: 0}]}",
        ]
    path = directory / "bus.yml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _dcfgen(directory: Path) -> None:
    r = lely("dcfgen", "bus.yml", cwd=directory)
    assert r.returncode == 0 and not r.stderr.strip(), f"Lely dcfgen: exit {r.returncode}\n{r.stdout}\n{r.stderr}"


def concise(path: Path) -> list[tuple[int, int, bytes]]:
    """The entries of a concise DCF (CiA 302-3 / Lely .bin): a UNSIGNED32
    count, then index, sub-index, size and data per entry."""
    data = path.read_bytes()
    (n,) = struct.unpack_from("<L", data)
    pos, out = 4, []
    for _ in range(n):
        index, sub, size = struct.unpack_from("<HBL", data, pos)
        pos += 7
        out.append((index, sub, data[pos : pos + size]))
        pos += size
    assert pos == len(data), f"{path}: {len(data) - pos} bytes after the last entry"
    return out


def test_dcfgen_takes_a_bus_of_every_profile(tmp_path):
    _bus_yaml(tmp_path)
    _dcfgen(tmp_path)
    assert (tmp_path / "master.dcf").stat().st_size > 0
    for p in PROFILES:
        entries = concise(tmp_path / f"{p}.bin")
        mapped = {(i, s): d for i, s, d in entries}
        assert mapped[(0x1A00, 1)] == struct.pack("<L", 0x6041_0010), f"{p}: TPDO1 mapping"
        assert mapped[(0x1600, 2)] == struct.pack("<L", 0x607A_0020), f"{p}: RPDO1 mapping"
    # Lely's master.dcf, a third-party DCF: our checker reads it, and our
    # rewrite (drivebus --eds FILE eds export) passes Lely's own dcfchk with
    # the same [DummyUsage].
    master = tmp_path / "master.dcf"
    our_check(master)
    again = export("--eds", master, "eds", "export", out=tmp_path / "master-again.dcf")
    dcfchk(again, 1)

    def dummies(path: Path) -> list[str]:
        lines = path.read_text().splitlines()
        start = lines.index("[DummyUsage]") + 1
        return [l for l in lines[start:] if l.startswith("Dummy")][:64]

    assert dummies(again) == dummies(master)


@pytest.mark.limit(120)
def test_dcfgen_configuration_is_accepted_by_the_drives(serve, tmp_path):
    _bus_yaml(tmp_path)
    _dcfgen(tmp_path)
    s = serve(*[f"{p}:{BUS_NODES[p]}" for p in PROFILES])
    net = connect(*s)
    try:
        # A master configures in pre-operational (CiA 302-2 boot-up; the
        # SSD 630 may have started itself, 2018h).
        net.nmt.state = "PRE-OPERATIONAL"
        time.sleep(0.1)
        for p in PROFILES:
            node = net.add_node(BUS_NODES[p], str(tmp_path / f"{p}.eds"))
            node.sdo.RESPONSE_TIMEOUT = 1.0
            for index, sub, data in concise(tmp_path / f"{p}.bin"):
                try:
                    node.sdo.download(index, sub, data)
                except Exception as e:  # noqa: BLE001 - name the entry
                    pytest.fail(f"{p}: concise DCF entry {index:04X}h:{sub} = {data.hex()} refused: {e}")
            assert node.sdo.upload(0x1A00, 1) == struct.pack("<L", 0x6041_0010), p
            cob = int.from_bytes(node.sdo.upload(0x1800, 1), "little")
            assert cob & 0x8000_0000 == 0, f"{p}: TPDO1 not valid after the configuration: {cob:08X}h"
        # Operational, SYNC: every drive sends its configured TPDO1.
        seen: set[int] = set()
        want = {0x180 + BUS_NODES[p] for p in PROFILES}
        for cob in want:
            net.subscribe(cob, lambda cob_id, data, ts: seen.add(cob_id))
        net.nmt.state = "OPERATIONAL"
        end = time.monotonic() + 5
        while seen != want and time.monotonic() < end:
            net.sync.transmit()
            time.sleep(0.02)
        assert seen == want, f"TPDO1 missing from nodes {sorted(c - 0x180 for c in want - seen)}"
    finally:
        net.disconnect()
