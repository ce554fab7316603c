"""canopen 2.4.1's BaseNode402 (CiA 402 helper) against the generic virtual
drive of `drivebus serve`: PDO set-up, state machine, operating modes,
homing, fault and fault reset."""

from __future__ import annotations

import time

import canopen
import pytest

from conftest import remote_node

NODE = 5
SW_STATE_MASK = 0x6F


@pytest.fixture
def drive(network, eds_path) -> canopen.BaseNode402:
    """BaseNode402 5 with TPDO1 = statusword + mode display (event timer
    20 ms) and RPDO1 = controlword + mode, the other PDOs disabled: the set-up
    canopen's 402 helper needs (a periodic TPDO, one RPDO per object)."""
    d = remote_node(network, NODE, eds_path, cls=canopen.BaseNode402)
    d.nmt.state = "PRE-OPERATIONAL"  # setup_pdos asserts a known NMT state
    d.tpdo.read()
    d.rpdo.read()
    for n in (2, 3, 4):
        d.tpdo[n].enabled = False
        d.rpdo[n].enabled = False
    t = d.tpdo[1]
    t.clear()
    t.add_variable(0x6041)
    t.add_variable(0x6061)
    t.trans_type = 255
    t.event_timer = 20
    t.enabled = True
    r = d.rpdo[1]
    r.clear()
    r.add_variable(0x6040)
    r.add_variable(0x6060)
    r.trans_type = 255
    r.enabled = True
    d.tpdo.save()
    d.rpdo.save()
    d.setup_402_state_machine(read_pdos=True)
    d.nmt.state = "OPERATIONAL"
    assert d.tpdo[1].wait_for_reception(timeout=2.0) is not None, "no TPDO1 after NMT start"
    return d


def settle(d: canopen.BaseNode402, n: int = 3) -> None:
    """Lets a few periodic TPDOs arrive so the cache is current."""
    for _ in range(n):
        d.tpdo[1].wait_for_reception(timeout=1.0)


def sdo_state(d) -> int:
    return d.sdo[0x6041].raw & SW_STATE_MASK


@pytest.mark.limit(60)
def test_state_machine_walk(drive):
    settle(drive)
    assert drive.state == "SWITCH ON DISABLED", f"statusword {drive.statusword:04X} after boot"
    for target in ("READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED"):
        drive.state = target
        assert drive.state == target
    assert sdo_state(drive) == 0x27  # operation enabled, seen over SDO too
    # quick stop option 6: stop on the quick stop ramp and stay in QUICK STOP
    # ACTIVE (with 1..4 the drive passes on to SWITCH ON DISABLED at once)
    drive.sdo[0x605A].raw = 6
    drive.state = "QUICK STOP ACTIVE"
    assert drive.state == "QUICK STOP ACTIVE"
    assert sdo_state(drive) == 0x07
    drive.state = "SWITCH ON DISABLED"
    assert drive.state == "SWITCH ON DISABLED"
    drive.state = "OPERATION ENABLED"
    assert drive.state == "OPERATION ENABLED"
    drive.state = "SWITCH ON DISABLED"
    settle(drive)
    assert drive.state == "SWITCH ON DISABLED"
    assert sdo_state(drive) & 0x4F == 0x40


@pytest.mark.limit(60)
def test_op_mode_switch_and_back(drive):
    settle(drive)
    assert drive.is_op_mode_supported("PROFILED POSITION")
    assert drive.is_op_mode_supported("HOMING")
    assert drive.is_op_mode_supported("CYCLIC SYNCHRONOUS POSITION")
    drive.state = "OPERATION ENABLED"
    drive.op_mode = "PROFILED POSITION"  # logs and swallows its timeout: check below
    assert drive.op_mode == "PROFILED POSITION"
    assert drive.sdo[0x6061].raw == 1
    drive.op_mode = "PROFILED VELOCITY"
    assert drive.op_mode == "PROFILED VELOCITY"
    assert drive.sdo[0x6061].raw == 3
    drive.op_mode = "PROFILED POSITION"  # and back
    assert drive.op_mode == "PROFILED POSITION"
    assert drive.sdo[0x6061].raw == 1
    assert drive.state == "OPERATION ENABLED"
    drive.state = "SWITCH ON DISABLED"
    assert drive.state == "SWITCH ON DISABLED"


@pytest.mark.limit(90)
@pytest.mark.parametrize("method", [35, 37])
def test_homing_on_current_position(drive, method):
    settle(drive)
    drive.sdo[0x6098].raw = method
    assert drive.sdo[0x6098].raw == method
    assert drive.homing(timeout=10) is True
    assert drive.is_homed() is True
    assert drive.op_mode == "HOMING"
    assert drive.state == "OPERATION ENABLED"
    # statusword bits 10 (target reached) and 12 (homing attained)
    assert drive.statusword & 0x1400 == 0x1400
    drive.state = "SWITCH ON DISABLED"
    assert drive.state == "SWITCH ON DISABLED"


@pytest.mark.limit(90)
def test_fault_emcy_and_reset_from_fault(drive):
    settle(drive)
    window = drive.sdo[0x6065].raw
    drive.op_mode = "PROFILED POSITION"
    assert drive.op_mode == "PROFILED POSITION"
    drive.state = "OPERATION ENABLED"
    # a following-error window of 0 increments with no tolerance time: any
    # lag during a move is a following error (8611h) → FAULT
    drive.sdo[0x6065].raw = 0
    drive.sdo[0x6066].raw = 0
    drive.sdo[0x607A].raw = 10_000_000
    drive.controlword = 0x000F  # operation enabled, new set-point low
    drive.controlword = 0x003F  # new set-point, change immediately
    end = time.monotonic() + 5.0
    while not drive.is_faulted() and time.monotonic() < end:
        drive.check_statusword(timeout=1.0)
    assert drive.state == "FAULT", f"statusword {drive.statusword:04X}"
    e = drive.emcy.wait(0x8611, timeout=2.0) or next((x for x in drive.emcy.log if x.code == 0x8611), None)
    assert e is not None, f"no EMCY 8611h; got {[hex(x.code) for x in drive.emcy.log]}"
    assert e.register & 0x21 == 0x21, f"error register {e.register:02X}"
    assert drive.sdo[0x603F].raw == 0x8611
    assert 0x8611 in [x.code for x in drive.emcy.active]

    drive.sdo[0x6065].raw = window  # take the cause away
    drive.reset_from_fault()
    assert drive.state == "OPERATION ENABLED", f"statusword {drive.statusword:04X}"
    assert not drive.is_faulted()
    # the fault reset clears the error: an EMCY 0000h empties canopen's active list
    end = time.monotonic() + 2.0
    while drive.emcy.active and time.monotonic() < end:
        time.sleep(0.02)
    assert drive.emcy.active == [], [hex(x.code) for x in drive.emcy.active]
    drive.state = "SWITCH ON DISABLED"
    settle(drive)
    assert drive.state == "SWITCH ON DISABLED"
