"""How much faster than real time the simulated-time master runs the CAN
demo's scenario from Python (issue 18: target >= 100x).

The scenario of `drivebus demo` (crates/cli/src/demo.rs) through the
Python API: an AKD at node 1 and a DDS6 at node 2 on a 1 Mbit/s bus; scan,
the demo's PDOs (RPDO2 carries the CSP target on SYNC), NMT start, SYNC at
1 kHz, enable both, homing (index pulse 34, else 35 or 37), profile-position
moves (node 1 one turn at 720 000 units/s, node 2 20 000 units), a CSP sine
of `--sine-seconds` on node 1 (one target per SYNC), then SYNC off and NMT
pre-operational. Prints simulated seconds, wall seconds and their ratio.

    python python/bench/sim_demo.py
"""

from __future__ import annotations

import argparse
import math
import time

import drivebus


def home(d: drivebus.Drive) -> None:
    """Index pulse (34) where the drive has it, else the current position (35, 37), as the demo picks."""
    for method in (34, 35, 37):
        try:
            d.home(method)
            return
        except drivebus.SdoError:
            continue
    raise RuntimeError(f"node {d.node}: none of the homing methods 34, 35, 37")


def configure(m: drivebus.Master) -> None:
    """The demo's PDOs: controlword on RPDO1, controlword + 607Ah on SYNC
    (RPDO2), statusword + mode on TPDO1, position + velocity on SYNC
    (TPDO2), node 1's following error on SYNC (TPDO3); the other TPDOs off."""
    for node in (1, 2):
        m.pdo.map(node, "rpdo", 1, ["6040:0:16"], cob_id=0x200 + node, transmission=255)
        m.pdo.map(node, "rpdo", 2, ["6040:0:16", "607A:0:32"], cob_id=0x300 + node, transmission=1)
        m.pdo.map(node, "tpdo", 1, ["6041:0:16", "6061:0:8"], cob_id=0x180 + node, transmission=255)
        m.pdo.map(node, "tpdo", 2, ["6064:0:32", "606C:0:32"], cob_id=0x280 + node, transmission=1)
        last = 3
        if node == 1:
            m.pdo.map(node, "tpdo", 3, ["60F4:0:32"], cob_id=0x381, transmission=1)
            last = 4
        for num in range(last, 5):
            comm = 0x1800 + num - 1
            m.sdo_write(node, comm, 1, m.sdo_read(node, comm, 1) | 0x8000_0000)


def scenario(sine_seconds: float) -> drivebus.Simulation:
    sim = drivebus.Simulation(drives=["akd:1", "dds6:2"], bitrate=1_000_000)
    m = sim.master()
    assert [n["node"] for n in m.scan()] == [1, 2]
    configure(m)
    m.nmt(0, "start")
    m.start_sync(0.001)
    d1, d2 = m.drive(1), m.drive(2)
    d1.enable()
    d2.enable()
    for d in (d1, d2):
        home(d)
    d1.move_to(360_000, velocity=720_000, acceleration=3_600_000, timeout=20)
    d2.move_to(20_000, timeout=20)
    base = d1.position
    cycles = round(sine_seconds * 1000)
    targets = [round(base + 45_000 * (1 - math.cos(2 * math.pi * k / 1000))) for k in range(cycles)]
    assert d1.csp(targets) == cycles
    sim.advance(0.1)
    m.stop_sync()
    m.nmt(0, "preop")
    sim.advance(0.005)
    return sim


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sine-seconds", type=float, default=2.0, help="the CSP sine's length (the demo's default: 2)")
    a = p.parse_args()
    t0 = time.perf_counter()
    sim = scenario(a.sine_seconds)
    wall = time.perf_counter() - t0
    simulated = sim.now
    frames = len(sim.log())
    print(f"simulated {simulated:.3f} s in {wall:.3f} s wall: {simulated / wall:.0f}x real time ({frames} frames)")


if __name__ == "__main__":
    main()
