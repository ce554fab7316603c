"""SOEM (through pysoem) against the README's mixed line, served by the
CLI: `drivebus ethercat serve --device …` (real devices' EEPROM images and
an ESI file, `tests/vectors/ethercat/`) and `--drive ipos` twice, over a
veth pair (set-up and skip rules as `test_ethercat_pysoem.py`).

Checks: the slaves sit in command-line order with the real names and
identities; SDO Information lists the board's ESI objects; SOEM maps the process data (SII categories for the terminals,
CoE for the board and the drives) and takes the line to OP with the
working counter a real line gives; the board's inputs loop its outputs
back; a damaged file stops the command before it serves, naming the file,
the place and the cause.
"""

from __future__ import annotations

import re
import subprocess
import time
from pathlib import Path

import pysoem
import pytest

from conftest import BIN, require_command
from test_ethercat_pysoem import NetnsProc, Wire

VECTORS = Path(__file__).resolve().parents[1] / "vectors" / "ethercat"
LINE = [
    "--device", str(VECTORS / "ek1100.bin"),
    "--device", str(VECTORS / "el2004.hex"),
    "--device", str(VECTORS / "el2828.bin"),
    "--device", str(VECTORS / "kickcat-freedom-k64f.xml"),
    "--drive", "ipos",
    "--drive", "ipos",
]


class DevWire(Wire):
    def __init__(self):
        super().__init__()
        tag = f"dbdv{self.ns[4:]}"
        self.ns, self.outer, self.inner = tag, f"{tag}a", f"{tag}b"


@pytest.fixture(scope="module")
def wire():
    w = DevWire()
    why = w.create()
    if why is not None:
        w.remove()
        pytest.skip(f"SOEM/pysoem over veth not run: {why}")
    yield w
    w.remove()


@pytest.fixture
def served(wire):
    require_command("ethercat", "serve")
    proc = NetnsProc(wire.ns, ["ethercat", "serve", "--iface", wire.inner, *LINE])
    try:
        m = proc.wait_line(rf"ready on {re.escape(wire.inner)} \(line (.*)\)")
    except BaseException:
        proc.p.kill()
        proc.p.wait(timeout=5)
        raise
    yield proc, m.group(1)
    assert proc.stop() == 0, proc.describe()


def test_mixed_line_in_order_to_op(wire, served):
    _, listed = served
    assert listed == "EK1100 EL2004 EL2828 Board ipos ipos"
    m = pysoem.Master()
    m.open(wire.outer)
    try:
        assert m.config_init() == 6
        ident = [(s.name, s.man, s.id, s.rev) for s in m.slaves]
        assert ident[:4] == [
            ("EK1100", 2, 0x044C2C52, 0x00120000),
            ("EL2004", 2, 0x07D43052, 0x00100000),
            ("EL2828", 2, 0x0B0C3052, 0x00110000),
            ("Board", 0x6A5, 0x00DEFEDE, 0x5A01),
        ]
        assert [i[0] for i in ident[4:]] == ["iPOS360x VX-CAT"] * 2
        # SDO Information over the ESI's dictionary (plus the 1C00h it lacks).
        names = {o.index: o.name for o in m.slaves[3].od}
        assert (names[0x6003], names[0x7000]) == (b"mag_x", b"LED_R"), names
        assert 0x1C00 in names and 0x1C12 in names
        m.config_map()
        assert [(len(s.output), len(s.input)) for s in m.slaves] == [(0, 0), (1, 0), (1, 0), (3, 12), (6, 16), (6, 16)]
        assert m.state_check(pysoem.SAFEOP_STATE, 500_000) == pysoem.SAFEOP_STATE
        m.state = pysoem.OP_STATE
        m.send_processdata()
        m.receive_processdata(10_000)
        m.write_state()
        for _ in range(200):
            m.send_processdata()
            m.receive_processdata(10_000)
            if m.state_check(pysoem.OP_STATE, 5_000) == pysoem.OP_STATE:
                break
        m.read_state()
        assert all(s.state == pysoem.OP_STATE for s in m.slaves), [hex(s.state) for s in m.slaves]
        board = m.slaves[3]
        wkc = []
        for n in range(105):
            k = min(n, 99)  # the last outputs held: inputs lag them by a cycle
            m.slaves[1].output = bytes([k & 0x0F])
            m.slaves[2].output = bytes([k])
            board.output = bytes([k, 2 * k & 0xFF, 3])
            m.send_processdata()
            wkc.append(m.receive_processdata(10_000))
            time.sleep(0.001)
        # 2 per slave written (5), 1 per slave read (3), as on a real line.
        assert set(wkc[5:]) == {13}, wkc
        assert bytes(board.input) == bytes([99, 198, 3]) * 4
    finally:
        m.close()


def test_damaged_file_is_refused_before_serving(wire, tmp_path):
    require_command("ethercat", "serve")
    bad = tmp_path / "bad.hex"
    bad.write_text(":0400000001020304F2\n:0400000001020304F3\n:00000001FF\n")
    r = subprocess.run(
        [str(BIN), "ethercat", "serve", "--iface", wire.outer, "--drive", "ipos", "--device", str(bad)],
        capture_output=True, text=True, timeout=30,
    )
    assert r.returncode != 0
    assert f"{bad}: line 2: checksum does not match" in r.stderr, r.stderr
    assert "ready on" not in r.stdout
