"""Fixtures for the interop suite: `drivebus serve` / `drivebus slcan-pty`
processes, canopen networks connected to them, the CLI, and a benchmark
recorder.

Every process started here is stopped in teardown with SIGTERM, and its exit
code must be 0 (part of the `drivebus serve` contract). Every test runs under
a SIGALRM deadline (default 60 s, `@pytest.mark.limit(seconds)` to change).
"""

from __future__ import annotations

import functools
import json
import os
import queue
import re
import signal
import socket
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import canopen
import pytest

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("DRIVEBUS_BIN", ROOT / "target" / "release" / "drivebus"))
EDS_DIR = ROOT / "crates" / "personality" / "eds"
LOCALHOST = "127.0.0.1"
CHANNEL = "can0"
READY_TIMEOUT = 20.0  # s, for the `listening on` / `slcan-pty PATH` line
STOP_TIMEOUT = 10.0  # s, from SIGTERM to exit
DEFAULT_LIMIT = 60.0  # s, per test
SDO_TIMEOUT = 1.0  # s; canopen's default 0.3 s is tight on a loaded 2-core CI box


def pytest_configure(config):
    config.addinivalue_line("markers", "limit(seconds): per-test deadline (SIGALRM)")


# --------------------------------------------------------------------------
# per-test deadline


class TestDeadline(Exception):
    """Raised in the main thread when a test runs past its limit."""


@pytest.fixture(autouse=True)
def _deadline(request):
    m = request.node.get_closest_marker("limit")
    limit = float(m.args[0]) if m else DEFAULT_LIMIT

    def on_alarm(signum, frame):
        raise TestDeadline(f"test exceeded its {limit:.0f} s limit")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


# --------------------------------------------------------------------------
# the CLI


