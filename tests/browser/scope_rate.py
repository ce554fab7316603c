"""Issue 19 §5: the scope's end-to-end latency and the rate it sustains.

Runs `drivebus serve --drive akd:1 --http` with the AKD's four default
TPDOs (6041h; 6041h, 6061h; 6041h, 6064h; 6041h, 606Ch) sent at every SYNC,
SYNC every 1 ms from `drivebus produce --sync 1`, and the page in headless
Chromium subscribed to 1:6041, 1:6061, 1:6064, 1:606C: four channels at
1 kHz. Reports, as one JSON object:

- rate: samples per second per channel, the server's dropped messages
  (its `status`), the page's own drops, reconnects; every `--every` s the
  server's RSS and the page's JS heap (memory growth = last minus the
  first after the warm-up);
- latency: the stream's bare echo (a `ping` through the same queue,
  round trip), the clock offset from the fastest echo, and per sample
  (server decode of the TPDO, `t`) -> page receipt and -> the next
  animation frame drawn after it; median and 99th percentile, and the
  median receipt latency as a multiple of the median echo round trip.

    DRIVEBUS_BIN=target/release/drivebus tests/browser/.venv/bin/python tests/browser/scope_rate.py --seconds 600
"""

import argparse
import json
import os
import re
import socket
import statistics
import subprocess
import sys
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service

CHANNELS = "1:6041, 1:6061, 1:6064, 1:606C"

# Injected into the page: counts every sample per channel from the page's
# own socket (`ws` of app.js), keeps latencies, answers pings.
PROBE = r"""
const P = window.__probe = { n: {}, syncs: 0, recv: [], draw: [], pings: [], status: null, sock: ws, pending: [], keep: arguments[0] };
ws.addEventListener("message", (m) => {
  const now = performance.now();
  const msg = JSON.parse(m.data);
  if (msg.type === "sample") {
    const k = `${msg.node}:${msg.index}:${msg.sub}`;
    P.n[k] = (P.n[k] || 0) + 1;
    if (P.keep) {
      P.recv.push([now, msg.t]);
      if (!P.pending.length) requestAnimationFrame((ft) => { const d = performance.now(); for (const t of P.pending) P.draw.push([d, t]); P.pending = []; });
      P.pending.push(msg.t);
    }
  } else if (msg.type === "frame" && msg.id === "080") {
    P.syncs += 1;
  } else if (msg.type === "pong") {
    P.pings.push([msg.ping, now, msg.t]);
  } else if (msg.type === "status") {
    P.status = msg;
  }
});
"""


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        return int(re.search(r"VmRSS:\s+(\d+)", f.read()).group(1))


