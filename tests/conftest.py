from __future__ import annotations

import importlib.metadata
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from fnmatch import fnmatchcase
from pathlib import Path

import pytest

WARMUP_MIN_TESTS = 500
"""Sessions with fewer tests compile only what they use, in the test process."""

WARMUP_WAIT_MAX = 600.0
"""Seconds the first test of a stage waits at most for the warm-up to finish the stage
(after one wait that long, the tests wait no more)."""

_warmup: list[subprocess.Popen[bytes]] = []
_progress: list[Path] = []
"""The file into which the running warm-up writes the last stage it has finished."""
_waited: dict[int, float] = {}
"""Seconds the tests waited for the warm-up, by stage."""
_staged: list[bool] = []
"""Set when the session runs in stages (:func:`pytest_collection_modifyitems`)."""

WARMUP_ENV = "REGOPACK_TEST_WARMUP_RUN"
"""Environment variable through which the session's workers learn of the warm-up: a
JSON list of ``[pid, progress file]`` per warm-up process (set by the process that started it)."""

WORKERS = 2
"""Processes that run a whole suite on a machine with at least as many CPUs
(``pytest-xdist``; a smaller session runs in the pytest process itself)."""


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def pytest_report_header(config: pytest.Config) -> str:
    names = ("regopack", "numpy", "scipy", "shapely", "numba", "pydantic", "pluggy")
    return "versions: " + ", ".join(f"{n} {_version(n)}" for n in names)


@pytest.fixture
def registry():
    from fakes import fake_registry

    return fake_registry()


WARMUP_DONE = "test-warmup-{install}.done"
"""File that ``kernel_warmup.py`` writes into the kernel cache folder when it has run to its end.

``{install}`` is a hash of the folder the kernels are installed in: the cache
folder is named after the kernel sources only, but numba files each
function's machine code by the path of its source file, so a second install
of the same sources (another clone, a fresh virtual environment) starts with
a cold cache in a folder that another install has warmed.
"""

WARMUP_LOG = "test-warmup.log"
"""File in the kernel cache folder that receives the warm-up's output (a failing warm-up
only makes the suite slower: its traceback is kept there)."""


def _warmup_marker() -> Path | None:
    """Return where the warm-up marks the kernel cache of the current install as warm."""
    import hashlib
    import importlib.util

    import regopack.base.jit  # noqa: F401  (sets NUMBA_CACHE_DIR)

    folder = os.environ.get("NUMBA_CACHE_DIR")
    if not folder:
        return None
    spec = importlib.util.find_spec("regopack.plugins")
    where = str(spec.origin if spec is not None else None)
    install = hashlib.sha256(where.encode()).hexdigest()[:12]
    return Path(folder) / WARMUP_DONE.format(install=install)


def _usable_cpus() -> int:
    """CPUs this process may run on (its affinity where the system tells it)."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity is not None else os.cpu_count() or 1


def _start_warmup(parts: int = 1) -> None:
    """Start ``kernel_warmup.py`` in ``parts`` processes, once, unless it has run on this cache.

    Each process compiles its share of every stage (``kernel_warmup.py``); the
    session's workers learn of them through :data:`WARMUP_ENV`.
    ``REGOPACK_TEST_WARMUP=0`` turns it off.
    """
    if _warmup or _usable_cpus() < 2 or os.environ.get("REGOPACK_TEST_WARMUP") == "0":
        return
    marker = _warmup_marker()
    if marker is None or marker.exists():
        return
    script = Path(__file__).with_name("kernel_warmup.py")
    with open(marker.with_name(WARMUP_LOG), "wb") as log:
        for part in range(parts):
            progress = marker.with_name(f"{marker.name}.{os.getpid()}.{part}.stage")
            progress.unlink(missing_ok=True)  # left by a killed session of the same pid
            command = [str(script), str(os.getpid()), str(marker), str(progress)]
            _warmup.append(
                subprocess.Popen(
                    [sys.executable, *command, str(part), str(parts)],
                    stdin=subprocess.DEVNULL,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                )
            )
            _progress.append(progress)
    listed = [[w.pid, str(f)] for w, f in zip(_warmup, _progress, strict=True)]
    os.environ[WARMUP_ENV] = json.dumps(listed)


def _warmup_parts() -> list[tuple[Callable[[], bool], Path]]:
    """Return, per warm-up process of this session, whether it runs and its progress file.

    The processes this one started, or in a worker those its controller started.
    """
    if _warmup:
        return [(lambda w=w: w.poll() is None, f) for w, f in zip(_warmup, _progress, strict=True)]
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return []
    try:
        listed = json.loads(os.environ.get(WARMUP_ENV, "[]"))
        return [(lambda pid=int(pid): _alive(pid), Path(f)) for pid, f in listed]
    except (TypeError, ValueError):
        return []


def _alive(pid: int) -> bool:
    """Say whether process ``pid`` runs (a process ended but not yet reaped is a zombie)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        try:
            os.kill(pid, 0)
        except OSError:
            return False
        return True
    return stat.rpartition(")")[2].split()[0] != "Z"


