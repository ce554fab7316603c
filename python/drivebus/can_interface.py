"""The python-can interface ``drivebus`` (entry point ``can.interface``).

``can.Bus(interface="drivebus", channel="virtual", drives=["akd:1"])``
joins the in-process virtual bus ``channel`` and hosts the drive twins
``drives`` on it while the bus is open.
"""

import os
import time
from typing import Any, List, Optional, Sequence, Tuple, Union

import can

from ._drivebus import DriveState, VirtualBus

__all__ = ["DrivebusBus"]


class DrivebusBus(can.BusABC):
    """A python-can bus on drivebus's in-process virtual CAN bus.

    :param channel: the bus's name; every bus of the process with the same
        channel shares one virtual bus (default ``"virtual"``).
    :param drives: drive twins to host, ``"PROFILE:NODE"`` as
        ``drivebus serve --drive`` takes them (``"akd:1"``).
    :param machine: a machine file (``drivebus serve --machine``) for the
        drives; default: each profile's default machine.
    :raises ValueError: a bad drive spec or machine file, with the CLI's message.
    """

    def __init__(
        self,
        channel: Any = "virtual",
        can_filters: Optional[can.typechecking.CanFilters] = None,
        drives: Sequence[str] = (),
        machine: Optional[Union[str, "os.PathLike[str]"]] = None,
        **kwargs: Any,
    ) -> None:
        name = "virtual" if channel is None else str(channel)
        if isinstance(drives, str):
            drives = [drives]
        self._channel = name
        self._bus = VirtualBus(name, list(drives), machine)
        self.channel_info = f"drivebus virtual bus {name!r}"
        super().__init__(channel=name, can_filters=can_filters, **kwargs)

    @property
    def drives(self) -> List[DriveState]:
        """The hosted drives, read now: each one's state (NMT, CiA 402 state, statusword, mode, position) and its run-time changes as methods (``drives[0].fault("encoder")``, ``.set_input(...)``, ``.power(False)``, ...)."""
        return self._bus.drives

    def input(
        self,
        node: int,
        input: str,
        value: float,
        line: Optional[int] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Sets a machine input of hosted drive ``node`` now, as ``drivebus control input`` (see ``VirtualBus.input``)."""
        self._bus.input(node, input, value, line, duration)

    def fault(
        self,
        node: int,
        kind: str,
        switch: Optional[str] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Starts (or with ``"clear"`` ends) a machine fault of hosted drive ``node``, as ``drivebus control fault``."""
        self._bus.fault(node, kind, switch, duration)

    def bus_off(self, node: int) -> None:
        """Hosted drive ``node``'s CAN controller goes bus-off (``drivebus control bus off``)."""
        self._bus.bus_off(node)

    def bus_on(self, node: int) -> None:
        """Hosted drive ``node`` is back on the bus (``drivebus control bus on``)."""
        self._bus.bus_on(node)

    def power(self, node: int, on: bool) -> None:
        """Cuts or restores hosted drive ``node``'s power (``drivebus control power``)."""
        self._bus.power(node, on)

    def send(self, msg: can.Message, timeout: Optional[float] = None) -> None:
        """Sends ``msg`` to every other participant of the virtual bus."""
        if msg.is_fd:
            raise ValueError("drivebus's virtual bus carries classic CAN frames, not CAN FD")
        if msg.is_error_frame:
            raise ValueError("error frames cannot be sent on drivebus's virtual bus")
        try:
            self._bus.send(
                msg.arbitration_id,
                bytes(msg.data or b""),
                msg.is_extended_id,
                msg.is_remote_frame,
                msg.dlc if msg.is_remote_frame else None,
            )
        except OSError as e:
            raise can.CanOperationError(str(e)) from e

    def _recv_internal(self, timeout: Optional[float]) -> Tuple[Optional[can.Message], bool]:
        try:
            got = self._bus.recv(timeout)
        except OSError as e:
            raise can.CanOperationError(str(e)) from e
        if got is None:
            return None, False
        arbitration_id, extended, remote, dlc, data = got
        msg = can.Message(
            # Wall-clock seconds, as python-can's own interfaces give them.
            timestamp=time.time(),
            arbitration_id=arbitration_id,
            is_extended_id=extended,
            is_remote_frame=remote,
            dlc=dlc,
            data=None if remote else data,
            channel=self._channel,
            is_rx=True,
        )
        return msg, False

    def shutdown(self) -> None:
        """Stops the drives this bus hosts and leaves the virtual bus."""
        super().shutdown()
        self._bus.close()

