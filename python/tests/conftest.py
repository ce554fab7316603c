"""Shared helpers of the Python package's tests."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EDS_DIR = ROOT / "crates" / "personality" / "eds"
_channels = itertools.count()

# test_plugin.py runs the plugin in fresh pytest runs.
pytest_plugins = ["pytester"]


@pytest.fixture
def channel(request) -> str:
    """A virtual bus of this test's own: tests do not hear each other."""
    return f"test-{request.node.name}-{next(_channels)}"


@pytest.fixture
def akd_eds() -> str:
    return str(EDS_DIR / "akd.eds")
