"""drivebus: CANopen CiA 402 drive twins inside your Python process.

``VirtualBus(channel, drives)`` joins the in-process virtual CAN bus
``channel`` and hosts the drive twins ``drives`` (``"akd:1"``, the
``drivebus serve --drive`` syntax) on it in real time. With python-can
installed, the same is ``can.Bus(interface="drivebus", channel="virtual",
drives=["akd:1"])``; every bus of the process with the same channel shares
one virtual bus.

``serve(drives)`` hosts them on a socketcand server in this process on a
free loopback port instead (``with drivebus.serve(["akd:1"]) as s:
s.url``), for code that must use socketcand.

``Simulation(drives, bitrate)`` hosts the same twins on a virtual bus in
simulated time: ``advance(seconds)``, ``send``, ``run_until``, the frame
log with simulated timestamps, the same for the same calls, and
``master()``, the ``drivebus`` tool's master (scan, SDO by index or name,
NMT, CiA 402 enable / home / move, PDO configuration ``master.pdo``, LSS
``master.lss``, SYNC and a CSP stream ``drive(n).csp``) running in
simulated time; ``sim.frame_log()`` the log as columns for pandas or numpy,
``drivebus.plot(sim, node, object)`` an object over simulated time
(matplotlib). ``input``, ``fault``, ``bus_off``, ``bus_on``, ``power`` of a
bus or a simulation change the hosted drives at run time as ``drivebus
control`` does.
"""

import os
from typing import Optional, Sequence, Union

from ._drivebus import (
    PROFILES,
    Drive,
    DriveError,
    Lss,
    Pdos,
    DrivebusError,
    DriveState,
    Master,
    SdoError,
    Server,
    Simulation,
    VirtualBus,
)

__all__ = [
    "PROFILES",
    "Drive",
    "DriveError",
    "Lss",
    "Pdos",
    "DrivebusError",
    "DriveState",
    "Master",
    "SdoError",
    "Server",
    "Simulation",
    "VirtualBus",
    "plot",
    "serve",
]

from .plot import plot  # noqa: E402  (needs the classes above)


def serve(
    drives: Union[str, Sequence[str]] = (),
    machine: Optional[Union[str, "os.PathLike[str]"]] = None,
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    channel: str = "can0",
) -> Server:
    """Starts ``drives`` on a socketcand server in this process, as ``drivebus serve`` does.

    Use it as a context manager: the server listens on ``host``:``port``
    (default: a free loopback port) until the ``with`` block ends, then the
    drives stop and the port is closed::

        with drivebus.serve(drives=["akd:1"]) as server:
            bus = can.Bus(interface="socketcand", host="127.0.0.1",
                          port=server.port, channel="can0")

    ``server.url`` is ``socketcand://127.0.0.1:PORT/can0``, ``server.drives``
    the hosted drives' state.

    :raises ValueError: a bad drive spec, machine file or channel, with the CLI's message.
    :raises OSError: the address cannot be listened on.
    """
    if isinstance(drives, str):
        drives = [drives]
    return Server(list(drives), machine, host, port, channel)
