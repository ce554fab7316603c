"""Drive twins in simulated time: deterministic frame logs."""

from __future__ import annotations

import pytest

import drivebus


def script() -> drivebus.Simulation:
    """Boot, an SDO upload of 1018h:1..4 from each drive, NMT start, and
    half a second of operational bus traffic."""
    sim = drivebus.Simulation(drives=["akd:1", "dds6:2"], bitrate=1_000_000)
    sim.advance(0.1)
    for node in (1, 2):
        for sub in range(1, 5):
            sim.send(0x600 + node, bytes([0x40, 0x18, 0x10, sub, 0, 0, 0, 0]))
    sim.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes
    sim.advance(0.5)
    return sim


def test_two_runs_give_identical_logs():
    a, b = script(), script()
    assert a.log_lines() == b.log_lines()
    assert a.log() == b.log()
    assert len(a.log()) >= 2 + 8 + 8 + 1


def test_log_has_simulated_timestamps_in_bus_order():
    sim = script()
    log = sim.log()
    times = [e[0] for e in log]
    assert times == sorted(times)
    assert 0 < times[0] < 0.001  # a boot-up at 1 Mbit/s takes some microseconds
    assert {e[1] for e in log[:2]} == {0x701, 0x702}
    responses = [e for e in log if e[1] in (0x581, 0x582)]
    assert len(responses) == 8
    assert all(0.1 < e[0] < 0.11 for e in responses)
    assert all(e[5][0] == 0x43 for e in responses)  # expedited upload, 4 bytes
    assert sim.now == pytest.approx(0.6)
    assert sim.log_lines()[0].startswith("(0.0000")
    assert [(d.profile, d.nmt) for d in sim.drives] == [("akd", "operational"), ("dds6", "operational")]
    # The host's station heard the same frames, except its own.
    heard = [(f[0], f[4]) for f in sim.received()]
    assert heard == [(e[1], e[5]) for e in log if e[1] not in (0x000, 0x601, 0x602)]


def test_bad_arguments():
    with pytest.raises(ValueError, match="unknown profile `x`"):
        drivebus.Simulation(drives=["x:1"])
    with pytest.raises(ValueError, match="bitrate must be positive"):
        drivebus.Simulation(bitrate=0)
    with pytest.raises(OverflowError):
        drivebus.Simulation(bitrate=-1)
    sim = drivebus.Simulation(drives=["akd:1"], bitrate=None)
    for bad in (-1.0, float("nan"), float("inf"), 1e12):
        with pytest.raises(ValueError, match="seconds must be"):
            sim.advance(bad)
    with pytest.raises(ValueError, match="does not fit in 11 bits"):
        sim.send(0x800, b"")
    sim.advance(0.01)
    assert sim.log()[0][0] == 0.0  # no bitrate: frames take no time


def test_any_thread_may_use_a_simulation():
    import threading

    sim = drivebus.Simulation(drives=["akd:1"])
    errors = []

    def other():
        try:
            sim.advance(0.01)
        except BaseException as e:  # a PanicException is a BaseException
            errors.append(e)

    t = threading.Thread(target=other)
    t.start()
    t.join()
    assert errors == []
    assert sim.now == pytest.approx(0.01)
