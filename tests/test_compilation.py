"""Compile timing from numba's events, and `regopack compile`."""

from __future__ import annotations

import numba
import numpy as np

import regopack
from regopack.cli import main
from regopack.compilation import TINY, compile_kernels, compile_timer


def test_the_timer_counts_a_compilation_once_and_not_a_second_call():
    @numba.njit(cache=False)
    def twice(x):
        return 2.0 * x

    with compile_timer() as first:
        twice(np.float64(1.5))
    assert first.functions >= 1 and first.seconds > 0
    with compile_timer() as second:
        twice(np.float64(2.5))
    assert second.functions == 0 and second.seconds == 0.0


def test_compile_kernels_covers_a_run_and_its_analyses(capsys):
    steps: list[str] = []
    compile_kernels(lambda step, seconds: steps.append(step))
    assert steps[0] == "packing polygons in a walled rectangle"
    assert any(s.startswith("analyses contacts") for s in steps)
    assert any(s.startswith("exports ") and "lammps" in s for s in steps)
    outcome = regopack.pack_and_summarise(
        "small", **{k.replace(".", "__"): v for k, v in TINY.items()}
    )
    summary = outcome.summary
    assert summary["compile_time_s"] == 0.0
    assert summary["insertion_time_s"] == summary["wall_time_s"]


def test_compile_command_reports_every_step_and_the_cache(capsys):
    assert main(["compile"]) == 0
    out = capsys.readouterr().out
    assert "packing the sweep order" in out
    assert "cache:" in out and "kernel signatures" in out
    assert main(["compile", "--quiet"]) == 0
    assert capsys.readouterr().out == ""
