"""The Python tutorial runs as written: every Python block, in order, in one namespace."""

from __future__ import annotations

import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial" / "python.md"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def test_the_tutorial_has_python_blocks():
    assert len(BLOCK.findall(TUTORIAL.read_text(encoding="utf-8"))) >= 8


def test_every_block_of_the_python_tutorial_runs(tmp_path, capsys):
    namespace: dict[str, object] = {"__name__": "__tutorial__"}
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for k, text in enumerate(BLOCK.findall(TUTORIAL.read_text(encoding="utf-8"))):
            exec(compile(text, f"{TUTORIAL.name}, python block {k + 1}", "exec"), namespace)
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert "scene(domain__width=...): domain.width = -5: Input should be greater than 0" in out
    assert (tmp_path / "packing.png").is_file()
    assert (tmp_path / "lammps" / "packing.in").is_file()
    assert (tmp_path / "runs" / "small-eta5" / "summary.json").is_file()
    assert (tmp_path / "runs" / "eta-tutorial" / "results.csv").is_file()
