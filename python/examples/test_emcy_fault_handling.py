"""An EMCY / fault-handling test of one's own master code, with the pytest
plugin's `drivebus_bus` fixture: a generic CiA 402 twin is driven into a
following-error fault, and the code under test (`FaultWatcher`, standing in
for your master) must see the EMCY, report it and bring the drive back.

    pytest python/examples/test_emcy_fault_handling.py
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import List, Tuple

import canopen
import pytest

GENERIC_EDS = Path(__file__).resolve().parents[2] / "crates" / "personality" / "eds" / "generic.eds"
NODE = 5


class FaultWatcher:
    """The code under test: records every EMCY of its drive and clears a
    fault once the cause is gone (what your master would do)."""

    def __init__(self, drive: canopen.BaseNode402) -> None:
        self.drive = drive
        self.seen: List[Tuple[int, int]] = []
        drive.emcy.add_callback(lambda e: self.seen.append((e.code, e.register)))

    def wait_for_fault(self, timeout: float = 5.0) -> int:
        """The error code (603Fh) once the drive is in FAULT."""
        end = time.monotonic() + timeout
        while not self.drive.is_faulted():
            if time.monotonic() > end:
                raise TimeoutError(f"no fault: statusword {self.drive.statusword:04X}h")
            self.drive.check_statusword(timeout=0.5)
        return self.drive.sdo[0x603F].raw

    def recover(self) -> None:
        self.drive.reset_from_fault()


@pytest.fixture
def drive(drivebus_bus) -> canopen.BaseNode402:
    """BaseNode402 on the fixture's bus: TPDO1 statusword + mode display
    every 20 ms, RPDO1 controlword + mode, operational."""
    network = canopen.Network(drivebus_bus)
    network.connect()  # the bus is open already: starts canopen's notifier
    d = canopen.BaseNode402(NODE, str(GENERIC_EDS))
    network.add_node(d)
    d.sdo.RESPONSE_TIMEOUT = 1.0
    d.nmt.state = "PRE-OPERATIONAL"
    d.tpdo.read()
    d.rpdo.read()
    for n in (2, 3, 4):
        d.tpdo[n].enabled = False
        d.rpdo[n].enabled = False
    d.tpdo[1].clear()
    d.tpdo[1].add_variable(0x6041)
    d.tpdo[1].add_variable(0x6061)
    d.tpdo[1].trans_type = 255
    d.tpdo[1].event_timer = 20
    d.tpdo[1].enabled = True
    d.rpdo[1].clear()
    d.rpdo[1].add_variable(0x6040)
    d.rpdo[1].add_variable(0x6060)
    d.rpdo[1].trans_type = 255
    d.rpdo[1].enabled = True
    d.tpdo.save()
    d.rpdo.save()
    d.setup_402_state_machine(read_pdos=True)
    d.nmt.state = "OPERATIONAL"
    d.tpdo[1].wait_for_reception(timeout=2.0)
    yield d
    network.notifier.stop()


@pytest.mark.drivebus(drives=[f"generic:{NODE}"])
def test_following_error_is_reported_and_recovered(drive, drivebus_bus):
    watcher = FaultWatcher(drive)
    window = drive.sdo[0x6065].raw
    drive.op_mode = "PROFILED POSITION"
    drive.state = "OPERATION ENABLED"
    # A following-error window of 0 with no tolerance time: any lag during
    # a move is a following error (EMCY 8611h), and the drive faults.
    drive.sdo[0x6065].raw = 0
    drive.sdo[0x6066].raw = 0
    drive.sdo[0x607A].raw = 10_000_000
    drive.controlword = 0x000F
    drive.controlword = 0x003F

    assert watcher.wait_for_fault() == 0x8611
    end = time.monotonic() + 2.0
    while not any(code == 0x8611 for code, _ in watcher.seen) and time.monotonic() < end:
        time.sleep(0.01)
    code, register = next((c, r) for c, r in watcher.seen if c == 0x8611)
    assert register & 0x21 == 0x21  # generic error + device profile specific
    assert drivebus_bus.drives[0].state == "fault"

    drive.sdo[0x6065].raw = window  # the cause gone
    watcher.recover()
    assert drive.state == "OPERATION ENABLED"
    assert drivebus_bus.drives[0].state == "operation enabled"
    # The fault reset sends EMCY 0000h (error reset).
    end = time.monotonic() + 2.0
    while not any(c == 0 for c, _ in watcher.seen) and time.monotonic() < end:
        time.sleep(0.01)
    assert watcher.seen[-1][0] == 0x0000
