"""No Python-visible call crashes the interpreter: whatever the arguments,
a call returns or raises an ordinary exception."""

from __future__ import annotations

import itertools

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import drivebus

OK_ERRORS = (ValueError, TypeError, OverflowError)
_n = itertools.count()

anything = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.binary(max_size=12),
    st.lists(st.text(max_size=8), max_size=3),
)
specs = st.lists(
    st.one_of(
        st.text(max_size=12),
        st.builds(lambda p, n: f"{p}:{n}", st.sampled_from(drivebus.PROFILES + ["x", ""]), st.integers(-5, 300)),
    ),
    max_size=3,
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(drives=st.one_of(specs, anything))
def test_virtual_bus_construction(drives):
    try:
        bus = drivebus.VirtualBus(f"prop-{next(_n)}", drives)
    except OK_ERRORS:
        return
    assert len(bus.drives) == len(drives)
    bus.close()


@settings(max_examples=300, deadline=None)
@given(
    arbitration_id=anything,
    data=anything,
    extended=anything,
    remote=anything,
    dlc=anything,
    timeout=anything,
)
def test_virtual_bus_calls(arbitration_id, data, extended, remote, dlc, timeout):
    bus = drivebus.VirtualBus(f"prop-{next(_n)}")
    listener = drivebus.VirtualBus(bus.channel)
    try:
        try:
            bus.send(arbitration_id, data, extended, remote, dlc)
        except OK_ERRORS:
            pass
        else:
            got = listener.recv(1.0)
            assert got is not None and got[0] == arbitration_id
        try:
            if timeout is None or (isinstance(timeout, (int, float)) and timeout > 0.01):
                timeout = 0.01  # None and long timeouts wait: valid, and slow
            bus.recv(timeout)
        except OK_ERRORS:
            pass
    finally:
        bus.close()
        listener.close()


@settings(max_examples=200, deadline=None)
@given(
    drives=specs,
    bitrate=anything,
    seconds=anything,
    arbitration_id=anything,
    data=anything,
)
def test_simulation_calls(drives, bitrate, seconds, arbitration_id, data):
    try:
        sim = drivebus.Simulation(drives, bitrate)
    except OK_ERRORS:
        return
    try:
        sim.send(arbitration_id, data)
    except OK_ERRORS:
        pass
    try:
        if isinstance(seconds, (int, float)) and seconds > 0.05:
            seconds = 0.05  # simulated time costs CPU time
        sim.advance(seconds)
    except OK_ERRORS:
        pass
    assert len(sim.drives) == len(drives)
    sim.log_lines()


MASTER_ERRORS = OK_ERRORS + (drivebus.DrivebusError, TimeoutError)
objects = st.one_of(
    anything,
    st.integers(0, 0x10000),
    st.sampled_from(["statusword", "identity/vendor-id", "6041:00", "1018sub2", "0x1A00", "controlword", "6060h"]),
)
_sim = None


def _master():
    """One simulation for all examples: its state carries over, as a script's would."""
    global _sim
    if _sim is None:
        _sim = drivebus.Simulation(["akd:1"])
    return _sim.master()


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    node=st.one_of(st.integers(-2, 130), anything),
    index=objects,
    sub=st.one_of(st.none(), st.integers(-1, 300), anything),
    value=anything,
    kind=st.one_of(st.none(), st.sampled_from(["u8", "i32", "str", "bytes", "nope"]), anything),
    command=st.one_of(st.sampled_from(["start", "stop", "preop", "reset", "reset-comm", "x"]), anything),
)
def test_master_calls(node, index, sub, value, kind, command):
    m = _master()
    # Node 1 is the drive; others cost an SDO timeout of simulated time only.
    for call in (
        lambda: m.sdo_read(node, index, sub, type=kind),
        lambda: m.sdo_write(node, index, value, type=kind),
        lambda: m.sdo_write(node, index, sub, value, type=kind),
        lambda: m.nmt(node, command),
        lambda: m.drive(node).move_to(value, timeout=0.05),
    ):
        try:
            call()
        except MASTER_ERRORS:
            pass


