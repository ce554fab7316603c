"""`drivebus.serve()`: drive twins on a socketcand server in this process,
reached by unmodified python-can (`interface="socketcand"`) and canopen."""

from __future__ import annotations

import socket

import can
import canopen
import pytest

import drivebus


def _connects(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(1.0)
        return s.connect_ex(("127.0.0.1", port)) == 0


def test_canopen_reads_identity_over_socketcand(akd_eds):
    with drivebus.serve(drives=["akd:1"]) as server:
        assert server.url == f"socketcand://127.0.0.1:{server.port}/can0"
        assert [(d.profile, d.node) for d in server.drives] == [("akd", 1)]
        network = canopen.Network()
        network.connect(interface="socketcand", host="127.0.0.1", port=server.port, channel="can0")
        try:
            node = canopen.RemoteNode(1, akd_eds)
            network.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 2.0
            vendor = node.sdo[0x1018][1].raw
            assert vendor == node.object_dictionary[0x1018][1].default != 0
        finally:
            network.disconnect()
        port = server.port
        assert _connects(port)
    assert server.closed
    # The port is closed when the `with` block has ended.
    assert not _connects(port)
    with pytest.raises(OSError, match="closed"):
        server.drives


def test_python_can_sees_boot_up_after_nmt_reset():
    with drivebus.serve("dds6:2") as server:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=server.port, channel="can0")
        try:
            bus.send(can.Message(arbitration_id=0x000, data=[0x81, 2], is_extended_id=False))
            got = None
            for _ in range(50):
                m = bus.recv(0.1)
                if m is not None and m.arbitration_id == 0x702:
                    got = m
                    break
            assert got is not None and bytes(got.data) == b"\x00"
        finally:
            bus.shutdown()


def test_two_servers_get_different_free_ports():
    with drivebus.serve(["akd:1"]) as a, drivebus.serve(["akd:1"]) as b:
        assert a.port != b.port
        assert a.port > 0 and b.port > 0


def test_bad_arguments_raise_with_the_cli_messages():
    with pytest.raises(ValueError, match="node-ID `0` is not in 1..127"):
        drivebus.serve(["akd:0"])
    with pytest.raises(ValueError, match="bad --channel `can 0`"):
        drivebus.serve(["akd:1"], channel="can 0")
    with drivebus.serve(["akd:1"]) as taken:
        with pytest.raises(OSError, match=f"cannot listen on 127.0.0.1:{taken.port}"):
            drivebus.serve(["akd:1"], port=taken.port)


def test_close_twice_is_harmless():
    server = drivebus.serve(["akd:1"])
    server.close()
    server.close()
    assert server.closed