def free_port() -> int:
    """An ephemeral TCP port on 127.0.0.1 that was free a moment ago."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((LOCALHOST, 0))
        return s.getsockname()[1]


def run_cli(*args, timeout: float = 30.0, input: str | None = None) -> subprocess.CompletedProcess:
    """Runs `drivebus ARGS...` to completion (bounded) and returns the result."""
    return subprocess.run(
        [str(BIN), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        input=input,
        stdin=None if input is not None else subprocess.DEVNULL,
    )


@functools.lru_cache(maxsize=None)
def _commands(*path: str) -> frozenset:
    """Subcommand names clap lists under `drivebus PATH... --help`."""
    if not BIN.exists():
        return frozenset()
    try:
        out = run_cli(*path, "--help", timeout=20).stdout
    except subprocess.TimeoutExpired:
        return frozenset()
    names, inside = set(), False
    for line in out.splitlines():
        if line.strip() == "Commands:":
            inside = True
            continue
        if inside:
            if not line.strip() or not line.startswith("  "):
                break
            names.add(line.split()[0])
    return frozenset(names)


def has_command(*path: str) -> bool:
    """True when `drivebus PATH...` is a command of the built binary."""
    for i in range(len(path)):
        if path[i] not in _commands(*path[:i]):
            return False
    return True


def require_command(*path: str) -> None:
    """Skips the test, saying exactly what is missing, when the CLI lacks a command."""
    if not BIN.exists():
        pytest.fail(f"no drivebus binary at {BIN} (tests/interop/run builds it)")
    if not has_command(*path):
        have = " ".join(sorted(_commands(*path[:-1]))) or "nothing"
        pytest.skip(f"drivebus has no `{' '.join(path)}` command yet (`drivebus {' '.join(path[:-1])} --help` lists: {have})")


# --------------------------------------------------------------------------
# long-running drivebus processes


_ALL_PROCS: list["Proc"] = []


def pytest_sessionfinish(session, exitstatus):
    """Last resort: no drivebus process outlives the session, whatever failed."""
    for p in _ALL_PROCS:
        if p.p.poll() is None:
            p.p.kill()
            p.p.wait(timeout=5)


class Proc:
    """A drivebus process with its stdout read line by line on a thread and
    its stderr kept in a file for failure messages."""

    def __init__(self, args: list[str]):
        self.args = [str(BIN), *map(str, args)]
        self._err = tempfile.TemporaryFile(mode="w+")
        self.p = subprocess.Popen(
            self.args,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self._err,
            text=True,
            bufsize=1,
            env={**os.environ, "RUST_LOG": os.environ.get("RUST_LOG", "warn")},
        )
        _ALL_PROCS.append(self)
        self.lines: "queue.Queue[str | None]" = queue.Queue()
        self.stdout: list[str] = []
        threading.Thread(target=self._pump, daemon=True).start()
        self.returncode: int | None = None

    def _pump(self):
        for line in self.p.stdout:
            self.stdout.append(line)
            self.lines.put(line)
        self.lines.put(None)

    def stderr(self) -> str:
        self._err.flush()
        self._err.seek(0)
        return self._err.read()

    def describe(self) -> str:
        return (
            f"command: {' '.join(self.args)}\nexit: {self.p.poll()}\n"
            f"stdout:\n{''.join(self.stdout)[-3000:]}\nstderr:\n{self.stderr()[-3000:]}"
        )

    def wait_line(self, pattern: str, timeout: float = READY_TIMEOUT) -> re.Match:
        """Waits for a stdout line matching `pattern` (regex search)."""
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no stdout line matching {pattern!r} within {timeout} s\n{self.describe()}")
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                continue
            if line is None:
                raise AssertionError(f"process ended before printing {pattern!r}\n{self.describe()}")
            m = re.search(pattern, line)
            if m:
                return m

    def stop(self) -> int:
        """SIGTERM, then wait; returns the exit code (kills and fails on a hang)."""
        if self.returncode is not None:
            return self.returncode
        if self.p.poll() is None:
            self.p.send_signal(signal.SIGTERM)
            try:
                self.p.wait(timeout=STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                self.p.kill()
                self.p.wait(timeout=5)
                self.returncode = self.p.returncode
                raise AssertionError(f"did not exit within {STOP_TIMEOUT} s of SIGTERM\n{self.describe()}")
        self.returncode = self.p.returncode
        return self.returncode


class Served:
    """A running `drivebus serve`; unpacks as (host, port)."""

    def __init__(self, proc: Proc, host: str, port: int, drives: tuple, state_dir):
        self.proc, self.host, self.port = proc, host, port
        self.drives, self.state_dir = drives, state_dir

    def __iter__(self):
        return iter((self.host, self.port))

    @property
    def url(self) -> str:
        return f"socketcand://{self.host}:{self.port}/{CHANNEL}"

    def stop(self) -> None:
        """The contract: SIGTERM → exit code 0."""
        rc = self.proc.stop()
        assert rc == 0, f"`drivebus serve` exited {rc} after SIGTERM (contract: 0)\n{self.proc.describe()}"


def start_serve(*drives: str, state_dir=None, bitrate=None, port: int | None = None, extra: tuple = ()) -> Served:
    require_command("serve")
    port = port or free_port()
    args = ["serve", "--listen", f"{LOCALHOST}:{port}", "--channel", CHANNEL, *extra]
    for d in drives:
        args += ["--drive", d]
    if state_dir is not None:
        args += ["--state-dir", str(state_dir)]
    if bitrate is not None:
        args += ["--bitrate", str(bitrate)]
    proc = Proc(args)
    try:
        proc.wait_line(r"listening on")
    except BaseException:
        proc.p.kill()
        proc.p.wait(timeout=5)
        raise
    return Served(proc, LOCALHOST, port, drives, state_dir)


@pytest.fixture
def serve():
    """Factory: `serve("generic:5", state_dir=None, bitrate=None, extra=())` starts
    `drivebus serve`, waits for `listening on` and returns a `Served`
    ((host, port) when unpacked). Teardown stops every server still running
    with SIGTERM and checks exit code 0."""
    started: list[Served] = []

    def start(*drives, state_dir=None, bitrate=None, port=None, extra=()):
        s = start_serve(
            *(drives or ("generic:5",)), state_dir=state_dir, bitrate=bitrate, port=port, extra=tuple(extra)
        )
        started.append(s)
        return s

    yield start
    errors = []
    for s in started:
        try:
            s.stop()
        except AssertionError as e:
            errors.append(str(e))
    assert not errors, "\n\n".join(errors)


@pytest.fixture
def served(serve) -> Served:
    """One `drivebus serve --drive generic:5`."""
    return serve("generic:5")


def connect(host: str, port: int) -> canopen.Network:
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.1  # quicker disconnect in teardown (default 1 s)
    net.connect(interface="socketcand", host=host, port=port, channel=CHANNEL)
    return net


@pytest.fixture
def networks():
    """Factory: `networks(host, port)` gives a canopen Network over socketcand;
    disconnected in teardown (before the server fixture stops the server)."""
    made: list[canopen.Network] = []

    def make(host, port):
        n = connect(host, port)
        made.append(n)
        return n

    yield make
    for n in made:
        try:
            n.disconnect()
        except Exception:  # noqa: BLE001 - teardown must go on
            pass


@pytest.fixture
def network(served, networks) -> canopen.Network:
    """canopen.Network(interface='socketcand') on the `served` generic:5 bus."""
    return networks(*served)


# --------------------------------------------------------------------------
# the EDS of the generic personality

_EXPORT: dict = {}


@pytest.fixture(scope="session")
def eds_path(tmp_path_factory) -> Path:
    """generic.eds: from `drivebus eds export --profile generic` when the CLI
    has it and it works, else the file in crates/personality/eds.
    (`test_eds_export_generic` fails if the export exists but is broken.)"""
    fallback = EDS_DIR / "generic.eds"
    if BIN.exists() and has_command("eds", "export"):
        out = tmp_path_factory.mktemp("eds") / "generic.eds"
        r = run_cli("eds", "export", "--profile", "generic", "--out", out)
        _EXPORT["result"] = r
        if r.returncode == 0 and out.exists() and out.stat().st_size > 0:
            return out
    return fallback


def remote_node(net: canopen.Network, node_id: int, eds, cls=canopen.RemoteNode):
    node = cls(node_id, str(eds))
    net.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
    return node


@pytest.fixture
def node(network, eds_path) -> canopen.RemoteNode:
    """RemoteNode 5 from the generic EDS on `network`."""
    return remote_node(network, 5, eds_path)


# --------------------------------------------------------------------------
# slcan pty emulator


class SlcanPty:
    def __init__(self, proc: Proc, path: str):
        self.proc, self.path = proc, path

    def stop(self) -> None:
        rc = self.proc.stop()
        assert rc == 0, f"`drivebus slcan-pty` exited {rc} after SIGTERM\n{self.proc.describe()}"


@pytest.fixture
def slcan_pty():
    """Factory: `slcan_pty("generic:5")` starts `drivebus slcan-pty` and
    returns its pty path; SIGTERM + exit code 0 in teardown."""
    started: list[SlcanPty] = []

    def start(*drives):
        require_command("slcan-pty")
        args = ["slcan-pty"]
        for d in drives or ("generic:5",):
            args += ["--drive", d]
        proc = Proc(args)
        try:
            m = proc.wait_line(r"slcan-pty\s+(/\S+)")
        except BaseException:
            proc.p.kill()
            proc.p.wait(timeout=5)
            raise
        s = SlcanPty(proc, m.group(1))
        started.append(s)
        return s

    yield start
    errors = []
    for s in started:
        try:
            s.stop()
        except AssertionError as e:
            errors.append(str(e))
    assert not errors, "\n\n".join(errors)


# --------------------------------------------------------------------------
# benchmark numbers (printed in the terminal summary; never asserted)

BENCH: list[dict] = []


@pytest.fixture
def bench():
    def record(name: str, value: float, unit: str, note: str = ""):
        BENCH.append({"name": name, "value": value, "unit": unit, "note": note})

    return record


def pytest_terminal_summary(terminalreporter):
    if not BENCH:
        return
    tr = terminalreporter
    tr.section("interop benchmarks (loopback; not asserted)")
    for b in BENCH:
        tr.write_line(f"{b['name']:<58} {b['value']:>12,.1f} {b['unit']:<8} {b['note']}")
    out = os.environ.get("INTEROP_BENCH_OUT")
    if out:
        Path(out).write_text(json.dumps(BENCH, indent=2))
