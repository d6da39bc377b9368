"""Worker processes of an experiment share the machine's cores and die with the sweep."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from regopack.experiments.workers import threads_per_worker


@pytest.mark.parametrize(
    ("workers", "cores", "threads"),
    [(1, 8, 8), (2, 8, 4), (3, 8, 2), (8, 8, 1), (16, 8, 1), (2, 2, 1), (2, None, 1), (0, 4, 4)],
)
def test_workers_share_the_cores(workers: int, cores: int | None, threads: int) -> None:
    assert threads_per_worker(workers, cores) == threads


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux's parent-death signal")
def test_a_worker_busy_in_compiled_code_dies_with_its_killed_parent(tmp_path: Path) -> None:
    """A worker that holds Python's lock (as a kernel or the compiler does) cannot run its
    watchdog thread; the kernel still ends it when the sweep is killed."""
    ready = tmp_path / "ready"
    parent = tmp_path / "parent.py"
    parent.write_text(
        "import ctypes, multiprocessing, sys, time\n"
        "from pathlib import Path\n"
        "from regopack.experiments.workers import _init_worker\n"
        "def work(ready):\n"
        "    _init_worker(1)\n"
        "    Path(ready).write_text('ok')\n"
        "    ctypes.PyDLL(None).sleep(120)  # holds Python's lock: no watchdog runs\n"
        "if __name__ == '__main__':\n"
        "    ctx = multiprocessing.get_context('spawn')\n"
        "    p = ctx.Process(target=work, args=(sys.argv[1],))\n"
        "    p.start()\n"
        "    print(p.pid, flush=True)\n"
        "    time.sleep(600)\n"
    )
    proc = subprocess.Popen(
        [sys.executable, str(parent), str(ready)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert proc.stdout is not None
        worker = int(proc.stdout.readline())
        deadline = time.monotonic() + 120
        while not ready.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert ready.exists()
        time.sleep(0.5)  # the worker is asleep in C
        proc.kill()
        proc.wait(timeout=30)
        deadline = time.monotonic() + 10
        while _alive(worker) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _alive(worker)
    finally:
        proc.kill()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return True
    return state != "Z"


def test_a_worker_loads_a_scenes_kernels_before_its_first_timed_run(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The first run's insertion time holds no loading of kernels: an untimed run of a few
    particles loads them, once per kind of scene in a process."""
    from regopack.experiments import workers as ew
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import load_scene, resolve_scene

    counts: list[object] = []
    monkeypatch.setattr(ew, "_WARMED", set())
    monkeypatch.setattr(ew, "run_scene", lambda s, *a, **k: counts.append(s.scene.count))
    registry = default_registry()
    small = resolve_scene(load_scene("small"), registry)
    ew._warm_up(small)
    ew._warm_up(resolve_scene(load_scene("small", ["domain.width=300", "seed=4"]), registry))
    assert counts == [ew.WARM_COUNT]  # sizes and seeds load no other kernel
    ew._warm_up(resolve_scene(load_scene("small", ["insertion.order=sweep"]), registry))
    ew._warm_up(resolve_scene(load_scene("small", ["count=5"]), registry))
    assert counts == [ew.WARM_COUNT, ew.WARM_COUNT]
    ew._warm_up(resolve_scene(load_scene("dem", ["count=5"]), registry))
    assert counts[-1] == 5
