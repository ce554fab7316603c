"""EtherCAT from Python: the slave line of ``drivebus ethercat serve`` in
this process.

``serve(iface, drives=["ipos", "generic"])`` serves drive twins with an
EtherCAT face on the network interface ``iface`` (an AF_PACKET socket:
needs root or CAP_NET_RAW, like the CLI) until the ``with`` block ends, so
a pysoem test sets up and tears down its slaves in the test itself::

    with drivebus.ethercat.serve("veth1", drives=["ipos"]):
        master = pysoem.Master()
        master.open("veth0")
        master.config_init()

``python -m drivebus.ethercat IFACE DRIVE...`` does the same in a process
of its own (the pytest fixture ``drivebus_ethercat`` runs it inside a
network namespace): it prints ``drivebus.ethercat: ready on IFACE (line
DRIVE...)`` once the socket is open and serves until its standard input
closes.

``Simulation(drives=["ipos"])`` is the in-process line of ``drivebus demo
--ethercat`` with the same master (ethercrab), in simulated time: scan,
OP with DC SYNC0, enable, homing, profile-position moves and a CSP stream
from Python, the process data of every cycle in ``log()`` and every frame
in ``capture()`` (pcapng). It runs as fast as the CPU allows and the same
calls give the same log and capture, byte for byte::

    line = drivebus.ethercat.Simulation(drives=["ipos"])
    line.start()          # scan, PRE-OP -> OP, DC SYNC0 at 1 ms
    line.enable()
    line.home(35)
    line.move_to(4000, velocity=200_000)
"""

import argparse
import sys
from typing import List, Optional, Sequence, Union

from ._drivebus import EthercatServer
from ._drivebus import EthercatSimulation as Simulation

__all__ = ["EthercatServer", "Simulation", "serve", "main"]


def serve(iface: str, drives: Union[str, Sequence[str]] = ("ipos",)) -> EthercatServer:
    """Serves the line ``drives`` (``"ipos"``, ``"generic"``, in line order) on ``iface``.

    Use it as a context manager; the socket is bound when it returns, so a
    master's first frame is not lost.

    :raises ValueError: a profile without an EtherCAT face, with the CLI's message.
    :raises OSError: the AF_PACKET socket cannot be opened (not root, no such interface, interface down).
    """
    if isinstance(drives, str):
        drives = [drives]
    return EthercatServer(iface, list(drives))


def main(argv: Optional[List[str]] = None) -> int:
    """``python -m drivebus.ethercat IFACE DRIVE...``: serves until stdin closes."""
    p = argparse.ArgumentParser(prog="python -m drivebus.ethercat", description=main.__doc__)
    p.add_argument("iface")
    p.add_argument("drives", nargs="+")
    a = p.parse_args(argv)
    try:
        server = serve(a.iface, a.drives)
    except (ValueError, OSError) as e:
        print(f"drivebus.ethercat: {e}", file=sys.stderr)
        return 1
    with server:
        print(f"drivebus.ethercat: ready on {a.iface} (line {' '.join(server.drives)})", flush=True)
        sys.stdin.read()
    return 0


if __name__ == "__main__":
    sys.exit(main())
