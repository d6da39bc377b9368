"""The cylinder how-to runs as written, and its scene is the example file.

Its TOML block is part of ``docs/examples/cylinder.toml``; its commands run
in a fresh folder (holding a copy of the example at the same path) through
the function the ``regopack`` program calls, in order.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import tomllib
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
HOWTO = ROOT / "docs" / "how-to" / "cylinder-specimen.md"
EXAMPLE = ROOT / "docs" / "examples" / "cylinder.toml"
BLOCK = re.compile(r"^```(toml|sh)\n(.*?)^```", re.S | re.M)


def blocks(kind: str) -> list[str]:
    text = HOWTO.read_text(encoding="utf-8")
    return [m.group(2) for m in BLOCK.finditer(text) if m.group(1) == kind]


def _within(part: Any, whole: Any) -> bool:
    if isinstance(part, dict):
        return isinstance(whole, dict) and all(
            k in whole and _within(v, whole[k]) for k, v in part.items()
        )
    return bool(part == whole)


def test_the_toml_block_is_the_example_file() -> None:
    example = tomllib.loads(EXAMPLE.read_text(encoding="utf-8"))
    [block] = blocks("toml")
    assert _within(tomllib.loads(block), example)
    assert example["domain"]["kind"] == "cylinder"


def test_every_command_runs(tmp_path: Path) -> None:
    from regopack.cli import main

    (tmp_path / "docs" / "examples").mkdir(parents=True)
    shutil.copy(EXAMPLE, tmp_path / "docs" / "examples" / "cylinder.toml")
    lines = [line for block in blocks("sh") for line in block.splitlines() if line.strip()]
    assert len(lines) >= 4
    here = os.getcwd()
    os.chdir(tmp_path)
    try:
        for line in lines:
            words = shlex.split(line)
            assert words[0] == "regopack", line
            assert main(words[1:] + ["--quiet"] * (words[1] == "run")) in (0, None), line
    finally:
        os.chdir(here)
    run = tmp_path / "runs" / "cylinder-seed1"
    for name in (
        "packing.npz",
        "summary.json",
        "packing.py",
        "packing.bodies",
        "packing.vtu",
        "packing.in",
    ):
        assert (run / name).is_file(), name
    import json

    summary = json.loads((run / "summary.json").read_text(encoding="utf-8"))
    assert summary["verify"]["ok"] and summary["verify"]["outside"] == 0
    assert summary["placed"] > 10


@pytest.mark.parametrize("page", ["docs/index.md", "mkdocs.yml"])
def test_the_howto_is_listed(page: str) -> None:
    assert "cylinder-specimen.md" in (ROOT / page).read_text(encoding="utf-8")
