"""A profile-position move on an AKD with canopen's BaseNode402, unmodified,
against an AKD twin hosted in this process (`interface="drivebus"`): the
same recipe as the repository README's over `drivebus serve`, with no
server and no port.

    python python/examples/akd_profile_position.py
"""

from __future__ import annotations

import time
from pathlib import Path

import canopen

AKD_EDS = Path(__file__).resolve().parents[2] / "crates" / "personality" / "eds" / "akd.eds"


def move(target: int = 90_000, channel: str = "akd-example") -> int:
    """Homes the AKD on its current position, moves it to ``target`` in
    profile position mode and returns the position it reports."""
    network = canopen.Network()
    network.connect(interface="drivebus", channel=channel, drives=["akd:1"])
    try:
        drive = canopen.BaseNode402(1, str(AKD_EDS))
        network.add_node(drive)
        drive.sdo.RESPONSE_TIMEOUT = 1.0
        drive.nmt.state = "PRE-OPERATIONAL"  # setup_pdos asserts a known NMT state
        drive.tpdo.read()
        drive.rpdo.read()
        for n in (2, 3, 4):  # one PDO per object: the others off
            drive.tpdo[n].enabled = False
            drive.rpdo[n].enabled = False
        drive.tpdo[1].clear()
        drive.tpdo[1].add_variable(0x6041)  # statusword
        drive.tpdo[1].add_variable(0x6061)  # modes of operation display
        drive.tpdo[1].trans_type = 255
        drive.tpdo[1].event_timer = 20  # periodic: canopen waits for the next one
        drive.tpdo[1].enabled = True
        drive.rpdo[1].clear()
        drive.rpdo[1].add_variable(0x6040)  # controlword
        drive.rpdo[1].add_variable(0x6060)  # modes of operation
        drive.rpdo[1].trans_type = 255
        drive.rpdo[1].enabled = True
        drive.tpdo.save()
        drive.rpdo.save()
        drive.setup_402_state_machine(read_pdos=True)
        drive.nmt.state = "OPERATIONAL"
        drive.tpdo[1].wait_for_reception(timeout=2.0)

        def wait_for(bits: int, timeout: float = 10.0) -> None:
            end = time.monotonic() + timeout
            while drive.statusword & bits != bits:
                if time.monotonic() > end:
                    raise TimeoutError(f"statusword {drive.statusword:04X}h")
                drive.tpdo[1].wait_for_reception(timeout=0.1)

        drive.state = "OPERATION ENABLED"
        drive.sdo[0x6098].raw = 35  # homing on the current position
        assert drive.homing(timeout=10)
        drive.op_mode = "PROFILED POSITION"
        drive.sdo[0x6081].raw = 360_000  # the AKD starts at 10 units/s
        drive.sdo[0x607A].raw = target
        drive.controlword = 0x2F  # enable operation, change set immediately
        drive.controlword = 0x3F  # new set-point
        wait_for(0x1000)  # set-point acknowledge
        drive.controlword = 0x2F
        wait_for(0x0400)  # target reached
        return drive.sdo[0x6064].raw
    finally:
        network.disconnect()


if __name__ == "__main__":
    print("position", move())
