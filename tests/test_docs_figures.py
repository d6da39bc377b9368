"""Every picture of the documentation says how to draw it again, with a script that runs."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SCRIPTS = sorted((DOCS / "scripts").glob("*.py"))


def figures_table() -> dict[str, str]:
    """Figure file name -> the 'drawn by' cell of the table in docs/index.md."""
    text = (DOCS / "index.md").read_text(encoding="utf-8")
    section = text.split("## The documentation's figures", 1)[1]
    rows: dict[str, str] = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`"):
            for name in re.findall(r"`([^`]+\.png)`", cells[0]):
                rows[name] = cells[2]
    return rows


def test_every_picture_is_listed_with_the_command_that_draws_it():
    table = figures_table()
    assert sorted(table) == sorted(p.name for p in (DOCS / "images").glob("*.png"))
    for name, command in table.items():
        script = re.search(r"python ((?:docs/scripts|benchmarks)/\w+\.py)", command)
        page = re.search(r"\]\(([\w/.-]+\.md)\)", command)  # or a page whose code draws it
        assert script or page, (name, command)
        assert (ROOT / script.group(1) if script else DOCS / page.group(1)).exists(), command


def test_no_figure_script_is_left_in_the_docs_folder():
    assert not list(DOCS.glob("make_*.py"))
    listed = (DOCS / "scripts" / "README.md").read_text(encoding="utf-8")
    assert SCRIPTS and all(f"`{p.name}`" in listed for p in SCRIPTS)


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_the_scripts_start(script):
    if script.name != "make_table1_figure.py":
        pytest.importorskip("vtk" if "export" in script.name else "porespy")
    done = subprocess.run(
        [sys.executable, str(script), "--help"], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "--packing" in done.stdout
