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


SIM_DEMO = SCRIPT.parent / "sim_demo.py"


def test_sim_demo_script_runs_the_demo_scenario():
    # A short sine: the whole scenario, every step checked by the script.
    r = subprocess.run(
        [sys.executable, str(SIM_DEMO), "--sine-seconds", "0.2"], capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    words = r.stdout.split()
    assert (words[0], words[3], words[6]) == ("simulated", "in", "wall:"), r.stdout
    simulated, wall = float(words[1]), float(words[4])
    assert simulated > 10 and wall > 0, r.stdout
