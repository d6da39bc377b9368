"""The warm-up that conftest.py starts on a cold cache asks for valid scenes."""

from __future__ import annotations

import importlib.util
import json
import os
from fnmatch import fnmatchcase
from pathlib import Path
from types import ModuleType

import kernel_warmup
import pytest

import regopack


def test_every_warmup_step_is_a_valid_scene() -> None:
    # the warm-up's output goes to a log file nobody reads: a step broken by a
    # renamed field would only make the suite slower, so it is checked here
    kinds = set()
    for steps in kernel_warmup.STAGE_STEPS:
        for changes, threads, _ in steps:
            resolved = regopack.scene("small", **{**kernel_warmup.TINY, **changes})
            kinds.add((resolved.insertion.kind, threads))
    assert ("available-arc", 2) in kinds and ("rsa", 1) in kinds
    assert ("available-surface", 1) in kinds


def test_the_warmup_has_the_steps_of_every_stage() -> None:
    # index 0 of STAGE_STEPS precedes the stages; the tests of stage n wait for index n
    conftest = _suite_conftest()
    assert len(kernel_warmup.STAGE_STEPS) == len(conftest.KERNEL_STAGES) + 1


def _suite_conftest() -> ModuleType:
    """Load ``tests/conftest.py`` under a name of its own (``conftest`` may be another one)."""
    path = Path(__file__).with_name("conftest.py")
    spec = importlib.util.spec_from_file_location("suite_conftest", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_stage_pattern_names_a_test_module_of_its_stage() -> None:
    # a renamed module would silently fall back to the first stage and compile
    # its kernels in the test process again
    conftest = _suite_conftest()
    here = Path(conftest.__file__).resolve().parent
    modules = list(here.rglob("test_*.py"))
    for n, patterns in enumerate(conftest.KERNEL_STAGES, start=1):
        for pattern in patterns:
            named = [m for m in modules if fnmatchcase(m.relative_to(here).as_posix(), pattern)]
            assert named, pattern
            assert any(conftest._stage(m, here) == n for m in named), pattern


def test_the_stages_follow_the_unlisted_modules_in_order() -> None:
    conftest = _suite_conftest()
    here = Path(conftest.__file__).resolve().parent
    names = [
        "cli/test_cli_end_to_end.py",
        "plugins/inserters/available_arc/test_sweep.py",
        "scene/test_schema.py",
        "plugins/analyzers/test_common.py",
        "plugins/analyzers/test_rdf.py",
        "plugins/analyzers/test_contacts.py",
        "plugins/shapes/test_octagon.py",
    ]
    assert [conftest._stage(here / n, here) for n in names] == [4, 3, 0, 1, 0, 2, 0]


def test_a_stage_waits_for_the_warmup_only_while_it_compiles_that_stage(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    conftest = _suite_conftest()

    class Compiling:
        """A warm-up process that has not exited."""

        def poll(self) -> None:
            return None

    progress = tmp_path / "progress"
    progress.write_text("2")
    monkeypatch.setattr(conftest, "_warmup", [Compiling()])
    monkeypatch.setattr(conftest, "_progress", [progress])
    monkeypatch.setattr(conftest, "_waited", {})
    monkeypatch.setattr(conftest, "WARMUP_WAIT_MAX", 0.3)
    conftest._wait_for_warmup(2)  # the warm-up has finished stage 2
    assert conftest._waited[2] < 0.2
    conftest._wait_for_warmup(3)  # still compiling stage 3: wait, at most WARMUP_WAIT_MAX
    assert conftest._waited[3] >= 0.3
    conftest._wait_for_warmup(4)  # after a wait that long the tests wait no more
    assert 4 not in conftest._waited


def test_two_warmup_processes_share_every_step_once() -> None:
    one = kernel_warmup.steps_of(0, 1)
    first, second = kernel_warmup.steps_of(0, 2), kernel_warmup.steps_of(1, 2)
    assert [list(s) for s in kernel_warmup.STAGE_STEPS] == one
    for n, steps in enumerate(one):
        assert sorted(map(repr, first[n] + second[n])) == sorted(map(repr, steps))
    assert any(second) and any(first)
    assert not any(kernel_warmup.steps_of(2, 3))  # a third process repeats nothing


def test_a_stage_waits_for_every_warmup_process_that_compiles_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    conftest = _suite_conftest()

    class Process:
        def __init__(self, code: int | None) -> None:
            self.code = code

        def poll(self) -> int | None:
            return self.code

    ahead, behind = tmp_path / "ahead", tmp_path / "behind"
    ahead.write_text("3")
    behind.write_text("1")
    monkeypatch.setattr(conftest, "_warmup", [Process(None), Process(None)])
    monkeypatch.setattr(conftest, "_progress", [ahead, behind])
    monkeypatch.setattr(conftest, "_waited", {})
    monkeypatch.setattr(conftest, "WARMUP_WAIT_MAX", 0.3)
    conftest._wait_for_warmup(1)  # both have finished stage 1
    assert conftest._waited[1] < 0.2
    conftest._wait_for_warmup(2)  # the second still compiles stage 2
    assert conftest._waited[2] >= 0.3
    monkeypatch.setattr(conftest, "_warmup", [Process(None), Process(1)])
    monkeypatch.setattr(conftest, "_waited", {})
    conftest._wait_for_warmup(3)  # the one behind has ended (failed): no wait for it
    assert conftest._waited[3] < 0.2


def test_a_worker_finds_the_warmup_its_controller_started(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    conftest = _suite_conftest()
    progress = tmp_path / "progress"
    progress.write_text("2")
    monkeypatch.setattr(conftest, "_warmup", [])
    monkeypatch.setenv("PYTEST_XDIST_WORKER", "gw0")
    monkeypatch.setenv(conftest.WARMUP_ENV, json.dumps([[os.getpid(), str(progress)]]))
    parts = conftest._warmup_parts()
    assert [(runs(), f) for runs, f in parts] == [(True, progress)]
    monkeypatch.setenv(conftest.WARMUP_ENV, "not json")
    assert conftest._warmup_parts() == []
    monkeypatch.delenv("PYTEST_XDIST_WORKER")
    monkeypatch.setenv(conftest.WARMUP_ENV, json.dumps([[os.getpid(), str(progress)]]))
    assert conftest._warmup_parts() == []  # not a worker: it starts its own
