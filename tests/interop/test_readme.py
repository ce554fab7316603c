"""The README's Python recipe (canopen 2.4.1's BaseNode402 against
`drivebus serve --drive akd:1 --drive dds6:2`), run exactly as written in
an empty directory (after the README's `drivebus eds export` line), only on
a free port instead of 29536."""

from __future__ import annotations

import contextlib
import io
import os
import re

import pytest

from conftest import ROOT, run_cli


def readme_block(heading: str, lang: str) -> str:
    text = (ROOT / "README.md").read_text()
    at = text.index(heading)
    m = re.search(rf"```{lang}\n(.*?)```", text[at:], re.S)
    assert m, f"no {lang} block under {heading}"
    return m.group(1)


@pytest.mark.limit(90)
def test_python_recipe_runs_as_written(serve, tmp_path):
    export = readme_block("## Using virtual drives from Python", "sh").split()
    assert export[:2] == ["drivebus", "eds"], export
    out_at = export.index("--out") + 1
    export[out_at] = str(tmp_path / export[out_at])
    r = run_cli(*export[1:])
    assert r.returncode == 0, r.stderr
    code = readme_block("## Using virtual drives from Python", "python")
    # The README serves akd:1 and dds6:2 on the default port.
    srv = serve("akd:1", "dds6:2")
    code = code.replace("port=29536", f"port={srv.port}")
    out = io.StringIO()
    cwd = os.getcwd()
    os.chdir(tmp_path)  # not the clone: the recipe needs no file of it
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
    finally:
        os.chdir(cwd)
    m = re.search(r"position (-?\d+)", out.getvalue())
    assert m, out.getvalue()
    assert abs(int(m.group(1)) - 90000) <= 100, out.getvalue()
