"""Run-time changes as methods of the hosted drives (`bus.drives[i].fault()`,
`.set_input()`, `.power()`, ...): the same calls as the bus's, simulation's
and server's own `fault(node, ...)`, on the drive they were read from."""

from __future__ import annotations

import time

import can
import canopen
import pytest

import drivebus
from conftest import EDS_DIR

NODE = 5
# generic: digital input line n is 60FDh bit 15 + n.
LINE3 = 1 << 18


def _until(cond, timeout: float = 2.0):
    end = time.monotonic() + timeout
    while True:
        got = cond()
        if got or time.monotonic() > end:
            return got
        time.sleep(0.01)


def test_simulation_drive_methods_input_fault_clear_and_power():
    sim = drivebus.Simulation(drives=["akd:1", f"generic:{NODE}"])
    m = sim.master()
    (akd, drive) = sim.drives
    assert (drive.node, drive.profile, drive.state) == (NODE, "generic", "switch on disabled")
    drive.set_input("digital", 1, line=3, duration=0.5)
    sim.advance(0.005)
    assert m.sdo_read(NODE, 0x60FD) & LINE3
    # Only that drive: node 1 took no input.
    assert akd.refresh().state == "switch on disabled"
    d = m.drive(NODE)
    d.enable()
    drive.fault("encoder")
    sim.advance(0.05)
    # The object is the state when read; refresh() reads it again.
    assert drive.state == "switch on disabled"
    assert drive.refresh().state == "fault"
    drive.clear_fault()
    sim.advance(0.02)
    d.enable()
    assert drive.refresh().state == "operation enabled"
    drive.power(False)
    assert [s.node for s in sim.drives] == [1]
    with pytest.raises(OSError, match="powered off"):
        drive.refresh()
    with pytest.raises(OSError, match="powered off"):
        drive.fault("encoder")
    drive.power(True)
    sim.advance(0.05)
    assert drive.refresh().nmt == "pre-operational"
    drive.bus_off()
    with pytest.raises(drivebus.SdoError, match="timed out"):
        m.sdo_read(NODE, 0x1000)
    drive.bus_on()
    assert m.sdo_read(NODE, 0x1000) == 0x0002_0192


def test_python_can_bus_drive_methods(channel):
    with can.Bus(interface="drivebus", channel=channel, drives=[f"generic:{NODE}"]) as bus:
        net = canopen.Network()
        net.connect(interface="drivebus", channel=channel)
        try:
            node = net.add_node(NODE, str(EDS_DIR / "generic.eds"))
            (drive,) = bus.drives
            assert node.sdo[0x60FD].raw & LINE3 == 0
            drive.set_input("digital", 1, line=3)
            assert _until(lambda: node.sdo[0x60FD].raw & LINE3)
            for cw in (0x06, 0x07, 0x0F):
                node.sdo[0x6040].raw = cw
            assert _until(lambda: node.sdo[0x6041].raw & 0x6F == 0x27)
            drive.fault("encoder")
            assert _until(lambda: drive.refresh().state == "fault")
            drive.clear_fault()
            time.sleep(0.05)
            node.sdo[0x6040].raw = 0x80
            assert _until(lambda: drive.refresh().state == "switch on disabled")
            drive.power(False)
            assert bus.drives == []
            drive.power(True)
            assert _until(lambda: bus.drives and bus.drives[0].nmt == "pre-operational")
        finally:
            net.disconnect()
    with pytest.raises(OSError, match="closed"):
        drive.bus_off()


def test_server_drive_methods():
    with drivebus.serve(drives=[f"generic:{NODE}"]) as server:
        (drive,) = server.drives
        drive.power(False)
        assert server.drives == []
        drive.power(True)
        assert _until(lambda: [d.node for d in server.drives] == [NODE])
    with pytest.raises(OSError, match="closed"):
        drive.fault("encoder")


def test_drive_method_bad_arguments_raise_the_control_messages():
    sim = drivebus.Simulation(drives=[f"generic:{NODE}"])
    (drive,) = sim.drives
    with pytest.raises(ValueError, match="^fault: .*encodr"):
        drive.fault("encodr")
    with pytest.raises(ValueError, match="^input: "):
        drive.set_input("no_such_input", 1)
    with pytest.raises(ValueError, match="line"):
        drive.set_input("digital", 1, line=17)
    with pytest.raises(ValueError, match="duration"):
        drive.fault("encoder", duration=-1)
