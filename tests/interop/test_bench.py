"""Throughput over `drivebus serve` (socketcand, loopback). Numbers go to the
terminal summary (and to $INTEROP_BENCH_OUT as JSON); only correctness is
asserted. Deselected by default: `INTEROP_BENCH=1 tests/interop/run -m bench`.

* drivebus's master (crates/master, via tests/interop/bench-master) vs
  python canopen's SDO client, same server, same objects;
* frames/s the hub relays among 10 python-can socketcand clients.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import threading
import time

import can
import pytest

from conftest import CHANNEL, ROOT, remote_node

pytestmark = pytest.mark.bench

NODE = 5
SECONDS = float(os.environ.get("INTEROP_BENCH_SECONDS", "2"))
BLOCK = 102_400
BENCH_DIR = ROOT / "tests" / "interop" / "bench-master"
BENCH_TARGET = ROOT / "target" / "interop-bench"
BENCH_BIN = BENCH_TARGET / "release" / "drivebus-interop-bench"


@pytest.fixture(scope="session")
def master_bench_bin() -> str:
    r = subprocess.run(
        ["cargo", "build", "-q", "--release", "--manifest-path", str(BENCH_DIR / "Cargo.toml")],
        env={**os.environ, "CARGO_TARGET_DIR": str(BENCH_TARGET)},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert r.returncode == 0, f"building bench-master failed:\n{r.stderr[-4000:]}"
    return str(BENCH_BIN)


def rate(fn, seconds: float = SECONDS) -> float:
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        fn(n)
        n += 1
    return n / (time.perf_counter() - t0)


@pytest.mark.limit(900)
def test_bench_drivebus_master_sdo(serve, bench, master_bench_bin):
    srv = serve("generic:5")
    r = subprocess.run(
        [master_bench_bin, srv.url, str(NODE), str(SECONDS), str(BLOCK)], capture_output=True, text=True, timeout=120
    )
    assert r.returncode == 0, f"stdout: {r.stdout}\nstderr: {r.stderr}"
    j = json.loads(r.stdout.strip().splitlines()[-1])
    bench("drivebus master: expedited upload 1000h", j["expedited_upload_per_s"], "SDO/s")
    bench("drivebus master: expedited download 1017h", j["expedited_download_per_s"], "SDO/s")
    bench(f"drivebus master: block download {BLOCK // 1024} KiB (CRC)", j["block_download_kB_per_s"], "kB/s")
    bench(f"drivebus master: block upload {BLOCK // 1024} KiB (CRC)", j["block_upload_kB_per_s"], "kB/s")


@pytest.mark.limit(120)
def test_bench_python_canopen_sdo(serve, networks, eds_path, bench):
    srv = serve("generic:5")
    node = remote_node(networks(*srv), NODE, eds_path)
    dev = node.sdo.upload(0x1000, 0)  # also lets the rawmode grace pass

    def up(_):
        assert node.sdo.upload(0x1000, 0) == dev

    def down(i):
        node.sdo.download(0x1017, 0, (i % 1000).to_bytes(2, "little"))

    bench("python canopen: expedited upload 1000h", rate(up), "SDO/s")
    bench("python canopen: expedited download 1017h", rate(down), "SDO/s")
    node.sdo.download(0x1017, 0, b"\x00\x00")

    blob = bytes(i % 256 for i in range(BLOCK))
    t0 = time.perf_counter()
    with node.sdo.open(0x1F50, 1, "wb", size=len(blob), block_transfer=True) as f:
        f.write(blob)
    down_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    with node.sdo.open(0x1F50, 1, "rb", block_transfer=True) as f:
        back = f.read()
    up_s = time.perf_counter() - t0
    assert back == blob
    bench(f"python canopen: block download {BLOCK // 1024} KiB (CRC)", len(blob) / 1000 / down_s, "kB/s")
    bench(f"python canopen: block upload {BLOCK // 1024} KiB (CRC)", len(blob) / 1000 / up_s, "kB/s")

    seg = blob[:10_240]
    t0 = time.perf_counter()
    node.sdo.download(0x1F50, 1, seg, force_segment=True)
    seg_down = time.perf_counter() - t0
    t0 = time.perf_counter()
    assert node.sdo.upload(0x1F50, 1) == seg
    seg_up = time.perf_counter() - t0
    bench("python canopen: segmented download 10 KiB", len(seg) / 1000 / seg_down, "kB/s")
    bench("python canopen: segmented upload 10 KiB", len(seg) / 1000 / seg_up, "kB/s")


WINDOW = 2000  # deliveries in flight; keeps slow Python readers from being dropped as too slow


@pytest.mark.limit(60)
@pytest.mark.parametrize("bitrate", [None, 1_000_000], ids=["unpaced", "paced-1M"])
def test_bench_hub_relay_10_clients(serve, bench, bitrate):
    """10 python-can clients send 8-byte frames (flow-controlled so that at
    most WINDOW deliveries are in flight) for 3 s; the hub relays every frame
    to the 9 others. Reported: deliveries/s summed over the clients, and bus
    frames/s (= deliveries / 9). Python's parsing is the limit here."""
    srv = serve("generic:5", bitrate=bitrate)
    buses = [can.Bus(interface="socketcand", host=srv.host, port=srv.port, channel=CHANNEL) for _ in range(10)]
    time.sleep(0.2)  # rawmode grace of every client
    duration = 3.0
    stop = threading.Event()
    sent = [0] * 10
    got = [0] * 10
    bad = []

    def sender(i):
        msg = can.Message(arbitration_id=0x110 + i, data=bytes([i] * 8), is_extended_id=False)
        try:
            while not stop.is_set():
                if sum(sent) * 9 - sum(got) > WINDOW:
                    time.sleep(0.0005)
                    continue
                buses[i].send(msg)
                sent[i] += 1
        except (can.CanError, OSError) as e:
            bad.append(f"send {i}: {e!r}")

    def receiver(i):
        try:
            while not stop.is_set():
                m = buses[i].recv(timeout=0.1)
                if m is None or m.arbitration_id & 0x780 == 0x700:  # the drive's boot-up/heartbeat
                    continue
                if not 0x110 <= m.arbitration_id <= 0x119 or m.arbitration_id == 0x110 + i or len(m.data) != 8:
                    bad.append(f"client {i} got {m}")
                    continue
                got[i] += 1
        except (can.CanError, OSError) as e:
            bad.append(f"recv {i}: {e!r}")

    threads = [threading.Thread(target=f, args=(i,), daemon=True) for i in range(10) for f in (sender, receiver)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    time.sleep(duration)
    stop.set()
    for t in threads:
        t.join(timeout=5)
    elapsed = time.perf_counter() - t0
    for b in buses:
        b.shutdown()
    assert not bad, bad[:5]
    assert sum(got) > 0
    assert sum(got) <= sum(sent) * 9
    label = "unpaced" if bitrate is None else f"--bitrate {bitrate}"
    bench(f"hub, 10 python-can clients ({label}): deliveries", sum(got) / elapsed, "frames/s")
    bench(f"hub, 10 python-can clients ({label}): bus frames", sum(got) / 9 / elapsed, "frames/s")


@pytest.mark.limit(60)
def test_bench_hub_relay_10_raw_clients(serve, bench):
    """The hub itself, without python-can's per-frame cost: 10 raw socketcand
    TCP clients (same protocol), each sending batches of `< send >` and
    counting `< frame` tokens, flow-controlled like the test above."""
    srv = serve("generic:5")
    socks = []
    for _ in range(10):
        s = socket.create_connection((srv.host, srv.port), timeout=5)
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        assert s.recv(256) == b"< hi >"
        s.sendall(f"< open {CHANNEL} >".encode())
        assert s.recv(256) == b"< ok >"
        s.sendall(b"< rawmode >")
        assert s.recv(256) == b"< ok >"
        socks.append(s)
    time.sleep(0.2)
    stop = threading.Event()
    sent = [0] * 10
    got = [0] * 10
    bad = []
    BATCH = 50

    def sender(i):
        chunk = "".join(f"< send {0x110 + i:03X} 8 1 2 3 4 5 6 7 8 >" for _ in range(BATCH)).encode()
        try:
            while not stop.is_set():
                if sum(sent) * 9 - sum(got) > WINDOW * 5:
                    time.sleep(0.0002)
                    continue
                socks[i].sendall(chunk)
                sent[i] += BATCH
        except OSError as e:
            bad.append(f"send {i}: {e!r}")

    def receiver(i):
        socks[i].settimeout(0.1)
        tail = b""
        try:
            while not stop.is_set():
                try:
                    data = socks[i].recv(65536)
                except socket.timeout:
                    continue
                if not data:
                    bad.append(f"client {i}: server closed")
                    return
                data = tail + data
                cut = data.rfind(b">") + 1
                got[i] += data[:cut].count(b"< frame 11")
                tail = data[cut:]
        except OSError as e:
            bad.append(f"recv {i}: {e!r}")

    threads = [threading.Thread(target=f, args=(i,), daemon=True) for i in range(10) for f in (sender, receiver)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    time.sleep(3.0)
    stop.set()
    for t in threads:
        t.join(timeout=5)
    elapsed = time.perf_counter() - t0
    for s in socks:
        s.close()
    assert not bad, bad[:5]
    assert 0 < sum(got) <= sum(sent) * 9
    bench("hub, 10 raw socketcand clients (unpaced): deliveries", sum(got) / elapsed, "frames/s")
    bench("hub, 10 raw socketcand clients (unpaced): bus frames", sum(got) / 9 / elapsed, "frames/s")