class Bench:
    """The serving process, the SYNC producer and the browser; `close()` ends all three."""

    def __init__(self, binary, sync_by="produce"):
        self.binary = binary
        listen = f"127.0.0.1:{free_port()}"
        self.serve = subprocess.Popen(
            [binary, "serve", "--listen", listen, "--drive", "akd:1", "--http", "127.0.0.1:0"],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )
        line = self.serve.stdout.readline()
        m = re.search(r"page on (http://\S+/)", line)
        if not m:
            raise RuntimeError(f"serve printed no page URL: {line!r}")
        self.url = m.group(1)
        for sub in range(4):  # TPDO1..4 at every SYNC
            self.put(f"/api/nodes/1/sdo/{0x1800 + sub:04X}/2", 1)
        self.put("/api/nodes/1/sdo/1017/0", 50)
        self.post("/api/nodes/1/nmt", {"command": "start"})
        # `produce --sync 1` runs the master's SYNC producer on tokio's
        # millisecond timer, which a loaded host wakes late (it then skips);
        # `gen` keeps absolute 1 ms deadlines and catches up.
        producer = (["produce", "--sync", "1"] if sync_by == "produce"
                    else ["gen", "-I", "080", "-L", "0", "-g", "1"])
        self.sync = subprocess.Popen(
            [binary, "--bus", f"socketcand://{listen}/can0", *producer],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
        opts = Options()
        opts.binary_location = "/usr/bin/chromium"
        for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                  "--window-size=1280,1080", "--enable-precise-memory-info"):
            opts.add_argument(a)
        self.browser = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)

    def request(self, method, path, body):
        req = urllib.request.Request(self.url.rstrip("/") + path, data=json.dumps(body).encode(), method=method,
                                     headers={"content-type": "application/json"})
        with urllib.request.urlopen(req, timeout=30) as r:
            return json.load(r)

    def put(self, path, value):
        return self.request("PUT", path, {"value": value})

    def post(self, path, body):
        return self.request("POST", path, body)

    def js(self, expr, *args):
        return self.browser.execute_script("return " + expr, *args)

    def open_page(self, keep_latency):
        b = self.browser
        b.get(self.url)
        deadline = time.time() + 30
        while not self.js("typeof ws !== 'undefined' && ws.readyState === 1"):
            if time.time() > deadline:
                raise RuntimeError("the page's stream did not open")
            time.sleep(0.1)
        b.execute_script(PROBE, keep_latency)

    def subscribe(self):
        b = self.browser
        for id_, v in (("scope-channels", CHANNELS), ("scope-period", "1"), ("scope-window", "10")):
            el = b.find_element("id", id_)
            el.clear()
            el.send_keys(v)
        b.find_element("css selector", '#scope-form button[type="submit"]').click()
        # The SYNCs the server's master receives: a sample per channel is due for each.
        b.execute_script("window.__probe.sock.send(JSON.stringify({frames: {ids: ['080']}}))")

    def counts(self):
        return self.js("""(() => { const P = window.__probe; return {n: P.n, syncs: P.syncs, status: P.status,
            page_dropped: (document.getElementById('page-dropped').textContent.match(/\\d+/) || [0])[0] * 1,
            reconnected: P.sock !== ws, heap: performance.memory ? performance.memory.usedJSHeapSize : null}; })()""")

    def close(self):
        self.browser.quit()
        for p in (self.sync, self.serve):
            p.terminate()
            p.wait(timeout=10)


def wait_rate(bench, limit_s=60):
    """Until every channel gets samples (the node operational, its TPDOs at every SYNC)."""
    deadline = time.time() + limit_s
    while time.time() < deadline:
        n = bench.counts()["n"]
        if len(n) == 4:
            time.sleep(1)
            m = bench.counts()["n"]
            if all(m[k] - n[k] > 300 for k in n):
                return
        time.sleep(0.5)
    raise RuntimeError(f"four channels at SYNC rate not seen: {bench.counts()}")


def run_rate(bench, seconds, every):
    bench.open_page(False)
    bench.subscribe()
    wait_rate(bench)
    c0, t0 = bench.counts(), time.time()
    memory = []
    next_mem = t0
    while True:
        now = time.time()
        if now >= next_mem:
            c = bench.counts()
            memory.append({"t_s": round(now - t0, 1), "server_rss_kib": rss_kib(bench.serve.pid), "page_heap_bytes": c["heap"]})
            next_mem += every
        if now - t0 >= seconds:
            break
        time.sleep(min(1.0, max(0.05, next_mem - time.time())))
    c1, t1 = bench.counts(), time.time()
    rates = {k: round((c1["n"][k] - c0["n"].get(k, 0)) / (t1 - t0), 1) for k in c1["n"]}
    syncs = c1["syncs"] - c0["syncs"]
    # A sample per channel per SYNC; the last SYNC's TPDOs may be on their way.
    missing = {k: syncs - (c1["n"][k] - c0["n"].get(k, 0)) for k in c1["n"]}
    first = memory[min(1, len(memory) - 1)]
    return {
        "seconds": round(t1 - t0, 1),
        "sync_rate": round(syncs / (t1 - t0), 1),
        "rate_per_channel": rates,
        "missing_per_channel": missing,
        "server_dropped": (c1["status"] or {}).get("dropped"),
        "page_dropped": c1["page_dropped"],
        "reconnected": c1["reconnected"],
        "server_rss_growth_kib": memory[-1]["server_rss_kib"] - first["server_rss_kib"],
        "page_heap_growth_bytes": (memory[-1]["page_heap_bytes"] or 0) - (first["page_heap_bytes"] or 0),
        "memory": memory,
    }


