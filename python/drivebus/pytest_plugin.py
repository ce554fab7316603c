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
"""

from __future__ import annotations

import itertools
from typing import Any, Dict, Iterator

import pytest

import drivebus

_channels = itertools.count()

_MARKER = (
    "drivebus(drives=[...], machine=None, bitrate=1000000): the drive twins "
    "(PROFILE:NODE) and machine file of the drivebus_bus, drivebus_socketcand "
    "and drivebus_sim fixtures"
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
