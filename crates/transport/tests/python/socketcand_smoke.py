#!/usr/bin/env python3
"""Smoke test of the drivebus socketcand server with python-can (4.6.1).

Usage: socketcand_smoke.py HOST PORT [CHANNEL] [--responder] [--slcan PTY]

Needs a running server, e.g.
    cargo run -p drivebus-transport --example vbus -- --responder --pty
Two python-can socketcand clients join the bus:
  * A sends a standard frame, a DLC-0 frame (SYNC, the two-space case) and
    an extended frame; B receives exactly those, A receives none (no echo).
  * B sends a frame; A receives it. A sends a burst of 500; B gets all, in order.
  * With --responder: A sends 0x605 and receives the toy responder's 0x585
    (a frame from an in-process participant of the hub).
  * With --slcan PTY: a python-can slcan client on the emulator's pty
    exchanges frames (RTR included) with A.
Exits 0 and prints "smoke: ok" on success.
"""
import sys
import time

import can


def recv(bus, what, timeout=3.0):
    msg = bus.recv(timeout)
    if msg is None:
        sys.exit(f"smoke: FAILED: no frame received ({what})")
    return msg


def expect(msg, arb_id, data, extended=False, remote=False):
    got = (msg.arbitration_id, bytes(msg.data) if not msg.is_remote_frame else b"", msg.is_extended_id, msg.is_remote_frame)
    want = (arb_id, bytes(data), extended, remote)
    if got != want:
        sys.exit(f"smoke: FAILED: got {got}, want {want}")


def quiet(bus, what, timeout=0.2):
    msg = bus.recv(timeout)
    if msg is not None:
        sys.exit(f"smoke: FAILED: unexpected {msg} ({what})")


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    host, port = args[0], int(args[1])
    channel = args[2] if len(args) > 2 and not args[2].startswith("--") else "can0"
    responder = "--responder" in args
    slcan_path = args[args.index("--slcan") + 1] if "--slcan" in args else None

    a = can.Bus(interface="socketcand", host=host, port=port, channel=channel)
    b = can.Bus(interface="socketcand", host=host, port=port, channel=channel)
    time.sleep(0.1)  # past the server's rawmode grace
    try:
        a.send(can.Message(arbitration_id=0x181, data=[1, 2, 3], is_extended_id=False))
        a.send(can.Message(arbitration_id=0x080, data=[], is_extended_id=False))
        a.send(can.Message(arbitration_id=0x18FF50E5, data=[0xAB], is_extended_id=True))
        expect(recv(b, "standard"), 0x181, [1, 2, 3])
        expect(recv(b, "dlc 0"), 0x080, [])
        expect(recv(b, "extended"), 0x18FF50E5, [0xAB], extended=True)
        quiet(a, "echo of own frames")

        b.send(can.Message(arbitration_id=0x7FF, data=[0xFF] * 8, is_extended_id=False))
        expect(recv(a, "from b"), 0x7FF, [0xFF] * 8)

        # A burst: python-can's Nagle-coalesced sends and straddled reads.
        for i in range(500):
            a.send(can.Message(arbitration_id=0x300, data=i.to_bytes(2, "little"), is_extended_id=False))
        for i in range(500):
            expect(recv(b, f"burst frame {i}"), 0x300, i.to_bytes(2, "little"))

        if responder:
            a.send(can.Message(arbitration_id=0x605, data=[0x40, 0x00, 0x10, 0, 0, 0, 0, 0], is_extended_id=False))
            expect(recv(a, "responder"), 0x585, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0])
            expect(recv(b, "request seen by b"), 0x605, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0])
            expect(recv(b, "response seen by b"), 0x585, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0])

        if slcan_path:
            s = can.Bus(interface="slcan", channel=slcan_path, bitrate=500000)
            try:
                time.sleep(0.1)
                s.send(can.Message(arbitration_id=0x705, is_remote_frame=True, dlc=1, is_extended_id=False))
                s.send(can.Message(arbitration_id=0x080, data=[], is_extended_id=False))
                # RTR cannot cross socketcand: A sees only the SYNC.
                expect(recv(a, "slcan sync"), 0x080, [])
                a.send(can.Message(arbitration_id=0x1ABCDEF, data=[1, 2], is_extended_id=True))
                expect(recv(s, "socketcand -> slcan"), 0x1ABCDEF, [1, 2], extended=True)
            finally:
                s.shutdown()
    finally:
        a.shutdown()
        b.shutdown()
    print("smoke: ok")


if __name__ == "__main__":
    main()
