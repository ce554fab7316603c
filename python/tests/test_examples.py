"""Every example of python/examples runs, as its docstring says to run it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_akd_profile_position_example_moves_to_the_target():
    r = subprocess.run(
        [sys.executable, str(EXAMPLES / "akd_profile_position.py")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    position = int(r.stdout.split("position", 1)[1].split()[0])
    assert abs(position - 90_000) <= 100, r.stdout


def test_emcy_fault_handling_example_passes():
    r = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(EXAMPLES / "test_emcy_fault_handling.py")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 passed" in r.stdout, r.stdout


def test_pysoem_csp_example_reaches_op_and_follows_the_ramp():
    if os.geteuid() != 0:
        pytest.skip(f"the pysoem example needs root for its namespace and AF_PACKET (euid {os.geteuid()})")
    r = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", str(EXAMPLES / "test_pysoem_csp.py")],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 passed" in r.stdout, r.stdout


def test_ethercat_simulation_example_homes_moves_and_streams():
    r = subprocess.run(
        [sys.executable, str(EXAMPLES / "ethercat_simulation.py")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert "DC SYNC0: True" in r.stdout, r.stdout
    moved = int(r.stdout.split("moved to", 1)[1].split()[0])
    assert abs(moved - 4000) <= 10, r.stdout
    assert "0 bad working counters" in r.stdout, r.stdout