def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(p / 100 * len(xs)))]


def send_pings(bench, seconds):
    """Pings every 50 ms for `seconds`; the pongs are in the probe."""
    t0 = time.time()
    while time.time() - t0 < seconds:
        bench.js("(() => { window.__probe.sock.send(JSON.stringify({ping: performance.now()})); })()")
        time.sleep(0.05)
    time.sleep(0.5)


def run_latency(bench, seconds):
    bench.open_page(True)
    # The bare echo: the stream idle (no subscription yet).
    send_pings(bench, min(seconds, 5))
    bare = [got - sent for sent, got, _ in bench.js("window.__probe.pings")]
    bench.subscribe()
    wait_rate(bench)
    bench.js("(() => { const P = window.__probe; P.recv = []; P.draw = []; P.pings = []; })()")
    send_pings(bench, seconds)
    pings, recv, draw = bench.js("[window.__probe.pings, window.__probe.recv, window.__probe.draw]")
    rtt = [got - sent for sent, got, _ in pings]
    # The server's clock minus the page's, from the fastest echo (its half-way point).
    sent, got, t_server = min(pings, key=lambda p: p[1] - p[0])
    offset = t_server - (sent + got) / 2
    lat_recv = [page + offset - t for page, t in recv]
    lat_draw = [page + offset - t for page, t in draw]
    med = lambda xs: round(statistics.median(xs), 3)
    return {
        "seconds": seconds, "pings": len(pings), "samples": len(recv),
        "bare_echo_rtt_ms": {"median": med(bare), "p99": round(pct(bare, 99), 3), "min": round(min(bare), 3)},
        "echo_rtt_under_load_ms": {"median": med(rtt), "p99": round(pct(rtt, 99), 3), "min": round(min(rtt), 3)},
        "receipt_latency_ms": {"median": med(lat_recv), "p99": round(pct(lat_recv, 99), 3)},
        "drawn_latency_ms": {"median": med(lat_draw), "p99": round(pct(lat_draw, 99), 3)},
        "receipt_over_bare_echo_rtt": round(statistics.median(lat_recv) / statistics.median(bare), 2),
        "drawn_over_bare_echo_rtt": round(statistics.median(lat_draw) / statistics.median(bare), 2),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=600, help="how long the rate runs (default 10 min)")
    ap.add_argument("--every", type=float, default=60, help="memory sampling period, s")
    ap.add_argument("--latency-seconds", type=float, default=20, help="how long latency is measured (0: not)")
    ap.add_argument("--sync-by", choices=["produce", "gen"], default="produce",
                    help="SYNC from the master's producer or from `gen` on absolute 1 ms deadlines")
    a = ap.parse_args()
    binary = os.environ.get("DRIVEBUS_BIN", "target/release/drivebus")
    out = {"binary": binary, "machine": {"cpus": os.cpu_count(), "uname": " ".join(os.uname())}}
    if a.latency_seconds > 0:
        b = Bench(binary)
        try:
            out["latency"] = run_latency(b, a.latency_seconds)
        finally:
            b.close()
    if a.seconds > 0:
        b = Bench(binary, a.sync_by)
        try:
            out["rate"] = run_rate(b, a.seconds, a.every)
        finally:
            b.close()
    json.dump(out, sys.stdout, indent=1)
    print()
    rate = out.get("rate")
    return 1 if rate and dropped(rate) else 0


def dropped(rate):
    """Whether samples were lost anywhere (the server's queue, the page, a reconnect, or fewer than SYNCs)."""
    late = any(abs(m) > 2 for m in rate["missing_per_channel"].values())
    return bool(rate["server_dropped"] or rate["page_dropped"] or rate["reconnected"] or late)


if __name__ == "__main__":
    sys.exit(main())
