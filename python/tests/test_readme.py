"""python/README.md's in-process example runs as written."""

from __future__ import annotations

import os
import re

from conftest import ROOT


def test_readme_example_runs(capsys):
    text = (ROOT / "python" / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "no python example in python/README.md"
    cwd = os.getcwd()
    os.chdir(ROOT)  # the example names the EDS relative to the repository
    try:
        exec(compile(blocks[0], "python/README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("vendor-ID 0x")
    assert out[1].split()[:4] == ["akd", "1", "operational", "switch"]
    assert out[2].split()[:3] == ["dds6", "2", "pre-operational"]
