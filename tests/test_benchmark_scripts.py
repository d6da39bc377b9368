"""Benchmark scripts stop on a mistake with one line, before they pack anything."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--columns", "0"], "--columns must be 1 or more"),
        (["--size", "nan"], "--size and --ring-width must be positive"),
        (["--count", "-3"], "--count must be 0 or more"),
        (["--scene", "no-such-scene"], "no-such-scene: no such scene file"),
        (["--size", "inf"], "domain.width = inf"),
    ],
)
def test_study_homogeneity_refuses_bad_input_in_one_line(args: list[str], says: str) -> None:
    run = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "study_homogeneity.py"), *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("study_homogeneity.py: error:") and says in last, last
    assert "seed" not in run.stdout  # nothing packed
