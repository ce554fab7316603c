"""canopen 2.4.1 (over python-can's socketcand interface) sees the CAN
faults of `drivebus serve --control` (docs/control.md) and recovers from
them (issue 17 §3): a node's bus-off with automatic recovery, its power cut
and restored, and SDO responses lost or corrupted by a rule.

The faults are requested with `drivebus control --connect ADDR …`, as a
test script beside a master would.
"""

from __future__ import annotations

import threading
import time

import canopen
import pytest

from conftest import LOCALHOST, SDO_TIMEOUT, free_port, remote_node, run_cli

NODE = 5
HEARTBEAT_MS = 20
# Paced at 10 kbit/s, a controller's automatic bus-off recovery (128 × 11
# recessive bits, ISO 11898-1) takes 140.8 ms: seven heartbeat periods, a
# silence the heartbeat consumer cannot miss.
BITRATE = 10_000
RECOVERY_S = 128 * 11 / BITRATE


def control(addr: str, *args) -> None:
    r = run_cli("control", "--connect", addr, *args)
    assert r.returncode == 0 and r.stdout == "ok\n", f"drivebus control {' '.join(map(str, args))}: {r.stderr}"


class Heartbeats:
    """canopen's heartbeat consumer (`NmtMaster.add_heartbeat_callback`)
    with the arrival time of each heartbeat: (time.monotonic(), state)."""

    def __init__(self, node):
        self.seen: list[tuple[float, int]] = []
        self.lock = threading.Lock()
        node.nmt.add_heartbeat_callback(self._on)

    def _on(self, state: int) -> None:
        with self.lock:
            self.seen.append((time.monotonic(), state))

    def since(self, t: float) -> list[tuple[float, int]]:
        with self.lock:
            return [h for h in self.seen if h[0] >= t]

    def wait(self, pred, timeout: float) -> tuple[float, int] | None:
        """The first heartbeat from now on whose state satisfies `pred`."""
        start, end = time.monotonic(), time.monotonic() + timeout
        while time.monotonic() < end:
            for h in self.since(start):
                if pred(h[1]):
                    return h
            time.sleep(0.005)
        return None


@pytest.fixture
def ctl(serve, networks, eds_path):
    """(control address, canopen RemoteNode 5) on `drivebus serve --drive
    generic:5 --control 127.0.0.1:PORT` paced at 10 kbit/s."""
    addr = f"{LOCALHOST}:{free_port()}"
    served = serve("generic:5", bitrate=BITRATE, extra=("--control", addr))
    node = remote_node(networks(*served), NODE, eds_path)
    return addr, node


def _heartbeat_on(node) -> None:
    node.sdo[0x1017].raw = HEARTBEAT_MS
    node.nmt.wait_for_heartbeat(timeout=2)


@pytest.mark.limit(60)
def test_bus_off_with_recovery_seen_by_heartbeat_and_emcy_consumers(ctl):
    addr, node = ctl
    _heartbeat_on(node)
    node.nmt.state = "OPERATIONAL"
    beats = Heartbeats(node)
    assert beats.wait(lambda s: s == 0x05, 2), "no heartbeat in OPERATIONAL"
    emcys: list[tuple[float, canopen.emcy.EmcyError]] = []
    node.emcy.add_callback(lambda e: emcys.append((time.monotonic(), e)))

    before = time.monotonic()
    control(addr, "bus", "off", str(NODE), "--recover")
    # The heartbeat consumer sees the node go silent, then come back in
    # PRE-OPERATIONAL (1029h sub 1, default: operational → pre-operational).
    back = beats.wait(lambda s: s == 0x7F, 3)
    assert back, f"no heartbeat after the recovery: {beats.since(before)}"
    times = [before] + [t for t, _ in beats.since(before) if t <= back[0]]
    gap = max(b - a for a, b in zip(times, times[1:]))
    assert gap >= 0.7 * RECOVERY_S, f"no silence: longest gap {gap * 1000:.0f} ms (recovery {RECOVERY_S * 1000:.0f} ms)"
    assert node.nmt.state == "PRE-OPERATIONAL"

    # The EMCY consumer: 8140h "recovered from bus off" with 1001h bit 4
    # (communication) and bit 0, then the error reset that empties `active`.
    deadline = time.monotonic() + 2
    while len(emcys) < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert [e.code for _, e in emcys] == [0x8140, 0x0000], [str(e) for _, e in emcys]
    recovered, reset = emcys[0][1], emcys[1][1]
    assert recovered.register & 0x11 == 0x11, f"1001h in the EMCY: {recovered.register:02X}h"
    assert reset.register == 0x00
    assert node.emcy.active == []
    assert emcys[0][0] > before + 0.7 * RECOVERY_S, "the EMCY came before the recovery"

    # The master recovers: SDO works, 1001h is clear again, and NMT start
    # brings the node back to OPERATIONAL.
    assert node.sdo[0x1000].raw == 0x0002_0192
    assert node.sdo[0x1001].raw == 0x00
    node.nmt.state = "OPERATIONAL"
    assert beats.wait(lambda s: s == 0x05, 2), "not OPERATIONAL again"


