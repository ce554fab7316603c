"""Type stubs of the Rust extension ``drivebus._drivebus``."""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

PROFILES: List[str]
"""The personalities a drive spec may name (``"kc1"``, ``"akd"``, ...)."""

class DriveState:
    """One hosted drive (``bus.drives``, ``sim.drives``, ``server.drives``): its state when it was read, and methods that change the drive now.

    The methods are the run-time changes of ``drivebus control``, the same
    calls as the host's own (``bus.fault(node, ...)``). A drive object keeps
    its bus, server or simulation alive. They raise ``ValueError`` with the
    control interface's message, ``OSError`` when the drive is powered off
    or its bus is closed.
    """

    def refresh(self) -> "DriveState":
        """The drive's state read now (a new object)."""
    def set_input(
        self, input: str, value: float, line: Optional[int] = None, duration: Optional[float] = None
    ) -> None:
        """Sets machine input ``input`` (``"digital"`` with ``line`` 1..16, ``"analog"`` in volts, ``"master_velocity"``, ...) now, for ``duration`` seconds if given."""
    def fault(self, kind: str, switch: Optional[str] = None, duration: Optional[float] = None) -> None:
        """Starts machine fault ``kind`` (``"encoder"``, ``"over_current"``, ``"trip"`` with ``switch``, ...) now."""
    def clear_fault(self) -> None:
        """Ends every machine fault that is on (a latched drive fault stays until the master's fault reset)."""
    def bus_off(self) -> None:
        """The drive's CAN controller goes bus-off."""
    def bus_on(self) -> None:
        """The drive is back on the bus."""
    def power(self, on: bool) -> None:
        """Cuts (``False``) or restores (``True``) the drive's power; off it leaves ``drives``."""

    @property
    def profile(self) -> str:
        """The personality (``"akd"``)."""
    @property
    def node(self) -> int:
        """The node-ID."""
    @property
    def nmt(self) -> str:
        """The NMT state: ``"initialisation"``, ``"pre-operational"``, ``"operational"`` or ``"stopped"``."""
    @property
    def state(self) -> str:
        """The CiA 402 state from the statusword (``"operation enabled"``); ``"unknown"`` for an undefined pattern."""
    @property
    def statusword(self) -> int:
        """6041h, the statusword."""
    @property
    def mode(self) -> int:
        """6061h, the mode of operation in force."""
    @property
    def position(self) -> int:
        """6064h, the position actual value in position units."""

