"""`drivebus.ethercat.Simulation`: the in-process EtherCAT line of `drivebus
demo --ethercat` with its master, from Python, in simulated time."""

from __future__ import annotations

import hashlib

import pytest

import drivebus
import drivebus.ethercat


def run_demo() -> drivebus.ethercat.Simulation:
    line = drivebus.ethercat.Simulation(drives=["ipos"])
    line.start()
    line.enable()
    line.home(35)
    line.move_to(2000, velocity=200_000)
    line.csp([2000 + k for k in range(200)])
    line.cycle(20)
    line.stop()
    return line


def test_scan_op_enable_move_and_csp_from_python():
    line = drivebus.ethercat.Simulation(drives=["ipos", "generic"])
    found = line.scan()
    assert [s["position"] for s in found] == [1, 2]
    assert all(s["coe_identity_matches"] for s in found), found
    t0 = line.now
    line.start(position=1, cycle=0.001)
    assert line.dc
    line.enable()
    sw, _, _ = line.cycle()
    assert sw & 0x6F == 0x27, hex(sw)  # operation enabled
    # Target reached: within the position window (6067h) of the target.
    assert abs(line.move_to(4000, velocity=200_000) - 4000) <= 10
    assert line.csp([4000 + 2 * k for k in range(100)]) == 100
    sw, position, following = line.cycle(10)
    assert abs(position - 4198) <= 3 and following is not None and abs(following) <= 3
    assert line.sdo_read(0x6064, 0) == position
    cycles, bad, lost = line.counters()
    assert cycles > 100 and bad == 0 and lost == 0
    # The log holds each cycle of move_to, csp and cycle, in simulated time.
    log = line.log()
    assert log[-1][2] == position
    times = [t for (t, _, _, _) in log]
    assert times == sorted(times) and times[-1] - times[0] >= 0.1
    assert line.now > t0
    line.stop()
    with pytest.raises(drivebus.DrivebusError, match="not in OP"):
        line.enable()


def test_two_runs_give_identical_logs_and_captures():
    a, b = run_demo(), run_demo()
    assert a.log() == b.log()
    ca, cb = a.capture(), b.capture()
    assert ca is not None and len(ca) > 10_000
    assert hashlib.sha256(ca).hexdigest() == hashlib.sha256(cb).hexdigest()


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="akd"):
        drivebus.ethercat.Simulation(drives=["akd"])
    with pytest.raises(ValueError, match="at least one"):
        drivebus.ethercat.Simulation(drives=[])
    line = drivebus.ethercat.Simulation(drives=["ipos"], capture=False)
    assert line.capture() is None
    with pytest.raises(drivebus.DrivebusError, match="not in OP"):
        line.home(35)
    with pytest.raises(ValueError, match="position"):
        line.start(position=2)
    with pytest.raises(ValueError, match="cycle"):
        line.start(cycle=float("nan"))
    with pytest.raises(ValueError, match="timeout"):
        line.start() or line.enable(timeout=-1.0)
    with pytest.raises(drivebus.DriveError):
        line.sdo_read(0x7FFF, 0)
