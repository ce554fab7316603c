"""The pytest plugin (entry point `pytest11`): its fixtures and marker,
used here as any project's tests would use them after `pip install`."""

from __future__ import annotations

from importlib.metadata import entry_points

import can
import canopen
import pytest

import drivebus


def test_the_plugin_is_registered_as_a_pytest11_entry_point():
    eps = entry_points()
    group = eps.select(group="pytest11") if hasattr(eps, "select") else eps.get("pytest11", [])
    assert any(ep.value == "drivebus.pytest_plugin" for ep in group)


@pytest.mark.drivebus(drives=["akd:1", "dds6:2"])
def test_drivebus_bus_hosts_the_marked_drives(drivebus_bus, akd_eds):
    assert isinstance(drivebus_bus, can.BusABC)
    assert [(d.profile, d.node) for d in drivebus_bus.drives] == [("akd", 1), ("dds6", 2)]
    network = canopen.Network(drivebus_bus)
    network.connect()  # the bus is already open: only the notifier starts
    try:
        node = network.add_node(1, akd_eds)
        node.sdo.RESPONSE_TIMEOUT = 1.0
        assert node.sdo[0x1018][1].raw == node.object_dictionary[0x1018][1].default
    finally:
        network.notifier.stop()


def test_drivebus_bus_without_a_marker_has_no_drives(drivebus_bus):
    assert drivebus_bus.drives == []


@pytest.mark.drivebus("dds6:2")
def test_drivebus_socketcand_serves_the_marked_drives(drivebus_socketcand):
    assert drivebus_socketcand.url == f"socketcand://127.0.0.1:{drivebus_socketcand.port}/can0"
    assert [(d.profile, d.node) for d in drivebus_socketcand.drives] == [("dds6", 2)]
    bus = can.Bus(interface="socketcand", host="127.0.0.1", port=drivebus_socketcand.port, channel="can0")
    try:
        bus.send(can.Message(arbitration_id=0x602, data=[0x40, 0x18, 0x10, 1, 0, 0, 0, 0], is_extended_id=False))
        reply = None
        for _ in range(50):
            m = bus.recv(0.1)
            if m is not None and m.arbitration_id == 0x582:
                reply = m
                break
        assert reply is not None and reply.data[0] == 0x43
    finally:
        bus.shutdown()


@pytest.mark.drivebus(drives=["akd:1"], bitrate=500_000)
def test_drivebus_sim_with_the_master(drivebus_sim):
    m = drivebus_sim.master()
    assert [n["node"] for n in m.scan()] == [1]
    m.drive(1).enable()
    assert drivebus_sim.drives[0].state == "operation enabled"


def test_fixtures_in_a_fresh_pytest_run(pytester):
    """A project's own test file, with nothing but `pip install`: the
    plugin loads by itself, the port is closed after the test."""
    pytester.makepyfile(
        """
        import socket
        import pytest

        PORTS = []

        @pytest.mark.drivebus(drives=["akd:1"])
        def test_served(drivebus_socketcand, drivebus_sim, drivebus_bus):
            PORTS.append(drivebus_socketcand.port)
            assert drivebus_sim.master().sdo_read(1, "identity/vendor-id") > 0
            assert drivebus_bus.drives[0].node == 1

        def test_closed_after():
            with socket.socket() as s:
                assert s.connect_ex(("127.0.0.1", PORTS[0])) != 0
        """
    )
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--strict-markers")
    result.assert_outcomes(passed=2)


def test_a_wrong_marker_says_what_it_takes(pytester):
    pytester.makepyfile(
        """
        import pytest

        @pytest.mark.drivebus(drive=["akd:1"])
        def test_typo(drivebus_sim):
            pass
        """
    )
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*unknown argument(s) ?'drive'? (drives, machine, bitrate)*"])
