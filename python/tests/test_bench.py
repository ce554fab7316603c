"""The throughput benchmark (python/bench/throughput.py, figures in
BENCHMARKS.md) runs: a short run of both interfaces, every frame through."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "bench" / "throughput.py"


def test_throughput_script_runs_both_interfaces():
    r = subprocess.run(
        [sys.executable, str(SCRIPT), "--frames", "3000"], capture_output=True, text=True, timeout=120
    )
    assert r.returncode == 0, r.stderr
    rows = {line.split()[0]: line.split()[1:] for line in r.stdout.splitlines()[1:]}
    assert set(rows) == {"drivebus", "virtual"}, r.stdout
    for rates in rows.values():
        assert all(float(x.replace(",", "")) > 0 for x in rates), r.stdout
