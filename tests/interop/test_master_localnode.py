"""Our master (the `drivebus` CLI) against canopen 2.4.1's LocalNode, an
independent SDO server (expedited and segmented only), both connected to
`drivebus serve`'s socketcand hub."""

from __future__ import annotations

import json
import re
import time

import canopen
import pytest
from canopen.objectdictionary import ODVariable
from canopen.objectdictionary import datatypes as dt

from conftest import require_command, run_cli

LOCAL = 7
LONG_TEXT = "drivebus talks to canopen's LocalNode, segmented"  # > 4 bytes: segmented


def make_od() -> canopen.ObjectDictionary:
    od = canopen.ObjectDictionary()
    od.device_information.product_name = "canopen LocalNode"
    for index, name, typ, access, default in [
        (0x1000, "Device type", dt.UNSIGNED32, "ro", 0x00020192),
        (0x2000, "Test u32", dt.UNSIGNED32, "rw", 0),
        (0x2001, "Test text", dt.VISIBLE_STRING, "rw", LONG_TEXT),
        (0x2002, "Test i16", dt.INTEGER16, "rw", 0),  # canopen exports -5 as "0x-5"
    ]:
        v = ODVariable(name, index, 0)
        v.data_type, v.access_type, v.default = typ, access, default
        od.add_object(v)
    return od


@pytest.fixture
def bus(serve, networks):
    """(socketcand URL, LocalNode 7) on a `drivebus serve --drive generic:5` hub."""
    require_command("sdo", "read")
    srv = serve("generic:5")  # serve requires a drive: host one at another node-ID
    net = networks(*srv)
    local = canopen.LocalNode(LOCAL, make_od())
    net.add_node(local)
    return srv.url, local


def cli(url: str, *args, node: int = LOCAL, timeout: float = 30.0):
    return run_cli("--bus", url, "--node", node, "--timeout", 1000, *args, timeout=timeout)


def cli_json(url, *args, node=LOCAL) -> dict:
    r = cli(url, "--json", *args, node=node)
    assert r.returncode == 0, f"exit {r.returncode}\nstdout: {r.stdout}\nstderr: {r.stderr}"
    lines = [ln for ln in r.stdout.splitlines() if ln.strip().startswith("{")]
    assert lines, f"no JSON on stdout: {r.stdout!r}"
    return json.loads(lines[-1])


def test_expedited_read(bus):
    url, local = bus
    j = cli_json(url, "sdo", "read", "0x1000", "0", "--type", "u32")
    assert j["value"] == 0x00020192
    assert j["raw"].upper() == "92010200"
    # text output mentions the value too
    r = cli(url, "sdo", "read", "0x1000", "0", "--type", "u32")
    assert r.returncode == 0, r.stderr
    assert re.search(r"\b131474\b|0x0*20192\b", r.stdout, re.I), r.stdout


def test_expedited_write(bus):
    url, local = bus
    r = cli(url, "sdo", "write", "0x2000", "0", "1234", "--type", "u32")
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert local.sdo[0x2000].raw == 1234
    assert local.get_data(0x2000, 0) == (1234).to_bytes(4, "little")
    assert cli_json(url, "sdo", "read", "0x2000", "0", "--type", "u32")["value"] == 1234
    r = cli(url, "sdo", "write", "0x2002", "0", "-300", "--type", "i16")
    assert r.returncode == 0, r.stderr
    assert local.sdo[0x2002].raw == -300
    assert cli_json(url, "sdo", "read", "0x2002", "0", "--type", "i16")["value"] == -300


def test_segmented_read(bus):
    url, local = bus
    j = cli_json(url, "sdo", "read", "0x2001", "0", "--type", "str")
    assert j["value"] == LONG_TEXT
    assert bytes.fromhex(j["raw"]) == LONG_TEXT.encode()


def test_segmented_write(bus):
    url, local = bus
    text = "written by the drivebus master, 40+ bytes long"
    r = cli(url, "sdo", "write", "0x2001", "0", text, "--type", "str")
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert local.get_data(0x2001, 0) == text.encode()
    assert cli_json(url, "sdo", "read", "0x2001", "0", "--type", "str")["value"] == text


def test_upload_and_download_files(bus, tmp_path):
    require_command("sdo", "upload")
    url, local = bus
    out = tmp_path / "text.bin"
    r = cli(url, "sdo", "upload", "0x2001", "0", out)
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert out.read_bytes() == LONG_TEXT.encode()
    src = tmp_path / "in.bin"
    src.write_bytes(b"file via segmented download " * 3)
    r = cli(url, "sdo", "download", "0x2001", "0", src)
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert local.get_data(0x2001, 0) == src.read_bytes()


def test_types_from_eds(bus, tmp_path):
    """The LocalNode's dictionary exported by canopen as an EDS gives the
    CLI its types (`--eds`), so no --type is needed."""
    url, local = bus
    eds = tmp_path / "local.eds"
    canopen.export_od(local.object_dictionary, str(eds), doc_type="eds")
    local.sdo[0x2002].raw = -42
    r = run_cli("--bus", url, "--node", LOCAL, "--eds", eds, "--json", "sdo", "read", "0x2002", "0")
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert json.loads(r.stdout.strip().splitlines()[-1])["value"] == -42
    r = run_cli("--bus", url, "--node", LOCAL, "--eds", eds, "sdo", "write", "0x2000", "0", "77")
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    assert local.sdo[0x2000].raw == 77


def norm(s: str) -> str:
    return re.sub(r"[\s_]", "", s).lower()


def test_abort_is_reported(bus):
    url, local = bus
    r = cli(url, "sdo", "read", "0x3000", "0", "--type", "u32")
    assert r.returncode != 0
    msg = r.stdout + r.stderr
    assert "06020000" in norm(msg), msg
    assert "exist" in msg.lower(), f"abort meaning not printed: {msg}"
    r = cli(url, "sdo", "write", "0x1000", "0", "5", "--type", "u32")  # read-only in the LocalNode
    assert r.returncode != 0
    assert "06010002" in norm(r.stdout + r.stderr), r.stdout + r.stderr


def test_no_such_node_times_out(bus):
    url, _ = bus
    t0 = time.monotonic()
    r = cli(url, "sdo", "read", "0x1000", "0", node=42)
    took = time.monotonic() - t0
    assert r.returncode != 0
    assert "time" in (r.stdout + r.stderr).lower(), r.stdout + r.stderr
    assert took < 15, f"took {took:.1f} s with --timeout 1000"
