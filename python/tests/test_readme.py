"""The in-process example of python/README.md and of the README's Python
section runs as written."""

from __future__ import annotations

import os
import re

import pytest

from conftest import ROOT


def example(readme: str, heading: str) -> str:
    text = (ROOT / readme).read_text(encoding="utf-8")
    at = text.index(heading)
    m = re.search(r"```python\n(.*?)```", text[at:], re.S)
    assert m, f"no python example under {heading} in {readme}"
    return m.group(1)


@pytest.mark.parametrize(
    "readme, heading",
    [
        ("python/README.md", "## The in-process bus"),
        ("README.md", "## Drive twins inside Python"),
    ],
)
def test_readme_example_runs(capsys, readme, heading):
    code = example(readme, heading)
    cwd = os.getcwd()
    os.chdir(ROOT)  # the example names the EDS relative to the repository
    try:
        exec(compile(code, readme, "exec"), {})
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("vendor-ID 0x")
    assert out[1].split()[:4] == ["akd", "1", "operational", "switch"]
    assert out[2].split()[:3] == ["dds6", "2", "pre-operational"]


def test_readme_control_example_runs(capsys):
    code = example("python/README.md", "## Inputs and faults at run time")
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        exec(compile(code, "python/README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    assert capsys.readouterr().out.splitlines() == ["EMCY ['0x7305']"]


def test_readme_sim_master_example_runs(capsys):
    code = example("python/README.md", "### PDOs, LSS, SYNC and CSP")
    exec(compile(code, "python/README.md", "exec"), {"drivebus": __import__("drivebus")})
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "500 targets on SYNC"
    assert out[1].endswith("TPDO1 frames") and int(out[1].split()[0]) >= 500


def test_root_readme_simulation_example_runs(capsys):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    at = text.index("## Drive twins inside Python")
    blocks = re.findall(r"```python\n(.*?)```", text[at : text.index("## Using virtual drives from Python")], re.S)
    assert len(blocks) == 2, "the in-process bus, then the simulation"
    exec(compile(blocks[1], "README.md", "exec"), {})
    end, position, *_ = capsys.readouterr().out.split()
    assert end == "target_reached" and abs(int(position) - 2000) <= 10


def test_python_readme_ethercat_simulation_example_runs():
    code = example("python/README.md", "### The EtherCAT line and its master in simulated time")
    scope: dict = {}
    exec(compile(code, "python/README.md", "exec"), scope)
    assert abs(scope["position"] - 4499) <= 3 and scope["statusword"] & 0x6F == 0x27
    assert scope["pcapng"][:4] == b"\x0a\x0d\x0d\x0a"  # a pcapng section header
