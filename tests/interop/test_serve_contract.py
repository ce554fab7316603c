"""The `drivebus serve` contract itself (issue 5 part 4), seen from python-can."""

from __future__ import annotations

import signal
import subprocess
import time

import can
import canopen
import pytest

from conftest import (
    CHANNEL,
    EDS_DIR,
    LOCALHOST,
    Proc,
    _EXPORT,
    free_port,
    has_command,
    require_command,
)


def test_listening_line_and_sigint_exit_0():
    require_command("serve")
    port = free_port()
    p = Proc(["serve", "--listen", f"{LOCALHOST}:{port}", "--drive", "generic:5"])
    try:
        m = p.wait_line(r"listening on")
        assert str(port) in m.string, m.string
        bus = can.Bus(interface="socketcand", host=LOCALHOST, port=port, channel=CHANNEL)
        bus.shutdown()
    finally:
        if p.p.poll() is None:
            p.p.send_signal(signal.SIGINT)
        try:
            rc = p.p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.p.kill()
            raise
    assert rc == 0, p.describe()


@pytest.mark.limit(60)
def test_sigterm_right_after_ready_line_exits_0():
    """Tools send SIGTERM as soon as they are done, which can be right after
    the `listening on` line: the handlers must be in place before it."""
    require_command("serve")
    bad = []
    for i in range(20):
        p = Proc(["serve", "--listen", f"{LOCALHOST}:{free_port()}", "--drive", "generic:5"])
        p.wait_line(r"listening on")
        p.p.send_signal(signal.SIGTERM)
        try:
            rc = p.p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.p.kill()
            p.p.wait(timeout=5)
            rc = "hang"
        if rc != 0:
            bad.append(rc)
    assert not bad, f"{len(bad)} of 20 runs ended with {bad} instead of exit 0 (SIGTERM right after the ready line)"


@pytest.mark.parametrize(
    "drive", ["nosuch:5", "generic:0", "generic:128", "generic"], ids=["profile", "node0", "node128", "no-node"]
)
def test_bad_drive_is_refused(drive):
    require_command("serve")
    p = Proc(["serve", "--listen", f"{LOCALHOST}:{free_port()}", "--drive", drive])
    try:
        rc = p.p.wait(timeout=10)
    except subprocess.TimeoutExpired:
        p.p.kill()
        pytest.fail(f"`serve --drive {drive}` kept running")
    assert rc != 0
    assert "listening on" not in "".join(p.stdout)
    assert p.stderr().strip(), "no error message"


def test_drives_boot_and_run_without_clients(serve):
    """Boot-up on start, and the drives keep running while nobody listens:
    a client that connects late still reaches them."""
    srv = serve("generic:5", "akd:1")
    time.sleep(0.3)
    bus = can.Bus(interface="socketcand", host=srv.host, port=srv.port, channel=CHANNEL)
    try:
        time.sleep(0.1)  # past the rawmode grace (see test_request_right_after_connect_is_answered)
        bus.send(can.Message(arbitration_id=0x601, data=b"\x40\x00\x10\x00\x00\x00\x00\x00", is_extended_id=False))
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            m = bus.recv(timeout=0.5)
            if m is not None and m.arbitration_id == 0x581:
                assert m.data[0] == 0x43
                break
        else:
            pytest.fail("akd:1 did not answer an SDO read of 1000h")
    finally:
        bus.shutdown()


def test_request_right_after_connect_is_answered(serve):
    """A client that sends as soon as python-can's Bus() returns must get the
    answer. The server's post-rawmode grace (transport-feasibility §4.2) may
    delay frames to the client, but must not drop them: canopen's scanner and
    every first SDO request of a script depend on it."""
    srv = serve("generic:5")
    for attempt in range(3):
        bus = can.Bus(interface="socketcand", host=srv.host, port=srv.port, channel=CHANNEL)
        try:
            bus.send(can.Message(arbitration_id=0x605, data=b"\x40\x00\x10\x00\x00\x00\x00\x00", is_extended_id=False))
            end = time.monotonic() + 1.0
            m = None
            while time.monotonic() < end:
                m = bus.recv(timeout=0.2)
                if m is not None and m.arbitration_id == 0x585:
                    break
            assert m is not None and m.arbitration_id == 0x585, (
                f"attempt {attempt}: no SDO response to a request sent right after connecting "
                "(frames relayed during the rawmode grace are dropped instead of delayed)"
            )
        finally:
            bus.shutdown()


def test_bootup_message_when_client_was_first(serve):
    """A client connected before a reset sees the boot-up (700h+N, data 00)."""
    srv = serve("generic:5")
    bus = can.Bus(interface="socketcand", host=srv.host, port=srv.port, channel=CHANNEL)
    try:
        time.sleep(0.1)
        bus.send(can.Message(arbitration_id=0x000, data=b"\x81\x05", is_extended_id=False))  # reset node 5
        end = time.monotonic() + 3.0
        while time.monotonic() < end:
            m = bus.recv(timeout=0.5)
            if m is not None and m.arbitration_id == 0x705:
                assert bytes(m.data) == b"\x00"
                break
        else:
            pytest.fail("no boot-up from node 5 after NMT reset")
    finally:
        bus.shutdown()


def test_eds_export_generic(eds_path):
    require_command("eds", "export")
    r = _EXPORT.get("result")
    assert r is not None and r.returncode == 0, f"`drivebus eds export --profile generic` failed: {r and r.stderr}"
    exported = canopen.import_od(str(eds_path), 5)
    shipped = canopen.import_od(str(EDS_DIR / "generic.eds"), 5)
    assert sorted(exported.indices) == sorted(shipped.indices)
    for index in (0x1000, 0x1008, 0x1018, 0x1A00, 0x6502):
        a, b = exported[index], shipped[index]
        if hasattr(a, "subindices"):
            assert {s: v.default for s, v in a.subindices.items()} == {s: v.default for s, v in b.subindices.items()}
        else:
            assert a.default == b.default


def test_has_command_helper_sees_the_cli():
    """Guards the skip logic: if `serve` vanished from --help, every serve test
    would skip; this one fails instead."""
    assert has_command("serve"), "drivebus --help does not list `serve`"


@pytest.mark.limit(60)
def test_bitrate_paces_the_bus(serve, networks, eds_path):
    """`--bitrate 125000`: an expedited SDO is two 8-byte frames of at least
    111 bits each, so 100 of them need at least 0.178 s; unpaced they take a
    fraction of that."""
    from conftest import remote_node

    srv = serve("generic:5", bitrate=125_000)
    node = remote_node(networks(*srv), 5, eds_path)
    node.sdo.upload(0x1000, 0)
    t0 = time.perf_counter()
    for _ in range(100):
        node.sdo.upload(0x1000, 0)
    paced = time.perf_counter() - t0
    min_s = 100 * 2 * 111 / 125_000
    assert paced >= 0.95 * min_s, f"100 SDOs in {paced * 1000:.0f} ms at 125 kbit/s: not paced (>= {min_s * 1000:.0f} ms)"
    assert paced < 20 * min_s, f"100 SDOs in {paced * 1000:.0f} ms at 125 kbit/s: far too slow"
