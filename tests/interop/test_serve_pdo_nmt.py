"""canopen 2.4.1's PDO, NMT, heartbeat and EMCY consumers against
`drivebus serve` over socketcand."""

from __future__ import annotations

import threading
import time

import pytest

NODE = 5
NMT_STATE = {0x00: "INITIALISING", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}


def wait_until(pred, timeout: float, step: float = 0.02):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(step)
    return pred()


def nmt_and_bootup(node, command: str, timeout: float = 3.0) -> None:
    """Sends an NMT reset and waits for the boot-up message; the listener is
    in place before the command goes out, so a fast boot-up is not missed."""
    booted = threading.Event()
    cb = lambda st: st == 0 and booted.set()  # noqa: E731
    node.nmt.add_heartbeat_callback(cb)
    try:
        node.nmt.state = command
        assert booted.wait(timeout), f"no boot-up within {timeout} s of NMT {command}"
    finally:
        node.nmt._callbacks.remove(cb)


def heartbeats(node, n: int, timeout: float = 3.0) -> list[str]:
    return [node.nmt.wait_for_heartbeat(timeout=timeout) for _ in range(n)]


def test_tpdo_read_matches_eds(node):
    node.tpdo.read()
    node.rpdo.read()
    od = node.object_dictionary
    for n in (1, 2, 3, 4):
        comm, mapping = od[0x1800 + n - 1], od[0x1A00 + n - 1]
        tp = node.tpdo[n]
        want = [mapping[s].default for s in range(1, mapping[0].default + 1)]
        got = [(v.index << 16) | (v.subindex << 8) | v.length for v in tp.map]
        assert got == want, f"TPDO{n} mapping"
        assert tp.cob_id == (0x180 + 0x100 * (n - 1) + NODE), f"TPDO{n} COB-ID"
        assert tp.trans_type == comm[2].default, f"TPDO{n} transmission type"
    assert 0x6041 in [v.index for v in node.tpdo[1].map], "statusword not in TPDO1"
    assert 0x6040 in [v.index for v in node.rpdo[1].map], "controlword not in RPDO1"


@pytest.mark.limit(40)
def test_tpdo_remap_save_and_receive(node):
    node.nmt.state = "PRE-OPERATIONAL"
    node.tpdo.read()
    tp = node.tpdo[1]
    tp.clear()
    tp.add_variable(0x6041)  # statusword, 16 bits
    tp.add_variable(0x6064)  # position actual value, 32 bits
    tp.trans_type = 255
    tp.event_timer = 20
    tp.enabled = True
    tp.save()

    # what the drive holds now, read back over SDO
    assert node.sdo[0x1A00][0].raw == 2
    assert node.sdo[0x1A00][1].raw == 0x60410010
    assert node.sdo[0x1A00][2].raw == 0x60640020
    assert node.sdo[0x1800][2].raw == 255
    assert node.sdo[0x1800][5].raw == 20
    assert node.sdo[0x1800][1].raw & 0x8000_07FF == 0x180 + NODE  # valid, our COB-ID

    stamps = []
    tp.add_callback(lambda m: stamps.append(time.monotonic()))
    node.nmt.state = "OPERATIONAL"
    assert tp.wait_for_reception(timeout=2.0) is not None, "no TPDO1 after NMT start"
    assert wait_until(lambda: len(stamps) >= 10, 3.0), f"only {len(stamps)} TPDO1 in 3 s with a 20 ms event timer"
    period = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
    assert 0.005 < period < 0.2, f"TPDO1 period {period * 1000:.1f} ms, event timer 20 ms"
    assert len(tp.data) == 6
    sw = tp[0x6041].raw
    assert sw == node.sdo[0x6041].raw or sw & 0x6F == node.sdo[0x6041].raw & 0x6F
    assert tp[0x6064].raw == pytest.approx(node.sdo[0x6064].raw, abs=1000)

    # stopped: no PDOs; pre-operational: no PDOs
    node.nmt.state = "STOPPED"
    time.sleep(0.1)
    n = len(stamps)
    time.sleep(0.3)
    assert len(stamps) == n, "TPDOs sent in STOPPED"