@settings(max_examples=40, deadline=None)
@given(drives=st.one_of(specs, anything), channel=anything, port=anything)
def test_serve_calls(drives, channel, port):
    if isinstance(port, int) and port != 0:
        port = 0  # never a port of another program
    try:
        server = drivebus.serve(drives, channel=channel, port=port)
    except OK_ERRORS + (OSError,):
        return
    with server:
        assert server.url.startswith("socketcand://127.0.0.1:")
        server.drives


_SIM = drivebus.Simulation(drives=["generic:5"])


@settings(max_examples=200, deadline=None)
@given(node=anything, what=anything, value=anything, line=anything, duration=anything, on=anything)
def test_run_time_changes(node, what, value, line, duration, on):
    # A drive powered off refuses with OSError; anything else as above.
    for call in (
        lambda: _SIM.input(node, what, value, line, duration),
        lambda: _SIM.fault(node, what, line, duration),
        lambda: _SIM.bus_off(node),
        lambda: _SIM.bus_on(node),
        lambda: _SIM.power(node, on),
    ):
        try:
            call()
        except OK_ERRORS + (OSError,):
            pass
    _SIM.power(5, True)
    _SIM.fault(5, "clear")
    _SIM.advance(0.001)


@settings(max_examples=150, deadline=None)
@given(what=anything, value=anything, line=anything, duration=anything, on=anything)
def test_drive_object_calls(what, value, line, duration, on):
    _SIM.power(5, True)
    (drive,) = _SIM.drives
    for call in (
        lambda: drive.set_input(what, value, line, duration),
        lambda: drive.fault(what, line, duration),
        drive.clear_fault,
        drive.bus_off,
        drive.bus_on,
        lambda: drive.power(on),
        drive.refresh,
    ):
        try:
            call()
        except OK_ERRORS + (OSError,):
            pass
    _SIM.power(5, True)
    _SIM.fault(5, "clear")
    _SIM.advance(0.001)


@settings(max_examples=150, deadline=None)
@given(node=anything, direction=anything, number=anything, entries=anything, mode=anything)
def test_pdo_and_lss_calls(node, direction, number, entries, mode):
    m = _SIM.master()
    for call in (
        lambda: m.pdo.read(node, direction, number),
        lambda: m.pdo.map(node, direction, number, entries),
        lambda: m.lss.switch_global(mode),
        lambda: m.lss.configure_node_id(node),
        lambda: m.sample(node, direction, seconds=0.001, period=number),
        lambda: _SIM.frame_log(columns=mode),
    ):
        try:
            call()
        except OK_ERRORS + (drivebus.DrivebusError,):
            pass
    m.lss.switch_global("waiting")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(drives=st.one_of(st.lists(st.sampled_from(["ipos", "generic", "akd", "", "x"]), max_size=3), anything))
def test_ethercat_simulation_construction(drives):
    import drivebus.ethercat

    try:
        line = drivebus.ethercat.Simulation(drives=drives, capture=False)
    except OK_ERRORS:
        return
    assert line.drives == list(drives)


_LINE = None


def _line():
    global _LINE
    if _LINE is None:
        import drivebus.ethercat

        _LINE = drivebus.ethercat.Simulation(drives=["ipos"], capture=False)
        _LINE.start()
    return _LINE


def _capped(x, cap):
    """`x` unless it is a valid count or time above `cap` (no hour-long run)."""
    if isinstance(x, (int, float)) and x == x and 0 < x < 1e12:
        return min(x, cap)
    return x


@settings(max_examples=100, deadline=None)
@given(a=anything, b=anything, c=anything, d=anything)
def test_ethercat_simulation_calls(a, b, c, d):
    line = _line()
    for call in (
        lambda: line.cycle(_capped(a, 5)),
        lambda: line.enable(timeout=_capped(a, 0.2)),
        lambda: line.disable(timeout=_capped(b, 0.2)),
        lambda: line.home(a, timeout=_capped(b, 0.2)),
        lambda: line.move_to(a, velocity=b, relative=c, timeout=_capped(d, 0.05)),
        lambda: line.csp(a[:5] if isinstance(a, list) else a),
        lambda: line.sdo_read(a, b),
        lambda: line.sdo_write(a, b, c),
        lambda: line.start(a, _capped(b, 0.01), c),
        lambda: line.scan(),
    ):
        try:
            call()
        except OK_ERRORS + (drivebus.DrivebusError,):
            pass
    assert line.now > 0
