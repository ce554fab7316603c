"""The pytest plugin of drivebus (entry point ``pytest11``: it loads by
itself once the package is installed).

Fixtures, each configured by the marker
``@pytest.mark.drivebus(drives=["akd:1"], machine="machine.toml")``
(``drives`` as ``drivebus serve --drive`` takes them, default none;
``machine`` a machine file, default each profile's default machine):

- ``drivebus_bus``: a python-can bus (``interface="drivebus"``) on a virtual
  bus of the test's own, hosting the drives; shut down after the test.
- ``drivebus_socketcand``: the drives on a socketcand server in the process
  (``drivebus.serve``), on a free loopback port; ``.url``, ``.port``,
  ``.drives``; closed after the test.
- ``drivebus_sim``: a ``drivebus.Simulation`` of the drives (the marker may
  give ``bitrate=``), with ``.master()`` in simulated time.
- ``drivebus_ethercat``: an EtherCAT line of the marker's drives (profiles
  with an EtherCAT face, ``drives=["ipos"]`` by default) served by
  ``drivebus.ethercat`` inside a network namespace of its own, on one end
  of a veth pair; the test's master opens the other end, ``.iface``.
  Needs root (a namespace, AF_PACKET): elsewhere the test is skipped with
  the reason.
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from dataclasses import dataclass
from typing import Any, Dict, Iterator, List, Optional

import pytest

import drivebus

_channels = itertools.count()

_MARKER = (
    "drivebus(drives=[...], machine=None, bitrate=1000000): the drive twins "
    "(PROFILE:NODE; for drivebus_ethercat the line's profiles) and machine file "
    "of the drivebus_bus, drivebus_socketcand, drivebus_sim and drivebus_ethercat fixtures"
)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", _MARKER)


def _options(request: pytest.FixtureRequest) -> Dict[str, Any]:
    """The marker's arguments: ``drives`` (also as the first positional one), ``machine``, ``bitrate``."""
    marker = request.node.get_closest_marker("drivebus")
    if marker is None:
        return {"drives": [], "machine": None}
    kwargs = dict(marker.kwargs)
    if marker.args:
        if "drives" in kwargs or len(marker.args) > 1:
            raise TypeError("@pytest.mark.drivebus takes the drives once: drivebus(drives=[...], machine=...)")
        kwargs["drives"] = marker.args[0]
    unknown = set(kwargs) - {"drives", "machine", "bitrate"}
    if unknown:
        raise TypeError(f"@pytest.mark.drivebus: unknown argument(s) {sorted(unknown)} (drives, machine, bitrate)")
    drives = kwargs.get("drives", [])
    kwargs["drives"] = [drives] if isinstance(drives, str) else list(drives)
    kwargs.setdefault("machine", None)
    return kwargs


@pytest.fixture
def drivebus_bus(request: pytest.FixtureRequest) -> Iterator[Any]:
    """A python-can bus on a virtual bus of this test's own, hosting the marker's drives."""
    import can

    o = _options(request)
    channel = f"pytest-{next(_channels)}-{request.node.name}"
    bus = can.Bus(interface="drivebus", channel=channel, drives=o["drives"], machine=o["machine"])
    try:
        yield bus
    finally:
        bus.shutdown()


@pytest.fixture
def drivebus_socketcand(request: pytest.FixtureRequest) -> Iterator[drivebus.Server]:
    """The marker's drives on a socketcand server in this process, on a free loopback port."""
    o = _options(request)
    with drivebus.serve(drives=o["drives"], machine=o["machine"]) as server:
        yield server


@pytest.fixture
def drivebus_sim(request: pytest.FixtureRequest) -> drivebus.Simulation:
    """A simulation of the marker's drives in simulated time (``.master()``, ``.advance()``, ``.log()``)."""
    o = _options(request)
    return drivebus.Simulation(drives=o["drives"], bitrate=o.get("bitrate", 1_000_000), machine=o["machine"])


@dataclass
class EthercatLine:
    """The line of ``drivebus_ethercat``: the master's interface and the slaves."""

    iface: str
    """The veth end in this process's namespace, for the master (``pysoem.Master().open(iface)``)."""
    namespace: str
    """The network namespace the line is served in."""
    drives: List[str]
    """The slaves in line order (``["ipos"]``)."""


def _ip(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", *args], capture_output=True, text=True, timeout=20)


def _wire(ns: str, outer: str, inner: str) -> Optional[str]:
    """A namespace ``ns`` holding veth end ``inner``; ``outer`` stays here. Why not, or None."""
    if os.geteuid() != 0:
        return f"needs root for a network namespace and AF_PACKET (euid {os.geteuid()})"
    try:
        r = _ip("netns", "add", ns)
    except FileNotFoundError:
        return "no `ip` command (iproute2)"
    if r.returncode != 0:
        return f"`ip netns add {ns}` failed: {r.stderr.strip()}"
    for step in (
        ["link", "add", outer, "type", "veth", "peer", "name", inner],
        ["link", "set", inner, "netns", ns],
        ["link", "set", outer, "up"],
        ["netns", "exec", ns, "ip", "link", "set", inner, "up"],
    ):
        r = _ip(*step)
        if r.returncode != 0:
            return f"`ip {' '.join(step)}` failed: {r.stderr.strip()}"
    return None


@pytest.fixture
def drivebus_ethercat(request: pytest.FixtureRequest) -> Iterator[EthercatLine]:
    """An EtherCAT line of the marker's drives in a network namespace, reached over a veth pair."""
    marker = request.node.get_closest_marker("drivebus")
    drives: Any = ["ipos"]
    if marker is not None:
        drives = marker.kwargs.get("drives", marker.args[0] if marker.args else drives)
    drives = [drives] if isinstance(drives, str) else list(drives)
    tag = f"dbpy{os.getpid() % 100_000}x{next(_channels)}"
    ns, outer, inner = tag, f"{tag}a", f"{tag}b"
    why = _wire(ns, outer, inner)
    try:
        if why is not None:
            pytest.skip(f"drivebus_ethercat: {why}")
        proc = subprocess.Popen(
            ["ip", "netns", "exec", ns, sys.executable, "-m", "drivebus.ethercat", inner, *drives],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            ready = proc.stdout.readline() if proc.stdout else ""
            if not ready.startswith("drivebus.ethercat: ready"):
                err = proc.stderr.read() if proc.stderr and proc.wait(10) is not None else ""
                pytest.fail(f"drivebus.ethercat did not start on {inner} in {ns}: {ready}{err}")
            yield EthercatLine(iface=outer, namespace=ns, drives=drives)
        finally:
            if proc.stdin:
                proc.stdin.close()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
    finally:
        _ip("link", "del", outer)
        _ip("netns", "del", ns)
