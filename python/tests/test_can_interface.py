"""Unmodified python-can 4.6.1 and canopen 2.4.1 against drive twins hosted
in this process through `interface="drivebus"`."""

from __future__ import annotations

import time

import can
import canopen
import pytest


def test_entry_point_and_drives(channel):
    bus = can.Bus(interface="drivebus", channel=channel, drives=["akd:1", "dds6:2"])
    try:
        states = bus.drives
        assert [(s.profile, s.node) for s in states] == [("akd", 1), ("dds6", 2)]
        for s in states:
            assert s.nmt == "pre-operational", s
            assert s.state == "switch on disabled", s
    finally:
        bus.shutdown()


def test_sdo_read_and_nmt_with_canopen(channel, akd_eds):
    network = canopen.Network()
    network.connect(interface="drivebus", channel=channel, drives=["akd:1", "dds6:2"])
    try:
        node = canopen.BaseNode402(1, akd_eds)
        network.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 1.0
        vendor = node.sdo[0x1018][1].raw
        assert vendor == node.object_dictionary[0x1018][1].default != 0
        assert node.sdo[0x1000].raw == node.object_dictionary[0x1000].default
        node.nmt.state = "OPERATIONAL"
        end = time.monotonic() + 2.0
        while network.bus.drives[0].nmt != "operational" and time.monotonic() < end:
            time.sleep(0.01)
        akd, dds6 = network.bus.drives
        assert akd.nmt == "operational"
        assert dds6.nmt == "pre-operational"  # addressed to node 1 only
    finally:
        network.disconnect()


def test_profile_position_move_on_the_akd(channel, akd_eds):
    """The README's BaseNode402 recipe, unmodified but for the connect line."""
    network = canopen.Network()
    network.connect(interface="drivebus", channel=channel, drives=["akd:1"])
    try:
        drive = canopen.BaseNode402(1, akd_eds)
        network.add_node(drive)
        drive.sdo.RESPONSE_TIMEOUT = 1.0

        drive.nmt.state = "PRE-OPERATIONAL"
        drive.tpdo.read()
        drive.rpdo.read()
        for n in (2, 3, 4):
            drive.tpdo[n].enabled = False
            drive.rpdo[n].enabled = False
        drive.tpdo[1].clear()
        drive.tpdo[1].add_variable(0x6041)
        drive.tpdo[1].add_variable(0x6061)
        drive.tpdo[1].trans_type = 255
        drive.tpdo[1].event_timer = 20
        drive.tpdo[1].enabled = True
        drive.rpdo[1].clear()
        drive.rpdo[1].add_variable(0x6040)
        drive.rpdo[1].add_variable(0x6060)
        drive.rpdo[1].trans_type = 255
        drive.rpdo[1].enabled = True
        drive.tpdo.save()
        drive.rpdo.save()
        drive.setup_402_state_machine(read_pdos=True)
        drive.nmt.state = "OPERATIONAL"
        assert drive.tpdo[1].wait_for_reception(timeout=2.0) is not None

        def wait_for(bits, timeout=10.0):
            end = time.monotonic() + timeout
            while drive.statusword & bits != bits:
                if time.monotonic() > end:
                    raise TimeoutError(f"statusword {drive.statusword:04X}h")
                drive.tpdo[1].wait_for_reception(timeout=0.1)

        drive.state = "OPERATION ENABLED"
        drive.sdo[0x6098].raw = 35
        assert drive.homing(timeout=10)
        drive.op_mode = "PROFILED POSITION"
        drive.sdo[0x6081].raw = 360000
        drive.sdo[0x607A].raw = 90000
        drive.controlword = 0x2F
        drive.controlword = 0x3F
        wait_for(0x1000)
        drive.controlword = 0x2F
        wait_for(0x0400)
        position = drive.sdo[0x6064].raw
        # Target reached (bit 10) means within the position window.
        assert abs(position - 90000) <= 900, position
        (akd,) = network.bus.drives
        assert akd.state == "operation enabled"
        assert akd.mode == 1
        assert abs(akd.position - position) <= 900
        drive.state = "SWITCH ON DISABLED"
        assert network.bus.drives[0].state == "switch on disabled"
    finally:
        network.disconnect()


def test_a_sniffer_on_the_same_channel_sees_every_frame(channel):
    """A python-can Notifier + BufferedReader on a second Bus of the same
    channel sees every frame of the master and the drives, in bus order."""
    sniffer = can.Bus(interface="drivebus", channel=channel)
    reader = can.BufferedReader()
    notifier = can.Notifier(sniffer, [reader], timeout=0.05)
    master = can.Bus(interface="drivebus", channel=channel, drives=["akd:1", "dds6:2"])
    seen_by_master = []
    try:
        deadline = time.monotonic() + 2.0
        while len(seen_by_master) < 2 and time.monotonic() < deadline:
            m = master.recv(0.1)
            if m is not None:
                seen_by_master.append(m)
        assert sorted(m.arbitration_id for m in seen_by_master) == [0x701, 0x702]  # boot-ups
        for i in range(100):
            node = 1 + i % 2
            req = can.Message(arbitration_id=0x600 + node, data=[0x40, 0x18, 0x10, 1 + i % 4, 0, 0, 0, 0], is_extended_id=False)
            master.send(req)
            seen_by_master.append(req)
            resp = master.recv(1.0)
            assert resp is not None and resp.arbitration_id == 0x580 + node, resp
            seen_by_master.append(resp)
        assert master.recv(0.3) is None  # pre-operational, no heartbeat: nothing more
        time.sleep(0.2)
    finally:
        notifier.stop()
        master.shutdown()
        sniffer.shutdown()
    sniffed = []
    while (m := reader.get_message(0)) is not None:
        sniffed.append(m)
    key = lambda m: (m.arbitration_id, m.is_extended_id, m.is_remote_frame, bytes(m.data))  # noqa: E731
    assert [key(m) for m in sniffed] == [key(m) for m in seen_by_master]
    assert len(sniffed) == 202


def test_buses_on_other_channels_do_not_hear_each_other(channel):
    a = can.Bus(interface="drivebus", channel=channel + "-a", drives=["akd:1"])
    b = can.Bus(interface="drivebus", channel=channel + "-b")
    try:
        assert a.recv(1.0).arbitration_id == 0x701  # boot-up
        a.send(can.Message(arbitration_id=0x601, data=[0x40, 0, 0x10, 0, 0, 0, 0, 0], is_extended_id=False))
        assert a.recv(1.0).arbitration_id == 0x581
        assert b.recv(0.2) is None
    finally:
        a.shutdown()
        b.shutdown()
