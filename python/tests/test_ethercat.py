"""`drivebus.ethercat.serve`: the EtherCAT slave line of `drivebus
ethercat serve` in the process, and the `drivebus_ethercat` fixture (the
line in a network namespace on a veth pair), each met by pysoem."""

from __future__ import annotations

import os
import subprocess
import time

import pytest

import drivebus
import drivebus.ethercat

pysoem = pytest.importorskip("pysoem")


def _ip(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", *args], capture_output=True, text=True, timeout=20)


@pytest.fixture
def veth():
    """A veth pair in this namespace: (the master's end, the line's end)."""
    if os.geteuid() != 0:
        pytest.skip(f"needs root for a veth pair and AF_PACKET (euid {os.geteuid()})")
    a, b = f"dbv{os.getpid() % 100_000}a", f"dbv{os.getpid() % 100_000}b"
    r = _ip("link", "add", a, "type", "veth", "peer", "name", b)
    if r.returncode != 0:
        pytest.skip(f"`ip link add {a} type veth` failed: {r.stderr.strip()}")
    try:
        for end in (a, b):
            # No IPv6 chatter on the line.
            subprocess.run(["sysctl", "-q", "-w", f"net.ipv6.conf.{end}.disable_ipv6=1"], capture_output=True)
            assert _ip("link", "set", end, "up").returncode == 0
        yield a, b
    finally:
        _ip("link", "del", a)


def test_serve_in_process_is_found_by_pysoem(veth):
    master_end, line_end = veth
    with drivebus.ethercat.serve(line_end, drives=["ipos", "generic"]) as server:
        assert server.drives == ["ipos", "generic"] and server.iface == line_end
        m = pysoem.Master()
        m.open(master_end)
        try:
            assert m.config_init() == 2
            ipos, generic = m.slaves
            assert ipos.man == 0x1A3
            assert generic.name == "drivebus generic CiA 402 servo"
            assert int.from_bytes(ipos.sdo_read(0x1000, 0), "little") == 0x0006_0192
        finally:
            m.close()
    assert server.closed
    # Closed: nobody answers any more.
    m = pysoem.Master()
    m.open(master_end)
    try:
        assert m.config_init() <= 0
    finally:
        m.close()


def test_bad_lines_raise_the_cli_messages():
    with pytest.raises(ValueError, match="akd"):
        drivebus.ethercat.serve("lo", drives=["akd"])
    with pytest.raises(ValueError, match="at least one drive"):
        drivebus.ethercat.serve("lo", drives=[])
    with pytest.raises(OSError, match="cannot open an AF_PACKET socket on nosuch0"):
        drivebus.ethercat.serve("nosuch0", drives=["ipos"])


@pytest.mark.drivebus(drives=["ipos", "generic"])
def test_the_fixture_serves_the_line_in_a_namespace(drivebus_ethercat):
    assert drivebus_ethercat.drives == ["ipos", "generic"]
    ns = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    assert drivebus_ethercat.namespace in ns
    m = pysoem.Master()
    m.open(drivebus_ethercat.iface)
    try:
        assert m.config_init() == 2
        assert [s.man for s in m.slaves][0] == 0x1A3
    finally:
        m.close()


def test_inputs_faults_and_power_of_the_line(veth):
    master_end, line_end = veth
    with drivebus.ethercat.serve(line_end, drives=["generic"]) as server:
        m = pysoem.Master()
        m.open(master_end)
        try:
            assert m.config_init() == 1
            (generic,) = m.slaves
            di = lambda: int.from_bytes(generic.sdo_read(0x60FD, 0), "little")  # noqa: E731
            assert di() & (1 << 18) == 0
            server.input(1, "digital", 1, line=3)  # generic: line n is 60FDh bit 15 + n
            deadline = time.monotonic() + 2
            while di() & (1 << 18) == 0 and time.monotonic() < deadline:
                time.sleep(0.01)
            assert di() & (1 << 18)
            with pytest.raises(ValueError, match=r"^no slave 2 on the line: use 1..1"):
                server.fault(2, "encoder")
            with pytest.raises(ValueError, match="^fault: "):
                server.fault(1, "encodr")
            server.power(1, False)
            with pytest.raises(OSError, match="slave 1 is powered off"):
                server.input(1, "digital", 0, line=3)
            assert m.config_init() <= 0
            server.power(1, True)
            assert m.config_init() == 1
        finally:
            m.close()
