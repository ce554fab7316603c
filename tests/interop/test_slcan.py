"""python-can's `slcan` interface (the code path of real USB-serial
adapters) on the pty of `drivebus slcan-pty`, with canopen on top."""

from __future__ import annotations

import threading
import time

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from conftest import SDO_TIMEOUT

NODE = 5


@pytest.fixture
def slcan_net(slcan_pty):
    pty = slcan_pty("generic:5")
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.1
    net.connect(interface="slcan", channel=pty.path, bitrate=500000, sleep_after_open=0.1)
    try:
        yield net
    finally:
        net.disconnect()


@pytest.fixture
def snode(slcan_net, eds_path):
    n = canopen.RemoteNode(NODE, str(eds_path))
    slcan_net.add_node(n)
    n.sdo.RESPONSE_TIMEOUT = max(SDO_TIMEOUT, 2.0)  # python-can reads slcan byte by byte
    return n


@pytest.mark.limit(60)
def test_slcan_sdo_expedited_and_segmented(snode):
    od = snode.object_dictionary
    assert snode.sdo[0x1000].raw == od[0x1000].default
    for sub in (1, 2, 3):
        assert snode.sdo[0x1018][sub].raw == od[0x1018][sub].default
    snode.sdo[0x1017].raw = 1234
    assert snode.sdo[0x1017].raw == 1234
    snode.sdo[0x1017].raw = 0
    name = snode.sdo[0x1008].raw
    assert name == od[0x1008].default and len(name) > 4
    payload = bytes(range(100))
    snode.sdo.download(0x1F50, 1, payload, force_segment=True)
    assert snode.sdo.upload(0x1F50, 1) == payload
    with pytest.raises(SdoAbortedError) as e:
        snode.sdo.upload(0x2FFF, 0)
    assert e.value.code == 0x06020000


@pytest.mark.limit(60)
def test_slcan_scan(slcan_net):
    slcan_net.scanner.search()
    end = time.monotonic() + 5.0
    while time.monotonic() < end and NODE not in slcan_net.scanner.nodes:
        time.sleep(0.05)
    assert slcan_net.scanner.nodes == [NODE]


@pytest.mark.limit(60)
def test_slcan_node_guarding_rtr(slcan_net, snode):
    """RTR crosses slcan (it cannot cross socketcand): the node answers each
    guarding request on 700h+N with its state and a toggling bit 7."""
    replies: list[bytes] = []
    got = threading.Event()

    def on_guard(can_id, data, ts):
        replies.append(bytes(data))
        if len(replies) >= 4:
            got.set()

    slcan_net.subscribe(0x700 + NODE, on_guard)
    for _ in range(4):
        n = len(replies)
        slcan_net.send_message(0x700 + NODE, None, remote=True)
        end = time.monotonic() + 2.0
        while len(replies) == n and time.monotonic() < end:
            time.sleep(0.01)
    assert got.wait(1.0), f"guarding replies: {[r.hex() for r in replies]}"
    assert all(len(r) == 1 for r in replies)
    assert {r[0] & 0x7F for r in replies} == {0x7F}, "state is not pre-operational"
    toggles = [r[0] >> 7 for r in replies]
    assert all(a != b for a, b in zip(toggles, toggles[1:])), f"toggle bit does not alternate: {toggles}"

    # canopen's guarding helper: periodic RTR; state follows NMT
    snode.nmt.state = "OPERATIONAL"
    snode.nmt.start_node_guarding(0.05)
    try:
        end = time.monotonic() + 3.0
        state = None
        while time.monotonic() < end:
            state = snode.nmt.wait_for_heartbeat(timeout=1.0)
            if state == "OPERATIONAL":
                break
        assert state == "OPERATIONAL"
    finally:
        snode.nmt.stop_node_guarding()
