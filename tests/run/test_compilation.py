"""Compile timing from numba's events, and `regopack compile`."""

from __future__ import annotations

import threading

import numba
import numpy as np
import pytest

import regopack
from regopack.api.warmup import VARIANTS, compile_kernels
from regopack.cli import main
from regopack.run.compilation import compile_timer


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


def test_a_helper_threads_compilation_is_told_apart_from_the_callers():
    """The partner thread compiles while the search packs: only the caller's own
    compilations are its compile time; ``seconds`` covers every thread's."""

    @numba.njit(cache=False)
    def elsewhere(x):
        return x - 3.0

    @numba.njit(cache=False)
    def here(x):
        return x * 5.0

    with compile_timer() as timer:
        helper = threading.Thread(target=elsewhere, args=(np.float64(1.0),))
        helper.start()
        helper.join()
    assert timer.functions >= 1 and timer.seconds > 0
    assert timer.own_seconds == 0.0 and timer.elsewhere
    with compile_timer() as timer:
        here(np.float64(1.0))
    assert timer.own_seconds > 0 and timer.seconds == timer.own_seconds
    assert not timer.elsewhere


def test_a_run_takes_only_its_own_threads_compilation_off_its_insertion_time(monkeypatch):
    """A helper's compilation overlaps the insertion: the insertion time keeps it, and
    the summary says that this run's time is not the usual one."""
    from contextlib import contextmanager

    from regopack.run import pipeline as run_module
    from regopack.run.compilation import CompileTime

    timers = iter([CompileTime(seconds=50.0, own_seconds=0.0), CompileTime()])

    @contextmanager
    def fake_timer():
        yield next(timers)

    monkeypatch.setattr(run_module, "compile_timer", fake_timer)
    tiny = {"domain__width": 60.0, "domain__height": 60.0, "count": 40}
    summary = regopack.pack_and_summarise("small", **tiny).summary
    assert summary["insertion_time_s"] == summary["wall_time_s"] > 0
    assert summary["compile_time_s"] == 50.0
    assert "another thread" in summary["insertion_time_note"]
    quiet = regopack.pack_and_summarise("small", **tiny).summary  # nothing compiled
    assert "insertion_time_note" not in quiet


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
