"""Frames per second a python-can client sends and receives through
`interface="drivebus"` (drivebus's in-process virtual bus), beside
python-can's own `interface="virtual"`, measured the same way in one run
(issue 18: target >= 20 000 frames/s each way on one core).

Two buses of one interface on one channel: the client sends a batch of
frames on the first (timed: send), then receives them on the second
(timed: receive), until `--frames` frames went through; every frame must
arrive, in order. Batches keep the receiver within drivebus's per-receiver
buffer (8192 frames).

    python python/bench/throughput.py --frames 200000
"""

from __future__ import annotations

import argparse
import time
from typing import Dict

import can

BATCH = 1000


def measure(interface: str, frames: int) -> Dict[str, float]:
    """Send and receive rates (frames/s) of `frames` frames through `interface`."""
    channel = f"bench-{interface}"
    tx = can.Bus(interface=interface, channel=channel)
    rx = can.Bus(interface=interface, channel=channel)
    try:
        msgs = [can.Message(arbitration_id=0x181 + (i % 64), data=i.to_bytes(8, "little"), is_extended_id=False) for i in range(BATCH)]
        sent = received = 0
        t_send = t_recv = 0.0
        while sent < frames:
            n = min(BATCH, frames - sent)
            t0 = time.perf_counter()
            for m in msgs[:n]:
                tx.send(m)
            t1 = time.perf_counter()
            for i in range(n):
                m = rx.recv(timeout=5.0)
                if m is None:
                    raise RuntimeError(f"{interface}: frame {sent + i} did not arrive")
                if int.from_bytes(m.data, "little") != i:
                    raise RuntimeError(f"{interface}: frame {sent + i} out of order")
            t2 = time.perf_counter()
            t_send += t1 - t0
            t_recv += t2 - t1
            sent += n
            received += n
        return {"send": sent / t_send, "receive": received / t_recv}
    finally:
        tx.shutdown()
        rx.shutdown()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=200_000, help="frames per interface (default 200000)")
    a = p.parse_args()
    print(f"{'interface':<10} {'send frames/s':>14} {'receive frames/s':>17}")
    for interface in ("drivebus", "virtual"):
        r = measure(interface, a.frames)
        print(f"{interface:<10} {r['send']:>14,.0f} {r['receive']:>17,.0f}")


if __name__ == "__main__":
    main()
