"""1010h store / 1011h restore through canopen's RemoteNode.store() and
restore(), across restarts of `drivebus serve --state-dir`."""

from __future__ import annotations

import threading

import pytest

from conftest import remote_node

NODE = 5


def reset_node(node, timeout: float = 3.0) -> None:
    booted = threading.Event()
    cb = lambda st: st == 0 and booted.set()  # noqa: E731
    node.nmt.add_heartbeat_callback(cb)
    try:
        node.nmt.state = "RESET"
        assert booted.wait(timeout), "no boot-up after NMT reset node"
    finally:
        node.nmt._callbacks.remove(cb)


@pytest.mark.limit(90)
def test_store_survives_restart_and_restore_brings_defaults(serve, networks, eds_path, tmp_path):
    state = tmp_path / "state"
    s1 = serve("generic:5", state_dir=state)
    net = networks(*s1)
    node = remote_node(net, NODE, eds_path)
    assert node.sdo[0x1010][1].raw & 0x1, "1010h:1 does not announce save on command"
    hb0, acc0 = node.sdo[0x1017].raw, node.sdo[0x6083].raw
    hb1, acc1 = hb0 + 321, acc0 + 1234
    node.sdo[0x1017].raw = hb1  # communication parameter
    node.sdo[0x6083].raw = acc1  # application parameter (profile acceleration)
    node.store()
    net.disconnect()
    s1.stop()
    assert state.exists() and any(p.is_file() for p in state.rglob("*")), "nothing written under --state-dir"

    s2 = serve("generic:5", state_dir=state)
    net = networks(*s2)
    node = remote_node(net, NODE, eds_path)
    assert node.sdo[0x1017].raw == hb1, "1017h not restored from --state-dir after restart"
    assert node.sdo[0x6083].raw == acc1, "6083h not restored from --state-dir after restart"
    # a reset node also loads the stored values (not the defaults)
    reset_node(node)
    assert node.sdo[0x1017].raw == hb1
    assert node.sdo[0x6083].raw == acc1

    node.restore()  # 1011h:1 = "load"
    reset_node(node)
    assert node.sdo[0x1017].raw == hb0, "1017h not back to its default after restore + reset node"
    assert node.sdo[0x6083].raw == acc0, "6083h not back to its default after restore + reset node"
    net.disconnect()
    s2.stop()

    # and the defaults stay after another restart
    s3 = serve("generic:5", state_dir=state)
    node = remote_node(networks(*s3), NODE, eds_path)
    assert (node.sdo[0x1017].raw, node.sdo[0x6083].raw) == (hb0, acc0)


@pytest.mark.limit(60)
def test_without_state_dir_nothing_survives(serve, networks, eds_path):
    s1 = serve("generic:5")
    node = remote_node(networks(*s1), NODE, eds_path)
    hb0 = node.sdo[0x1017].raw
    node.sdo[0x1017].raw = hb0 + 5
    node.store()  # accepted (kept in memory) ...
    reset_node(node)
    assert node.sdo[0x1017].raw == hb0 + 5  # ... and used at reset node
    node.network.disconnect()
    s1.stop()
    s2 = serve("generic:5")
    node = remote_node(networks(*s2), NODE, eds_path)
    assert node.sdo[0x1017].raw == hb0  # a new process without --state-dir starts from defaults


def test_store_with_bad_signature_aborts(node):
    from canopen.sdo.exceptions import SdoAbortedError

    with pytest.raises(SdoAbortedError) as e:
        node.sdo.download(0x1010, 1, b"nope")
    # CiA 301 §7.5.2.13: wrong signature → "data cannot be transferred or stored"
    assert e.value.code == 0x08000020, f"{e.value.code:08X}"
