"""Runs killed while they write: the output folder holds the old run or the new one.

Each test starts ``regopack`` in a subprocess with ``REGOPACK_TEST_PAUSE_BEFORE``
naming a step of the writing; the process stops there (saying so on standard
error), the test sends a signal, and checks the folder: the complete previous
run or the complete new one, never a mix, and no temporary left once the next
run is done.
"""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

import regopack.registry.manager
from regopack.base.outdir import PAUSE_ENV
from regopack.cli import main
from regopack.packing.core import load

HERE = Path(__file__).resolve().parent
FAKE_CLI = HERE / "fake_regopack.py"
TIMEOUT = 120.0

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def _default_sigint() -> None:
    """Give the child the default SIGINT, which a suite run as a background job ignores."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class Paused:
    """A ``regopack`` subprocess, stopped before a step of its writing."""

    def __init__(self, argv: list[str], step: str, cwd: Path, *, fake: bool = True) -> None:
        command = [sys.executable, str(FAKE_CLI)] if fake else [sys.executable, "-m", "regopack"]
        self.proc = subprocess.Popen(
            [*command, *argv],
            cwd=cwd,
            env={**os.environ, PAUSE_ENV: step},
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=_default_sigint,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        self.seen: list[str] = []
        while True:
            line = self._next()
            if line is None:
                self.proc.wait()
                pytest.fail(f"exited with {self.proc.returncode} before {step}: {self.seen}")
            if line == f"regopack: paused before {step} ({PAUSE_ENV})":
                break

    def _read(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def _next(self) -> str | None:
        try:
            line = self.lines.get(timeout=TIMEOUT)
        except queue.Empty:
            self.proc.kill()
            pytest.fail(f"no output for {TIMEOUT} s: {self.seen}")
        if line is not None:
            self.seen.append(line)
        return line

    def stop(self, signum: int) -> tuple[int, list[str]]:
        """Send ``signum``; return the exit status and the other lines on standard error."""
        self.proc.send_signal(signum)
        try:
            status = self.proc.wait(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise
        while self._next() is not None:
            pass
        return status, [line for line in self.seen if "paused before" not in line]


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its content."""
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def assert_one_run(folder: Path, seed: int, files: list[str]) -> None:
    """``folder`` holds exactly one complete run of ``seed``."""
    assert sorted(p.name for p in folder.iterdir()) == sorted([".regopack", *files])
    assert json.loads((folder / "summary.json").read_text())["seed"] == seed
    assert load(folder / "packing.npz").seed == seed