@pytest.mark.limit(30)
def test_rpdo_controlword_write(node):
    node.rpdo.read()
    rp = node.rpdo[1]
    assert rp.enabled and 0x6040 in [v.index for v in rp.map]
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    assert node.sdo[0x6041].raw & 0x4F == 0x40, "drive not in SWITCH ON DISABLED after boot"
    rp[0x6040].raw = 0x0006  # shutdown → READY TO SWITCH ON
    rp.transmit()
    assert wait_until(lambda: node.sdo[0x6040].raw == 0x0006, 1.0), "RPDO controlword not applied"
    assert wait_until(lambda: node.sdo[0x6041].raw & 0x6F == 0x21, 1.0), f"statusword {node.sdo[0x6041].raw:04X}"
    # an RPDO in PRE-OPERATIONAL is ignored (CiA 301)
    node.nmt.state = "PRE-OPERATIONAL"
    time.sleep(0.05)
    rp[0x6040].raw = 0x0000
    rp.transmit()
    time.sleep(0.2)
    assert node.sdo[0x6040].raw == 0x0006, "RPDO processed in PRE-OPERATIONAL"


@pytest.mark.limit(30)
def test_heartbeat_and_nmt_states(node):
    node.sdo[0x1017].raw = 50
    assert node.nmt.wait_for_heartbeat(timeout=2.0) == "PRE-OPERATIONAL"
    stamps = []
    node.nmt.add_heartbeat_callback(lambda st: stamps.append(time.monotonic()))
    assert wait_until(lambda: len(stamps) >= 6, 2.0)
    period = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
    assert 0.025 < period < 0.15, f"heartbeat period {period * 1000:.1f} ms, 1017h = 50 ms"

    for cmd, want in [
        ("OPERATIONAL", "OPERATIONAL"),
        ("STOPPED", "STOPPED"),
        ("PRE-OPERATIONAL", "PRE-OPERATIONAL"),
        ("OPERATIONAL", "OPERATIONAL"),
    ]:
        node.nmt.state = cmd
        # the first heartbeat may predate the command: take the second
        assert heartbeats(node, 2)[-1] == want, f"after NMT {cmd}"

    # reset communication: boot-up, then pre-operational; 1017h is kept (communication
    # parameters are reset to their stored/default values: default 0 → no heartbeat)
    nmt_and_bootup(node, "RESET COMMUNICATION")
    assert node.nmt.state == "PRE-OPERATIONAL"
    assert node.sdo[0x1017].raw == 0
    node.sdo[0x1017].raw = 50
    assert node.nmt.wait_for_heartbeat(timeout=2.0) == "PRE-OPERATIONAL"

    # reset node: boot-up again
    nmt_and_bootup(node, "RESET")
    assert node.sdo[0x1000].raw  # answering SDO after the reset


@pytest.mark.limit(30)
def test_bootup_heartbeat_state_via_broadcast(served, networks, eds_path):
    from conftest import remote_node

    net = networks(*served)
    node = remote_node(net, NODE, eds_path)
    node.sdo[0x1017].raw = 40
    net.nmt.state = "OPERATIONAL"  # broadcast, node-ID 0
    assert heartbeats(node, 2)[-1] == "OPERATIONAL"
    net.nmt.state = "PRE-OPERATIONAL"
    assert heartbeats(node, 2)[-1] == "PRE-OPERATIONAL"


@pytest.mark.limit(30)
def test_emcy_on_rpdo_length_error(node):
    got = []
    node.emcy.add_callback(got.append)
    node.rpdo.read()
    rp = node.rpdo[1]
    assert rp.enabled and rp.length >= 16
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    # RPDO1 maps at least 16 bits; one byte is a length error → EMCY 8210h
    node.network.send_message(rp.cob_id, b"\x06")
    # canopen's emcy.wait() sees only an EMCY that arrives after it is
    # called; the node may answer before that, so the callback's list is
    # polled instead.
    deadline = time.monotonic() + 2.0
    e = None
    while e is None and time.monotonic() < deadline:
        e = next((x for x in got if x.code == 0x8210), None)
        time.sleep(0.01)
    assert e is not None, f"no EMCY 8210h; got {[hex(x.code) for x in got]}"
    assert e.register & 0x01, f"error register {e.register:02X}: generic error bit not set"
    assert e.register & 0x10, f"error register {e.register:02X}: communication error bit not set"
    assert len(e.data) == 5  # canopen unpacks exactly 8 bytes: code, register, 5 bytes
    assert got and got[0].code == 0x8210, "callback not called"
    # a correct RPDO afterwards is processed
    rp[0x6040].raw = 0x0006
    rp.transmit()
    assert wait_until(lambda: node.sdo[0x6040].raw == 0x0006, 1.0)