def _warmed_stage(progress: Path) -> int:
    """Return the last stage a warm-up process has finished (-1: none yet)."""
    try:
        return int(progress.read_text())
    except (OSError, ValueError):
        return -1


def _wait_for_warmup(stage: int) -> None:
    """Wait while a warm-up process runs that has not finished ``stage`` (at most
    ``WARMUP_WAIT_MAX``).

    Compiling the kernels the warm-up is compiling would take the test process
    longer than waiting for them (the warm-up is part way through), and would
    slow both on a machine with two cores.
    """
    if stage in _waited or any(s >= WARMUP_WAIT_MAX for s in _waited.values()):
        return
    parts = _warmup_parts()
    if not parts:
        return
    start = time.monotonic()
    while any(runs() and _warmed_stage(progress) < stage for runs, progress in parts):
        if time.monotonic() - start >= WARMUP_WAIT_MAX:
            break
        time.sleep(0.1)
    _waited[stage] = time.monotonic() - start


def pytest_configure(config: pytest.Config) -> None:
    """Start the warm-up before collection (12 s) when the whole suite is asked for.

    A selection by keyword (``-k``) waits for the collection: it may pick a few tests.
    """
    if hasattr(config, "workerinput") or not _whole_suite(config):
        return
    # with workers (pytest-xdist), a warm-up process per worker, up to the parts that
    # kernel_warmup.py shares the stages between: the stages are ready sooner
    workers = int(getattr(config.option, "numprocesses", 0) or 0)
    _start_warmup(min(WORKERS, max(1, workers)))


def _whole_suite(config: pytest.Config) -> bool:
    """Say whether the session runs the whole suite (no ``-k``, no paths but ``tests/``)."""
    here = Path(__file__).resolve().parent
    if config.getoption("keyword", ""):
        return False
    return bool(config.args) and all(Path(arg).resolve() == here for arg in config.args)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """Run the whole suite in :data:`WORKERS` processes where the CPUs allow, else in this one.

    The warm-up compiles beside them (:func:`_start_warmup`); each worker waits
    for the stages it reaches, as a single test process would.
    """
    if _usable_cpus() < WORKERS or not _whole_suite(config):
        return 0
    return WORKERS


def pytest_collection_finish(session: pytest.Session) -> None:
    """Start the warm-up for any other session of at least ``WARMUP_MIN_TESTS`` tests."""
    if len(session.items) >= WARMUP_MIN_TESTS and not hasattr(session.config, "workerinput"):
        _start_warmup()


