"""`sim.master()`: the drivebus tool's master on a `Simulation`'s bus, in
simulated time (scan, SDO by index and name, NMT, CiA 402 enable / home /
move), and `sim.run_until`."""

from __future__ import annotations

import time

import canopen
import pytest

import drivebus


def test_scan_finds_the_hosted_drives_with_their_identity(akd_eds):
    sim = drivebus.Simulation(drives=["akd:1", "dds6:2"])
    found = sim.master().scan()
    assert [n["node"] for n in found] == [1, 2]
    od = canopen.import_od(akd_eds, 1)
    assert found[0]["vendor_id"] == od[0x1018][1].default != 0
    assert found[0]["product_code"] == od[0x1018][2].default
    assert found[0]["device_type"] == od[0x1000].default
    # Absent nodes cost the 100 ms probe timeout, in simulated time.
    assert 0.1 <= sim.now < 1.0


def test_sdo_by_index_and_by_name_agree():
    sim = drivebus.Simulation(drives=["akd:1"])
    m = sim.master()
    assert m.sdo_read(1, "statusword") == m.sdo_read(1, 0x6041, 0) == m.sdo_read(1, "6041:00")
    assert m.sdo_read(1, "identity/vendor-id") == m.sdo_read(1, 0x1018, 1)
    ident = m.sdo_read(1, 0x1018)
    assert ident[0] == 4 and ident[1] == m.sdo_read(1, 0x1018, 1)
    m.sdo_write(1, "modes of operation", 1)
    assert m.sdo_read(1, 0x6060) == 1
    m.sdo_write(1, 0x6081, 0, 1234)
    assert m.sdo_read(1, "profile velocity") == 1234
    # A name of the AKD's own EDS.
    m.sdo_write(1, 0x1017, 0, 100)
    assert m.sdo_read(1, "1017") == 100


def test_sdo_errors_carry_the_cli_messages():
    sim = drivebus.Simulation(drives=["akd:1"])
    m = sim.master()
    with pytest.raises(drivebus.SdoError, match=r"^node 1: SDO read 1234h:00 aborted by the device with code 0x06020000: "):
        m.sdo_read(1, 0x1234)
    with pytest.raises(drivebus.SdoError, match=r"^node 5: SDO read 1000h:00 timed out: no response within 500 ms"):
        m.sdo_read(5, 0x1000)
    with pytest.raises(drivebus.SdoError, match=r"^node 1: SDO write 1000h:00 aborted"):
        m.sdo_write(1, 0x1000, 0, 5)
    assert issubclass(drivebus.SdoError, drivebus.DrivebusError)
    with pytest.raises(ValueError, match="is not an object: write the index in hex"):
        m.sdo_read(1, "no such object")
    with pytest.raises(ValueError, match="names one entry already; drop the sub-index"):
        m.sdo_read(1, "statusword", 1)
    with pytest.raises(ValueError, match="bad value `abc`"):
        m.sdo_write(1, "controlword", "abc")
    with pytest.raises(ValueError, match="give OBJECT \\[SUB\\] VALUE"):
        m.sdo_write(1, "controlword")
    with pytest.raises(ValueError, match="node-ID `0` is not in 1..127"):
        m.sdo_read(0, 0x1000)
    with pytest.raises(ValueError, match="unknown type `u7`"):
        m.sdo_read(1, 0x1000, type="u7")


def test_nmt_commands_reach_the_drives():
    sim = drivebus.Simulation(drives=["akd:1", "dds6:2"])
    m = sim.master()
    m.nmt(1, "start")
    assert [d.nmt for d in sim.drives] == ["operational", "pre-operational"]
    m.nmt(0, "stop")
    assert [d.nmt for d in sim.drives] == ["stopped", "stopped"]
    m.nmt(2, "reset")
    assert [d.nmt for d in sim.drives] == ["stopped", "pre-operational"]
    with pytest.raises(ValueError, match="invalid NMT command `go`"):
        m.nmt(1, "go")


def test_a_move_of_a_second_runs_in_far_less_wall_time():
    sim = drivebus.Simulation(drives=["akd:1"])
    drive = sim.master().drive(1)
    drive.enable()
    assert drive.state == "operation enabled"
    assert sim.drives[0].state == "operation enabled"
    start, wall = sim.now, time.perf_counter()
    # 2000 units at 2000 units/s with steep ramps: just over 1 s of motion.
    report = drive.move_to(2000, velocity=2000, acceleration=100_000)
    wall = time.perf_counter() - wall
    assert report["end"] == "target_reached"
    assert report["position"] == report["target"] == 2000
    assert 1.0 <= report["duration"] <= sim.now - start
    assert drive.position == 2000
    assert sim.master().sdo_read(1, "position actual value") == 2000
    assert sim.drives[0].position == 2000
    assert wall < report["duration"] / 4, (wall, report)


def test_a_move_that_cannot_finish_raises_drive_error():
    sim = drivebus.Simulation(drives=["akd:1"])
    drive = sim.master().drive(1)
    drive.enable()
    with pytest.raises(drivebus.DriveError, match=r"^node 1: timeout waiting for target reached"):
        drive.move_to(10_000, velocity=10, acceleration=100_000, timeout=2.0)
    assert 2.0 <= sim.now < 5.0


def test_homing_on_the_current_position():
    sim = drivebus.Simulation(drives=["akd:1"])
    drive = sim.master().drive(1)
    drive.enable()
    drive.move_to(500, velocity=5000, acceleration=100_000)
    report = drive.home(method=35)
    assert report["end"] == "homing_attained"
    assert drive.position == 0


def test_run_until_returns_the_simulated_time_or_names_it_in_timeout_error():
    sim = drivebus.Simulation(drives=["akd:1"])
    m = sim.master()
    m.nmt(1, "start")
    m.drive(1).enable()
    m.sdo_write(1, "modes of operation", 1)
    m.sdo_write(1, "profile velocity", 1000)
    m.sdo_write(1, "profile acceleration", 100_000)
    m.sdo_write(1, "profile deceleration", 100_000)
    m.sdo_write(1, "target position", 300)
    m.sdo_write(1, "controlword", 0x1F)
    t0 = sim.now
    t = sim.run_until(lambda: sim.drives[0].position >= 300, timeout=5.0)
    assert 0.25 < t - t0 < 1.0 and sim.now == t
    with pytest.raises(TimeoutError, match=r"after 0\.5 s of simulated time \(simulated time \d+\.\d+ s\)"):
        sim.run_until(lambda: sim.drives[0].position < 0, timeout=0.5)
    assert sim.now == pytest.approx(t + 0.5, abs=1e-6)
    with pytest.raises(ValueError, match="timeout must be"):
        sim.run_until(lambda: True, timeout=-1)


def _script() -> list:
    sim = drivebus.Simulation(drives=["akd:1", "dds6:2"])
    m = sim.master()
    m.scan()
    m.nmt(0, "start")
    m.sdo_read(2, "identity")
    d = m.drive(1)
    d.enable()
    d.move_to(1500, velocity=3000, acceleration=50_000)
    m.nmt(2, "reset")
    sim.advance(0.1)
    return sim.log_lines()


def test_the_same_master_script_gives_a_byte_identical_log():
    first, second = _script(), _script()
    assert len(first) > 300
    assert "\n".join(first).encode() == "\n".join(second).encode()
    # The master's frames are in it: SDO requests to node 1 (601h).
    assert any(" 601#" in line for line in first)
