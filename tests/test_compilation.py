"""Compile timing from numba's events, and `regopack compile`."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import regopack
from regopack.cli import main
from regopack.compilation import VARIANTS, compile_kernels, compile_timer


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


def test_the_timer_stops_listening_after_an_error():
    @numba.njit(cache=False)
    def once(x):
        return x + 1

    with pytest.raises(RuntimeError), compile_timer() as timer:
        raise RuntimeError
    once(1)
    assert timer.functions == 0


@pytest.fixture(scope="module")
def compiled():
    steps: list[str] = []
    compile_kernels(lambda step, seconds: steps.append(step))
    return steps


def test_compile_kernels_reports_every_variant(compiled):
    assert compiled == [
        f"{label}: packed, analysed" if "3D" in label else f"{label}: packed, analysed, exported"
        for label, _ in VARIANTS
    ]


@pytest.mark.parametrize(
    "changes",
    [
        {"domain__width": 90.0, "domain__height": 70.0, "count": 90},
        {
            "domain__kind": "periodic",
            "domain__width": 90.0,
            "domain__height": 90.0,
            "count": 120,
            "phases__1__shape": {"kind": "disk"},
        },
        {"domain": {"kind": "circle", "radius": 40.0}, "count": 80, "insertion__order": "sweep"},
    ],
)
def test_after_compile_other_scenes_compile_nothing(compiled, changes):
    outcome = regopack.pack_and_summarise("small", **changes)
    regopack.analyze(outcome.packing)
    summary = outcome.summary
    assert summary["compile_time_s"] == 0.0
    assert summary["insertion_time_s"] == summary["wall_time_s"]


def test_compile_command_reports_every_step_and_the_cache(compiled, capsys):
    assert main(["compile"]) == 0
    out = capsys.readouterr().out
    assert "the sweep order: packed, analysed, exported" in out
    assert "cache:" in out and "kernel signatures" in out
    assert main(["compile", "--quiet"]) == 0
    assert capsys.readouterr().out == ""