class VirtualBus:
    """A participant of the in-process virtual CAN bus ``channel``, hosting ``drives`` on it.

    Raises ``ValueError`` with the message of ``drivebus serve --drive`` for
    a bad drive spec (unknown profile, node-ID outside 1..127, a node-ID
    taken twice), and ``path: line:column: cause`` for a bad machine file
    (``machine``, as ``drivebus serve --machine`` takes it).
    """

    def __init__(
        self,
        channel: str = "virtual",
        drives: Sequence[str] = ...,
        machine: Optional[Union[str, "os.PathLike[str]"]] = None,
    ) -> None: ...
    @property
    def channel(self) -> str:
        """The channel (the bus's name)."""
    @property
    def closed(self) -> bool:
        """True once ``close()`` was called."""
    @property
    def drives(self) -> List[DriveState]:
        """The hosted drives, read now, in the order they were given (each with its run-time changes as methods); ``OSError`` once closed."""
    def send(
        self,
        arbitration_id: int,
        data: bytes,
        is_extended_id: bool = False,
        is_remote_frame: bool = False,
        dlc: Optional[int] = None,
    ) -> None:
        """Sends a classic CAN frame; ``ValueError`` for a frame CAN cannot carry, ``OSError`` once closed."""
    def recv(self, timeout: Optional[float] = None) -> Optional[Tuple[int, bool, bool, int, bytes]]:
        """The next frame as ``(arbitration_id, is_extended_id, is_remote_frame, dlc, data)``, or ``None`` on timeout."""
    def close(self) -> None:
        """Stops the hosted drives and leaves the bus; closing twice is harmless."""
    def input(
        self,
        node: int,
        input: str,
        value: float,
        line: Optional[int] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Sets machine input ``input`` of drive ``node`` (``drivebus control input``).

        ``"digital"`` (``line`` 1..16, value 0/1), ``"analog"`` (``line``
        1..4, volts), ``"master_velocity"``, ``"master_position"``,
        ``"motor_temperature"``, ``"brake"``; for ``duration`` seconds, then
        back to the machine's value. Shows in 60FDh / a TPDO at the drive's
        next control period. ``ValueError`` with the control interface's
        message; ``OSError`` when the drive is powered off.
        """
    def fault(
        self,
        node: int,
        kind: str,
        switch: Optional[str] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Starts machine fault ``kind`` of drive ``node`` (``drivebus control fault``).

        ``"encoder"``, ``"over_current"``, ``"over_temperature"``,
        ``"over_voltage"``, ``"under_voltage"``, ``"trip"`` / ``"wire_break"``
        with ``switch`` (``"negative_limit"``, ``"positive_limit"``,
        ``"home_switch"``); ``"clear"`` ends every machine fault that is on
        (a latched drive fault stays until the master's fault reset).
        """
    def bus_off(self, node: int) -> None:
        """Drive ``node``'s CAN controller goes bus-off: it hears nothing, what it sends is lost."""
    def bus_on(self, node: int) -> None:
        """Drive ``node`` is back on the bus (a manual recovery)."""
    def power(self, node: int, on: bool) -> None:
        """Cuts (``on=False``) or restores drive ``node``'s power; on, it boots again (a boot-up message).

        A drive without power is left out of ``drives``.
        """

class Simulation:
    """Drive twins on a virtual CAN bus in simulated time, deterministic.

    Nothing moves between calls: ``advance(seconds)`` runs the bus and the
    drives; the same calls give the same frame log, byte for byte. Any
    thread may use it, one call at a time. Raises ``ValueError`` with the CLI's message
    for a bad drive spec, and for a bitrate of 0 (``None``: frames take no
    time).
    """

    def __init__(
        self,
        drives: Sequence[str] = ...,
        bitrate: Optional[int] = 1_000_000,
        machine: Optional[Union[str, "os.PathLike[str]"]] = None,
    ) -> None: ...
    @property
    def now(self) -> float:
        """Simulated time in seconds since the start."""
    @property
    def drives(self) -> List[DriveState]:
        """The drives, read now, in the order they were given (each with its run-time changes as methods)."""
    def advance(self, seconds: float) -> None:
        """Runs the bus and the drives for ``seconds`` of simulated time (0 to a year)."""
    def send(
        self,
        arbitration_id: int,
        data: bytes,
        is_extended_id: bool = False,
        is_remote_frame: bool = False,
        dlc: Optional[int] = None,
    ) -> None:
        """Queues a frame from the host's station at the current simulated time."""
    def received(self) -> List[Tuple[int, bool, bool, int, bytes]]:
        """The frames the host's station received since the last call, as ``VirtualBus.recv`` gives them."""
    def log(self) -> List[Tuple[float, int, bool, bool, int, bytes]]:
        """Every frame delivered so far: ``(seconds, arbitration_id, is_extended_id, is_remote_frame, dlc, data)``."""
    def log_lines(self) -> List[str]:
        """The log as candump lines (``(0.000047) can0 701#00``)."""
    def frame_log(self, columns: bool = True, numpy: bool = False) -> Any:
        """The frame log for analysis.

        ``columns=True``: a dict of equal-length lists ``time`` (simulated
        seconds), ``id``, ``extended``, ``remote``, ``dlc``, ``data`` (bytes),
        ready for ``pandas.DataFrame(...)``; ``columns=False``: a list of
        dicts with those keys; ``numpy=True``: a numpy structured array with
        those fields (``data`` as 8 ``uint8``, zero padded). ``ImportError``
        naming numpy when it is asked for and not installed.
        """
    def master(self) -> "Master":
        """The ``drivebus`` tool's CANopen master on this bus; its calls run in simulated time."""
    def input(
        self,
        node: int,
        input: str,
        value: float,
        line: Optional[int] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Sets machine input ``input`` of drive ``node`` (``drivebus control input``).

        ``"digital"`` (``line`` 1..16, value 0/1), ``"analog"`` (``line``
        1..4, volts), ``"master_velocity"``, ``"master_position"``,
        ``"motor_temperature"``, ``"brake"``; for ``duration`` seconds, then
        back to the machine's value. Shows in 60FDh / a TPDO at the drive's
        next control period. ``ValueError`` with the control interface's
        message; ``OSError`` when the drive is powered off.
        """
    def fault(
        self,
        node: int,
        kind: str,
        switch: Optional[str] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Starts machine fault ``kind`` of drive ``node`` (``drivebus control fault``).

        ``"encoder"``, ``"over_current"``, ``"over_temperature"``,
        ``"over_voltage"``, ``"under_voltage"``, ``"trip"`` / ``"wire_break"``
        with ``switch`` (``"negative_limit"``, ``"positive_limit"``,
        ``"home_switch"``); ``"clear"`` ends every machine fault that is on
        (a latched drive fault stays until the master's fault reset).
        """
    def bus_off(self, node: int) -> None:
        """Drive ``node``'s CAN controller goes bus-off: it hears nothing, what it sends is lost."""
    def bus_on(self, node: int) -> None:
        """Drive ``node`` is back on the bus (a manual recovery)."""
    def power(self, node: int, on: bool) -> None:
        """Cuts (``on=False``) or restores drive ``node``'s power; on, it boots again (a boot-up message).

        A drive without power is left out of ``drives``.
        """
    def run_until(self, predicate: Callable[[], object], timeout: float, step: float = 0.001) -> float:
        """Advances simulated time by ``step`` until ``predicate()`` is true; returns the simulated time then.

        Raises ``TimeoutError`` naming the simulated time reached when
        ``timeout`` seconds of simulated time pass first.
        """

class DrivebusError(Exception):
    """A CANopen operation failed on the bus."""

class SdoError(DrivebusError):
    """An SDO transfer failed (aborted by the device, timed out), with the ``drivebus sdo`` message."""

class DriveError(DrivebusError):
    """A CiA 402 drive command failed (fault, a move stopped short, a timeout), with the ``drivebus drive`` message."""

Obj = Union[int, str]
"""An object: an index, or text as the tool takes it (``"6041"``, ``"1018:01"``, ``"statusword"``)."""

class Master:
    """The ``drivebus`` tool's CANopen master on a ``Simulation``'s bus (``sim.master()``).

    Each call returns when its work is done on the simulated bus, however
    long that took there; ``TimeoutError`` when it did not finish within an
    hour of simulated time.
    """

    def scan(self, timeout: float = 0.1) -> List[Dict[str, Optional[int]]]:
        """Active scan of 1..127: dicts ``node``, ``device_type``, ``vendor_id``, ``product_code``, ``revision``, ``serial``."""
    def sdo_read(self, node: int, index: Obj, sub: Optional[Obj] = None, *, type: Optional[str] = None) -> Any:
        """Reads an object (``drivebus sdo read``), decoded by ``type``, the drive's EDS or the standard type.

        A record or array without a sub-index reads as a dict of its
        entries; ``bytes`` when the type is unknown. ``SdoError`` with the
        tool's message; ``ValueError`` for an object written wrongly.
        """
    def sdo_write(self, node: int, index: Obj, *args: Any, type: Optional[str] = None) -> None:
        """Writes an object: ``sdo_write(node, index, value)`` or ``sdo_write(node, index, sub, value)`` (``drivebus sdo write``)."""
    def nmt(self, node: int, command: str) -> None:
        """``start``, ``stop``, ``preop``, ``reset`` or ``reset-comm`` to ``node`` (0: all); a reset waits for the boot-up."""
    def drive(self, node: int) -> "Drive":
        """The CiA 402 drive at ``node``."""
    @property
    def pdo(self) -> "Pdos":
        """PDO configuration (``drivebus pdo show|map``)."""
    @property
    def lss(self) -> "Lss":
        """The CiA 305 LSS services (``drivebus lss``), 100 ms of simulated time per answer."""
    def start_sync(self, period: float = 0.001, counter: int = 0) -> None:
        """Produces SYNC every ``period`` seconds of simulated time (``counter``: overflow value, 0: no counter)."""
    def stop_sync(self) -> None:
        """Stops producing SYNC."""
    def sample(
        self,
        node: int,
        index: Obj,
        sub: Optional[Obj] = None,
        *,
        seconds: float = 1.0,
        period: float = 0.01,
    ) -> Tuple[List[float], List[Any]]:
        """Reads an object by SDO every ``period`` for ``seconds`` of simulated time: ``(times, values)``."""

class Pdos:
    """The PDO configuration of the nodes on a simulation's bus (``master.pdo``)."""

    def read(self, node: int, direction: str, number: int) -> Dict[str, Any]:
        """PDO ``number`` (``direction`` ``"rpdo"``/``"tpdo"``): ``dir``, ``number``, ``cob_id``, ``valid``,
        ``transmission_type``, ``inhibit_time``, ``event_timer_ms``, ``sync_start``, ``mapping``
        (dicts ``index``, ``sub``, ``bits``, ``name``); ``SdoError``."""
    def show(self, node: int) -> List[Dict[str, Any]]:
        """Every PDO of ``node`` (``drivebus pdo show``): the RPDOs, then the TPDOs."""
    def map(
        self,
        node: int,
        direction: str,
        number: int,
        entries: Sequence[Union[Tuple[int, int, int], str]],
        *,
        cob_id: Optional[int] = None,
        transmission: Optional[int] = None,
        inhibit: Optional[int] = None,
        event_timer: Optional[int] = None,
    ) -> None:
        """Maps PDO ``number`` (``drivebus pdo map``): entries ``(index, sub, bits)``, ``"6041:0:16"`` or an
        object name; the previous mapping is restored when the device refuses (``SdoError`` says so)."""

class Lss:
    """The LSS master on a simulation's bus (``master.lss``); ``DrivebusError`` (``LSS: no answer``, ...)."""

    def switch_global(self, mode: str) -> None:
        """``"configuration"`` or ``"waiting"`` for every LSS slave."""
    def switch_selective(self, vendor_id: int, product_code: int, revision: int, serial: int) -> None:
        """The slave with this LSS address goes to configuration."""
    def inquire_identity(self) -> Dict[str, int]:
        """The LSS address of the slave in configuration: ``vendor_id``, ``product_code``, ``revision``, ``serial``."""
    def inquire_node_id(self) -> int:
        """The node-ID of the slave in configuration (0xFF: none)."""
    def configure_node_id(self, node_id: int) -> None:
        """Node-ID of the slave in configuration; in force after its next NMT reset communication."""
    def store(self) -> None:
        """Stores the configuration of the slave in configuration."""
    def configure_selected(
        self, node_id: int, vendor_id: int, product_code: int, revision: int, serial: int, store: bool = False
    ) -> None:
        """``drivebus lss set-node-id``: selective switch, configure, store when asked, back to waiting."""
    def scan(self) -> Optional[Dict[str, Any]]:
        """``drivebus lss scan``: the non-configured slave with the lowest address and ``more``, or ``None``."""
    def configure_only_slave(self, node_id: int, store: bool = False) -> Optional[Dict[str, int]]:
        """Gives ``node_id`` to the only non-configured slave; ``DrivebusError`` when several answer."""

class Drive:
    """A CiA 402 drive of a simulation (``master.drive(node)``); each call runs the ``drivebus drive`` procedure."""

    @property
    def node(self) -> int:
        """The node-ID."""
    @property
    def state(self) -> str:
        """The CiA 402 state from the statusword (``"operation enabled"``)."""
    @property
    def position(self) -> Optional[int]:
        """6064h, the position actual value."""
    def enable(self) -> None:
        """To operation enabled (fault reset first when faulted); ``DriveError`` otherwise."""
    def disable(self) -> None:
        """To ready to switch on."""
    def home(self, method: Optional[int] = None, timeout: float = 60.0) -> Dict[str, Any]:
        """Homing with ``method`` (default: the drive's 6098h); the report (``end``, ``position``, ``target``, ``statusword``, ``duration``)."""
    def move_to(
        self,
        position: int,
        relative: bool = False,
        velocity: Optional[int] = None,
        acceleration: Optional[int] = None,
        timeout: float = 60.0,
    ) -> Dict[str, Any]:
        """A profile-position move; the report, or ``DriveError`` when it stopped anywhere but the target."""
    def csp(self, positions: Sequence[int]) -> int:
        """Cyclic synchronous position: mode 8, one target 607Ah per SYNC; how many were sent. Needs SYNC and the drive enabled."""

class Server:
    """Drive twins on a socketcand server in this process (what ``drivebus serve`` runs).

    ``drivebus.serve(...)`` makes one; use it as a context manager. Raises
    ``ValueError`` with the CLI's message for a bad drive spec, machine
    file or channel, ``OSError`` when it cannot listen.
    """

    def __init__(
        self,
        drives: Sequence[str] = ...,
        machine: Optional[Union[str, "os.PathLike[str]"]] = None,
        host: str = "127.0.0.1",
        port: int = 0,
        channel: str = "can0",
    ) -> None: ...
    @property
    def url(self) -> str:
        """``socketcand://HOST:PORT/CHANNEL``."""
    @property
    def port(self) -> int:
        """The port it listens on (a free one when 0 was asked)."""
    @property
    def closed(self) -> bool:
        """True once ``close()`` was called."""
    @property
    def drives(self) -> List[DriveState]:
        """The hosted drives' state, read now; ``OSError`` once closed."""
    def input(
        self,
        node: int,
        input: str,
        value: float,
        line: Optional[int] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Sets a machine input of drive ``node`` (``drivebus control input``; see ``VirtualBus.input``)."""
    def fault(
        self,
        node: int,
        kind: str,
        switch: Optional[str] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Starts (``"clear"``: ends) a machine fault of drive ``node`` (``drivebus control fault``)."""
    def bus_off(self, node: int) -> None:
        """Drive ``node``'s CAN controller goes bus-off."""
    def bus_on(self, node: int) -> None:
        """Drive ``node`` is back on the bus."""
    def power(self, node: int, on: bool) -> None:
        """Cuts or restores drive ``node``'s power; on, it boots again."""
    def close(self) -> None:
        """Stops the drives and the server; the port is closed when it returns."""
    def __enter__(self) -> "Server": ...
    def __exit__(self, *args: object) -> bool: ...

class EthercatServer:
    """A line of drive twins served on a network interface (``drivebus.ethercat.serve``), as ``drivebus ethercat serve``.

    ``ValueError`` with the CLI's message for a profile without an EtherCAT
    face; ``OSError`` when the AF_PACKET socket cannot be opened (needs
    root or CAP_NET_RAW, and the interface up).
    """

    def __init__(self, iface: str, drives: Sequence[str] = ...) -> None: ...
    @property
    def iface(self) -> str:
        """The interface it serves on."""
    @property
    def drives(self) -> List[str]:
        """The line's slaves in order (``["ipos", "generic"]``)."""
    @property
    def closed(self) -> bool:
        """True once ``close()`` was called."""
    def input(
        self,
        slave: int,
        input: str,
        value: float,
        line: Optional[int] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Sets a machine input of the drive at ``slave`` (position from 1), as ``drivebus control input``."""
    def fault(
        self,
        slave: int,
        kind: str,
        switch: Optional[str] = None,
        duration: Optional[float] = None,
    ) -> None:
        """Starts (``"clear"``: ends) a machine fault of the drive at ``slave``, as ``drivebus control fault``."""
    def power(self, slave: int, on: bool) -> None:
        """Cuts or restores the power of the slave at ``slave``; on, its ESC starts in INIT."""
    def close(self) -> None:
        """Stops serving; returns when the socket is closed. ``OSError`` when serving had failed."""
    def __enter__(self) -> "EthercatServer": ...
    def __exit__(self, *args: object) -> bool: ...

class EthercatSimulation:
    """An EtherCAT line of drive twins with the ``drivebus`` master, in simulated time (``drivebus.ethercat.Simulation``).

    The in-process line of ``drivebus demo --ethercat``: the drives
    ``drivebus ethercat serve`` builds, on a simulated clock that moves
    only when the master waits, so a run depends only on the calls made
    (the same calls give the same ``log()`` and ``capture()``). Raises
    ``ValueError`` with the CLI's message for a profile without an
    EtherCAT face. Master errors raise ``DrivebusError``, drive errors
    (fault, timeout) ``DriveError``, with the CLI's messages. Each line
    leaves a parked thread and about 18 kB of frame buffers behind for the
    life of the process.
    """

    def __init__(self, drives: Sequence[str] = ..., capture: bool = True) -> None: ...
    @property
    def drives(self) -> List[str]:
        """The line's slaves in order (``["ipos"]``)."""
    @property
    def now(self) -> float:
        """Simulated time in seconds."""
    @property
    def dc(self) -> bool:
        """True while the line is in OP with distributed clocks (SYNC0)."""
    def scan(self) -> List[Dict[str, Any]]:
        """Scans the line (SII, 1018h over CoE) and leaves it in PRE-OP: per slave ``position``, ``name``, ``vendor_id``, ``product_code``, ``revision``, ``serial``, ``coe_identity_matches``, ``dc``."""
    def start(self, position: int = 1, cycle: float = 0.001, dc: bool = True) -> None:
        """Brings the line to OP with the drive at ``position`` under control, process data every ``cycle`` seconds (DC SYNC0 when ``dc``); scans first if needed."""
    def cycle(self, n: int = 1) -> Tuple[int, int, Optional[int]]:
        """Runs ``n`` process-data cycles; returns the last ``(statusword, position, following)``."""
    def enable(self, timeout: float = 2.0) -> None:
        """Enables the drive (Operation enabled) over the process data."""
    def disable(self, timeout: float = 2.0) -> None:
        """Disables the drive (Switch on disabled)."""
    def home(self, method: int = 35, timeout: float = 10.0) -> int:
        """Homes with ``method`` (6098h); returns the position at homing attained."""
    def move_to(
        self, target: int, velocity: Optional[int] = None, relative: bool = False, timeout: float = 20.0
    ) -> int:
        """A profile-position move to ``target`` at ``velocity`` (6081h) if given; returns the position at target reached."""
    def csp(self, targets: Sequence[int]) -> int:
        """Cyclic synchronous position, one target per cycle; returns the cycles run."""
    def sdo_read(self, index: int, sub: int) -> int:
        """Reads ``index``:``sub`` of the drive under control over CoE, as a signed integer."""
    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        """Writes little-endian ``data`` to ``index``:``sub`` of the drive under control over CoE."""
    def stop(self) -> None:
        """Leaves OP for SAFE-OP; ``scan()`` or ``start()`` begin again."""
    def counters(self) -> Tuple[int, int, int]:
        """``(cycles, bad_wkc, lost)`` of the cyclic exchange."""
    def log(self) -> List[Tuple[float, int, int, Optional[int]]]:
        """The process data of every cycle of ``cycle``/``home``/``move_to``/``csp``: ``(seconds, statusword, position, following)``."""
    def capture(self) -> Optional[bytes]:
        """Every frame so far as pcapng bytes (simulated timestamps); ``None`` with ``capture=False``."""
