"""The EtherCAT demo's line from Python: an emulated iPOS and the
`drivebus` master (ethercrab) in one process, in simulated time.

Scan, OP with DC SYNC0 at 1 ms, enable, homing (method 35), a
profile-position move of two turns and a 1 s CSP sine of half a turn, as
`drivebus demo --ethercat` runs them; prints what the process data showed.

    python python/examples/ethercat_simulation.py
"""

import math

import drivebus.ethercat


def main() -> None:
    line = drivebus.ethercat.Simulation(drives=["ipos"])
    (slave,) = line.scan()
    print(f"slave 1: {slave['name']} vendor {slave['vendor_id']:#x} product {slave['product_code']:#x}")
    line.start(cycle=0.001)
    print(f"OP, DC SYNC0: {line.dc}")
    line.enable()
    home = line.home(35)
    print(f"homed at {home}")
    position = line.move_to(4000, velocity=200_000)
    print(f"moved to {position}")
    base = position
    targets = [round(base + 1000 * (1 - math.cos(2 * math.pi * k / 1000))) for k in range(1000)]
    line.csp(targets)
    line.cycle(100)
    worst = max(abs(f) for (_, _, _, f) in line.log()[-1100:] if f is not None)
    cycles, bad, _ = line.counters()
    line.stop()
    print(f"csp: {len(targets)} cycles, |following error| <= {worst}; {cycles} cycles, {bad} bad working counters")
    print(f"simulated {line.now:.3f} s, {len(line.capture() or b'')} bytes of pcapng")


if __name__ == "__main__":
    main()