KERNEL_STAGES: tuple[tuple[str, ...], ...] = (
    # the paper's order with disks (its loop for rounded particles)
    (
        "plugins/analyzers/test_common.py",
        "plugins/analyzers/test_homogeneity.py",
        "plugins/inserters/available_arc/test_bound_queue.py",
        "plugins/exporters/test_image_export.py",
        "cli/test_cli_domains.py",
    ),
    # three dimensions
    (
        "plugins/inserters/available_surface/test_*.py",
        "cli/test_cli_export.py",
        "plugins/analyzers/test_figures.py",
        "plugins/exporters/test_gsd_export.py",
        "plugins/analyzers/test_psd.py",
        "plugins/shapes/polyhedra/test_*.py",
        "plugins/analyzers/test_contacts.py",
        "plugins/analyzers/test_coordination.py",
        "plugins/analyzers/test_density.py",
        "plugins/analyzers/test_network.py",
        "plugins/analyzers/test_scale.py",
        "plugins/exporters/test_slice_export.py",
        "plugins/exporters/test_solid_export_common.py",
        "plugins/exporters/test_stl_export.py",
        "plugins/exporters/test_liggghts_export.py",
        "plugins/exporters/test_yade_export.py",
        "plugins/shapes/solid_templates/test_*.py",
        "*/test_*3d*.py",
        "geometry/test_solids.py",
    ),
    # the sweep (sharp and rounded, one thread and several), exact refusals, RSA
    (
        "plugins/inserters/available_arc/test_batches.py",
        "plugins/inserters/available_arc/test_disk_bound.py",
        "plugins/inserters/available_arc/test_disk_path.py",
        "plugins/inserters/available_arc/test_domains.py",
        "plugins/inserters/available_arc/test_lag.py",
        "plugins/inserters/available_arc/test_neighbours.py",
        "plugins/inserters/available_arc/test_partner.py",
        "plugins/inserters/available_arc/test_sweep.py",
        "plugins/shapes/test_disk.py",
        "plugins/inserters/test_rsa.py",
        "run/test_fabric.py",
        "run/test_summary_counts.py",
        "test_doctests.py",
        "base/test_jit.py",
    ),
    # the modules that run every kind of scene
    (
        "cli/test_cli_end_to_end.py",
        "run/test_compilation.py",
        "test_howto_export.py",
        "plugins/density/test_target.py",
        "test_benchmarks_suite.py",
    ),
)
"""Test modules by the kernels they compile first, in the order the warm-up compiles them.

Patterns are matched against the whole path below ``tests/`` (``fnmatch``). A
session of at least ``WARMUP_MIN_TESTS`` tests runs the other modules first
(they need the paper's loop for sharp polygons, which the test process
compiles itself, and the analyses), then each stage in turn. ``kernel_warmup.py``
compiles the kernels of each stage in the second process (its ``STAGE_STEPS``),
in this order; the first test of a stage waits for it to finish them while it
runs, so that the two processes never compile the same kernel at once (a
kernel not in the cache is compiled by the test that needs it, with the same
result). The sweep comes after the 3D stage: its kernels take the warm-up the
longest. Within a stage, and among the other modules, the tests keep their
order; a smaller session keeps the order it was given.
"""


def _stage(path: Path, here: Path) -> int:
    """Return the stage of test module ``path`` (0: unlisted; ``here``: the tests folder)."""
    if here not in path.parents:
        return 0
    rel = path.relative_to(here).as_posix()
    for n, patterns in enumerate(KERNEL_STAGES, start=1):
        if any(fnmatchcase(rel, p) for p in patterns):
            return n
    return 0


def pytest_collection_modifyitems(session: pytest.Session, items: list[pytest.Item]) -> None:
    """Order a large session by :data:`KERNEL_STAGES` (a stable sort: nothing else moves)."""
    if len(items) >= WARMUP_MIN_TESTS:
        here = Path(__file__).resolve().parent
        items.sort(key=lambda item: _stage(item.path, here))
        _staged.append(True)


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Let the first test of a stage wait for the warm-up to finish that stage's kernels."""
    if _staged and _warmup_parts():
        stage = _stage(item.path, Path(__file__).resolve().parent)
        if stage > 0:
            _wait_for_warmup(stage)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Say how long the tests waited for the warm-up, when it ran."""
    if _warmup and _staged:
        waits = ", ".join(f"stage {n} {s:.1f} s" for n, s in sorted(_waited.items()))
        terminalreporter.write_line(f"kernel warm-up: the tests waited for it: {waits or 'never'}")


def pytest_unconfigure(config: pytest.Config) -> None:
    """Stop the warm-up if it is still compiling (also after ``--markers`` or a failed start).

    Of several warm-up processes that have all ended well, mark the cache warm.
    """
    marker = _warmup_marker() if len(_warmup) > 1 else None
    if marker is not None and all(proc.poll() == 0 for proc in _warmup):
        if all(_warmed_stage(f) == len(KERNEL_STAGES) for f in _progress):
            marker.touch()
    for proc in _warmup:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    for progress in _progress:
        progress.unlink(missing_ok=True)