@pytest.mark.limit(60)
def test_power_off_and_on_seen_as_silence_and_boot_up(ctl):
    addr, node = ctl
    _heartbeat_on(node)
    # Volatile changes that a power cycle must forget.
    node.sdo[0x6060].raw = 1  # profile position (power-on: 0)
    assert node.sdo[0x6060].raw == 1
    beats = Heartbeats(node)

    control(addr, "power", str(NODE), "off")
    off = time.monotonic()
    time.sleep(0.5)
    # (A heartbeat already on its way may still arrive just after.)
    assert beats.since(off + 0.2) == [], "heartbeats from a node without power"
    with pytest.raises(canopen.SdoCommunicationError):
        node.sdo[0x1000].raw

    booted = threading.Event()
    boot_cb = lambda s: s == 0 and booted.set()  # noqa: E731
    node.nmt.add_heartbeat_callback(boot_cb)
    control(addr, "power", str(NODE), "on")
    assert booted.wait(3), "no boot-up message after power on"
    assert node.nmt.state == "PRE-OPERATIONAL"
    # Power-on values: no heartbeat (1017h = 0), mode 0, 1001h clear.
    assert node.sdo[0x1017].raw == 0
    assert node.sdo[0x6060].raw == 0
    assert node.sdo[0x1001].raw == 0
    assert node.sdo[0x1000].raw == 0x0002_0192
    # And it is managed as before.
    _heartbeat_on(node)
    node.nmt.state = "OPERATIONAL"
    assert beats.wait(lambda s: s == 0x05, 2), "not OPERATIONAL after the power cycle"


@pytest.mark.limit(60)
def test_dropped_sdo_responses_time_out_then_the_client_succeeds(ctl):
    addr, node = ctl
    # canopen's default: one request per transfer step, no retry on a timeout.
    assert node.sdo.MAX_RETRIES == 1
    assert node.sdo[0x1000].raw == 0x0002_0192
    # Two responses lost: the first upload times out (and the client
    # aborts it); with a retry allowed, the second loses its first
    # response and gets the retry's.
    control(addr, "bus", "drop", "--id", "0x585", "--count", "2")
    t0 = time.monotonic()
    with pytest.raises(canopen.SdoCommunicationError):
        node.sdo[0x1018][1].raw
    assert time.monotonic() - t0 >= 0.9 * SDO_TIMEOUT, "failed before its response timeout"
    node.sdo.MAX_RETRIES = 2
    t0 = time.monotonic()
    assert node.sdo[0x1018][1].raw == node.object_dictionary[0x1018][1].default
    assert time.monotonic() - t0 >= 0.9 * SDO_TIMEOUT, "the first request of the retried upload was answered"
    # The count is used up: every request is answered at once.
    node.sdo.MAX_RETRIES = 1
    for _ in range(5):
        assert node.sdo[0x1000].raw == 0x0002_0192
    # A rule without a count lasts until `bus clear`.
    control(addr, "bus", "drop", "--id", "0x585")
    for _ in range(2):
        with pytest.raises(canopen.SdoCommunicationError):
            node.sdo[0x1000].raw
    control(addr, "bus", "clear")
    assert node.sdo[0x1000].raw == 0x0002_0192


@pytest.mark.limit(60)
def test_corrupted_sdo_responses_are_refused_or_read_then_the_client_succeeds(ctl):
    addr, node = ctl
    assert node.sdo[0x1000].raw == 0x0002_0192
    # The index in the next response is flipped (the CRC is assumed to
    # miss it): canopen sees an answer for another object and refuses it.
    control(addr, "bus", "corrupt", "--id", "0x585", "--mask", "00FF", "--count", "1")
    with pytest.raises(canopen.SdoCommunicationError, match="Node returned a value for"):
        node.sdo[0x1000].raw
    assert node.sdo[0x1000].raw == 0x0002_0192
    # A bit of the data flipped: no client can tell; the value read is off
    # by exactly that bit, and the next read is right again.
    control(addr, "bus", "corrupt", "--id", "0x585", "--mask", "0000000001", "--count", "1")
    assert node.sdo[0x1000].raw == 0x0002_0192 ^ 0x01
    for _ in range(3):
        assert node.sdo[0x1000].raw == 0x0002_0192
