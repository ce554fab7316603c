"""Bad arguments raise Python exceptions with the CLI's messages; none
crashes the interpreter."""

from __future__ import annotations

import can
import pytest

import drivebus


@pytest.mark.parametrize(
    "spec, message",
    [
        ("nope:1", "bad drive `nope:1`: unknown profile `nope` (profiles: kc1, akd, ipos, ssd630, dds6, generic)"),
        ("akd:0", "bad drive `akd:0`: node-ID `0` is not in 1..127"),
        ("akd:128", "bad drive `akd:128`: node-ID `128` is not in 1..127"),
        ("akd:x", "bad drive `akd:x`: node-ID `x` is not in 1..127"),
        ("akd", "bad drive `akd`: expected PROFILE:NODE, e.g. akd:1 (profiles: kc1, akd, ipos, ssd630, dds6, generic)"),
    ],
)
def test_bad_drive_spec_raises_the_cli_message(channel, spec, message):
    with pytest.raises(ValueError) as e:
        can.Bus(interface="drivebus", channel=channel, drives=[spec])
    assert str(e.value) == message
    with pytest.raises(ValueError) as e:
        drivebus.VirtualBus(channel, [spec])
    assert str(e.value) == message


def test_node_id_taken_twice(channel):
    with pytest.raises(ValueError, match=r"node-ID 1 is already taken by akd:1"):
        drivebus.VirtualBus(channel, ["akd:1", "dds6:1"])


def test_wrong_types_raise_type_error(channel):
    with pytest.raises(TypeError):
        drivebus.VirtualBus(channel, [1])  # type: ignore[list-item]
    with pytest.raises(TypeError):
        drivebus.VirtualBus(42)  # type: ignore[arg-type]


def test_frames_can_cannot_carry(channel):
    bus = drivebus.VirtualBus(channel)
    with pytest.raises(ValueError, match="0x800 does not fit in 11 bits"):
        bus.send(0x800, b"")
    with pytest.raises(ValueError, match="0x20000000 does not fit in 29 bits"):
        bus.send(0x2000_0000, b"", is_extended_id=True)
    with pytest.raises(ValueError, match="longer than 8 bytes"):
        bus.send(0x123, bytes(9))
    with pytest.raises(ValueError, match="longer than 8 bytes"):
        bus.send(0x123, b"", is_remote_frame=True, dlc=9)
    with pytest.raises(OverflowError):
        bus.send(-1, b"")
    with pytest.raises(ValueError, match="non-negative"):
        bus.recv(-1.0)
    with pytest.raises(ValueError, match="non-negative"):
        bus.recv(float("nan"))
    assert bus.recv(0.0) is None
    bus.close()


def test_closed_bus(channel):
    bus = can.Bus(interface="drivebus", channel=channel, drives=["akd:1"])
    assert len(bus.drives) == 1
    bus.shutdown()
    with pytest.raises(can.CanOperationError, match="closed"):
        bus.send(can.Message(arbitration_id=0x601, data=bytes(8), is_extended_id=False))
    with pytest.raises(can.CanOperationError, match="closed"):
        bus.recv(0.1)
    with pytest.raises(OSError, match="closed"):
        _ = bus.drives
    bus.shutdown()  # twice is harmless


def test_fd_and_error_frames_are_refused(channel):
    with can.Bus(interface="drivebus", channel=channel) as bus:
        with pytest.raises(ValueError, match="CAN FD"):
            bus.send(can.Message(arbitration_id=1, data=bytes(12), is_fd=True, is_extended_id=False))
        with pytest.raises(ValueError, match="error frames"):
            bus.send(can.Message(arbitration_id=1, is_error_frame=True, is_extended_id=False))