@pytest.fixture(autouse=True)
def in_tmp_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every command of a test runs in its temporary folder."""
    monkeypatch.chdir(tmp_path)


@pytest.fixture
def fakes(monkeypatch: pytest.MonkeyPatch) -> None:
    """In this process too, ``regopack`` sees the fakes of ``fake_regopack.py``."""
    sys.path.insert(0, str(HERE))
    try:
        import fake_regopack
    finally:
        sys.path.remove(str(HERE))
    monkeypatch.setattr(regopack.registry.manager, "default_registry", fake_regopack.registry)


def run(*argv: str) -> None:
    assert main([*argv, "--quiet"] if argv[0] == "run" else list(argv)) == 0


def test_sigkill_between_the_packing_and_the_summary_keeps_the_old_run(tmp_path: Path) -> None:
    out = tmp_path / "out"
    scene = ["run", "small", "--set", "count=60", "--out", str(out)]
    run(*scene, "--seed", "1")
    before = snapshot(out)

    paused = Paused([*scene, "--seed", "2", "--quiet"], "summary", tmp_path, fake=False)
    assert paused.stop(signal.SIGKILL)[0] == -signal.SIGKILL
    assert snapshot(out) == before
    assert_one_run(out, 1, ["packing.npz", "summary.json"])
    assert len(list(tmp_path.glob("out.tmp-*"))) == 1  # what the kill left beside the folder

    run(*scene, "--seed", "2")
    assert_one_run(out, 2, ["packing.npz", "summary.json"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize(
    ("signum", "step", "status", "message"),
    [
        (signal.SIGTERM, "exports", 143, "regopack: terminated; no partial files were written"),
        (signal.SIGTERM, "swap", 143, "regopack: terminated; no partial files were written"),
        (signal.SIGINT, "swap", 130, "regopack: interrupted; no partial files were written"),
    ],
)
def test_sigterm_and_sigint_leave_the_old_run_and_no_temporary(
    tmp_path: Path, fakes: None, signum: int, step: str, status: int, message: str
) -> None:
    out = tmp_path / "out"
    scene = ["run", "small", "--set", "count=30", "--out", str(out)]
    more = ["--set", 'outputs.exports=["vtk", "csv"]']
    run(*scene, "--seed", "1")
    before = snapshot(out)

    paused = Paused([*scene, *more, "--seed", "2", "--quiet"], step, tmp_path)
    assert paused.stop(signum) == (status, [message])
    assert snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]

    run(*scene, *more, "--seed", "2")
    exports = ["packing.vtp", "packing.csv", "packing_vertices.csv", "packing_meta.json"]
    assert_one_run(out, 2, ["packing.npz", "summary.json", *exports])
    assert json.loads((out / "packing_meta.json").read_text())["seed"] == 2


def test_a_killed_analysis_leaves_the_old_one(tmp_path: Path, fakes: None) -> None:
    for seed in (1, 2):
        run("run", "small", "--set", "count=30", "--seed", str(seed), "--out", f"p{seed}")
    analysis = ["analyze", "--only", "density", "--no-figures", "--out", "a"]
    run(*analysis[:1], "p1/packing.npz", *analysis[1:])
    before = snapshot(tmp_path / "a")
    assert json.loads(before["analysis.json"])["seed"] == 1

    paused = Paused([*analysis[:1], "p2/packing.npz", *analysis[1:]], "swap", tmp_path)
    assert paused.stop(signal.SIGKILL)[0] == -signal.SIGKILL
    assert snapshot(tmp_path / "a") == before

    run(*analysis[:1], "p2/packing.npz", *analysis[1:])
    assert json.loads((tmp_path / "a" / "analysis.json").read_text())["seed"] == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "p1", "p2"]


def test_a_terminated_sweep_stops_its_workers_and_resumes(tmp_path: Path) -> None:
    from regopack.experiments import run_experiment

    experiment = tmp_path / "tiny.toml"
    experiment.write_text(
        'name = "tiny"\nbase = "small"\n[set]\ncount = 40\n[sweep]\nseed = "1..3"\n',
        encoding="utf-8",
    )
    argv = ["sweep", str(experiment), "--out", "out", "--workers", "2", "--quiet", "--no-plots"]
    paused = Paused(argv, "swap", tmp_path, fake=False)  # a worker is about to swap its run in
    assert paused.stop(signal.SIGTERM) == (
        143,
        ["regopack: terminated; no partial files were written"],
    )
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == ["experiment.json", "results.csv"]
    assert (out / "results.csv").read_text().count("\n") == 1  # the header: no run finished

    outcome: Any = run_experiment(experiment, out, workers=1)
    assert outcome.ok and not any(r.reused for r in outcome.runs)
    assert sorted(p.name for p in out.iterdir()) == [
        "experiment.json",
        "results.csv",
        "seed=1",
        "seed=2",
        "seed=3",
    ]
    for seed in (1, 2, 3):
        assert_one_run(out / f"seed={seed}", seed, ["packing.npz", "scene.json", "summary.json"])


def _children(pid: int) -> list[int]:
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(p) for p in path.read_text().split()] if path.exists() else []


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs /proc")
def test_workers_exit_when_the_sweep_is_killed(tmp_path: Path) -> None:
    import time

    experiment = tmp_path / "tiny.toml"
    experiment.write_text(
        'name = "tiny"\nbase = "small"\n[set]\ncount = 40\n[sweep]\nseed = "1..4"\n',
        encoding="utf-8",
    )
    argv = ["sweep", str(experiment), "--out", "out", "--workers", "2", "--quiet", "--no-plots"]
    paused = Paused(argv, "swap", tmp_path, fake=False)  # a worker waits before its swap
    workers = _children(paused.proc.pid)
    assert workers
    paused.proc.kill()  # SIGKILL: the parent cannot stop its workers itself
    paused.proc.wait(timeout=TIMEOUT)
    deadline = time.monotonic() + 20
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(_alive(w) for w in workers)
