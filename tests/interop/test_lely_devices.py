"""Devices from third-party EDS/DCF files (`drivebus serve --device
FILE:NODE`, `slcan-pty --device`; tests/vectors/eds/ and the CiA 401 module
crates/cia401/eds/io16.eds) on a bus Lely's `dcfgen` (dcf-tools 2.4.2,
pinned) configures: the files pass Lely's `dcfchk`, `dcfgen` takes a bus of
them (warnings as errors), the running devices accept every entry of the
concise DCFs it generates, and the configuration runs — the CiA 401
module's remapped TPDO1 and RPDO1, every device's heartbeat at the
configured period. A served device also gives its file back at 1021h
(`--eds-object`), and Lely's `dcfchk` takes that too.
"""

from __future__ import annotations

import shutil
import struct
import time
from pathlib import Path

import canopen
import pytest

from conftest import ROOT, connect
from test_lely import concise, dcfchk, lely

VECTORS = ROOT / "tests" / "vectors" / "eds"
IO16 = ROOT / "crates" / "cia401" / "eds" / "io16.eds"
# name on the bus, file, node-ID, heartbeat period dcfgen configures (ms)
BUS = [
    ("io", IO16, 3, 200),
    ("canopennode", VECTORS / "canopennode-DS301_profile.eds", 4, 300),
    ("nmt", VECTORS / "lely-co-nmt-slave.dcf", 6, 400),
    ("sdev", VECTORS / "lely-co-sdev.dcf", 5, None),
    ("pdot", VECTORS / "lely-co-pdo-transmit.dcf", 7, None),
]


def _bus(directory: Path) -> None:
    lines = ["master:", "  node_id: 1", "  baudrate: 500", "  heartbeat_producer: 100"]
    for name, path, node, hb in BUS:
        shutil.copy(path, directory / path.name)
        lines += [f"{name}:", f"  dcf: {path.name}", f"  node_id: {node}"]
        if hb:
            lines.append(f"  heartbeat_producer: {hb}")
        if name == "io":
            lines += [
                "  rpdo:",
                "    1: {enabled: true, cob_id: auto, transmission: 255, mapping: "
                "[{index: 0x6200, sub_index: 1}, {index: 0x6200, sub_index: 2}]}",
                "  tpdo:",
                "    1: {enabled: true, cob_id: auto, transmission: 255, mapping: "
                "[{index: 0x6000, sub_index: 2}, {index: 0x6000, sub_index: 1}]}",
            ]
    (directory / "bus.yml").write_text("\n".join(lines) + "\n")
    r = lely("dcfgen", "bus.yml", cwd=directory)
    assert r.returncode == 0 and not r.stderr.strip(), f"Lely dcfgen: exit {r.returncode}\n{r.stdout}\n{r.stderr}"


@pytest.mark.parametrize("path", sorted(VECTORS.glob("*.dcf")) + [VECTORS / "canopennode-DS301_profile.eds", IO16], ids=lambda p: p.name)
def test_the_files_pass_dcfchk(path):
    dcfchk(path, 5)


@pytest.mark.limit(120)
def test_dcfgen_configures_a_bus_of_devices_from_their_files(serve, tmp_path):
    _bus(tmp_path)
    devices = []
    for _, path, node, _ in BUS:
        devices += ["--device", f"{tmp_path / path.name}:{node}"]
    s = serve("generic:9", extra=tuple(devices))
    assert "io16.eds:3 (CiA 401)" in s.proc.describe(), "the ready line names the module"
    net = connect(*s)
    try:
        net.nmt.state = "PRE-OPERATIONAL"
        time.sleep(0.1)
        configured = 0
        for name, path, node, hb in BUS:
            binary = tmp_path / f"{name}.bin"
            if hb is None:
                assert not binary.exists(), f"{name}: dcfgen configured nothing, yet wrote {binary}"
                continue
            dev = net.add_node(node)  # raw SDO: canopen-python cannot read every DCF Lely writes
            dev.sdo.RESPONSE_TIMEOUT = 1.0
            for index, sub, data in concise(binary):
                try:
                    dev.sdo.download(index, sub, data)
                except Exception as e:  # noqa: BLE001 - name the entry
                    pytest.fail(f"{name}: concise DCF entry {index:04X}h:{sub} = {data.hex()} refused: {e}")
                configured += 1
            assert dev.sdo.upload(0x1017, 0) == struct.pack("<H", hb), name
        assert configured >= 10
        io = net.nodes[3]
        io.sdo.RESPONSE_TIMEOUT = 1.0
        seen: dict[int, list[bytes]] = {}
        for cob in (0x183, 0x703, 0x704, 0x706):
            net.subscribe(cob, lambda cob_id, data, ts: seen.setdefault(cob_id, []).append(bytes(data)))
        net.nmt.state = "OPERATIONAL"
        # RPDO1 of the configuration: outputs 1–16; output bytes read back.
        net.send_message(0x203, bytes([0xA5, 0x3C]))
        end = time.monotonic() + 3
        while time.monotonic() < end and not (seen.get(0x183) and all(seen.get(c) for c in (0x703, 0x704, 0x706))):
            time.sleep(0.05)
        assert io.sdo.upload(0x6200, 1) == b"\xa5" and io.sdo.upload(0x6200, 2) == b"\x3c"
        # TPDO1 as remapped: 6000h:2 first, then 6000h:1 (all inputs low).
        assert seen.get(0x183, [None])[0] == b"\x00\x00", f"TPDO1 of the module: {seen.get(0x183)}"
        for cob in (0x703, 0x704, 0x706):
            assert seen.get(cob), f"no heartbeat from node {cob - 0x700}"
    finally:
        net.disconnect()


def test_a_served_file_comes_back_at_1021h_and_passes_dcfchk(serve, tmp_path):
    src = VECTORS / "canopennode-DS301_profile.eds"
    s = serve("generic:9", extra=("--eds-object", "--device", f"{src}:4"))
    net = connect(*s)
    try:
        dev = net.add_node(4)
        dev.sdo.RESPONSE_TIMEOUT = 1.0
        text = dev.sdo.upload(0x1021, 0)
    finally:
        net.disconnect()
    assert text == src.read_bytes(), "1021h is the file as given"
    got = tmp_path / "read-back.eds"
    got.write_bytes(text)
    dcfchk(got, 4)


@pytest.mark.limit(60)
def test_a_cia401_module_behind_slcan_pty():
    """`slcan-pty --device`: canopen over python-can's slcan reads and
    writes the module with its own EDS as the dictionary."""
    from conftest import Proc

    proc = Proc(["slcan-pty", "--device", f"{IO16}:3"])
    try:
        path = proc.wait_line(r"slcan-pty\s+(/\S+)").group(1)
        net = canopen.Network()
        net.NOTIFIER_CYCLE = 0.1
        net.connect(interface="slcan", channel=path, bitrate=500000, sleep_after_open=0.1)
        try:
            io = net.add_node(3, str(IO16))
            io.sdo.RESPONSE_TIMEOUT = 2.0
            assert io.sdo[0x1000].raw == 0x000F0191
            io.sdo[0x6200][1].raw = 0x33
            assert io.sdo[0x6200][1].raw == 0x33
            assert io.sdo["Read analogue input 16-bit"][1].raw == 0
        finally:
            net.disconnect()
    finally:
        assert proc.stop() == 0, proc.describe()
