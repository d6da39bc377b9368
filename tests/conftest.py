from __future__ import annotations

import importlib.metadata
import os
import subprocess
import sys
from fnmatch import fnmatchcase
from pathlib import Path

import pytest

WARMUP_MIN_TESTS = 500
"""Sessions with fewer tests compile only what they use, in the test process."""

_warmup: list[subprocess.Popen[bytes]] = []


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


WARMUP_DONE = "test-warmup.done"
"""File that ``kernel_warmup.py`` writes into the kernel cache folder when it has run to its end."""


def _warmup_marker() -> Path | None:
    """Return where the warm-up marks the kernel cache of the current sources as warm."""
    import regopack.base.jit  # noqa: F401  (sets NUMBA_CACHE_DIR)

    folder = os.environ.get("NUMBA_CACHE_DIR")
    return Path(folder) / WARMUP_DONE if folder else None


def _usable_cpus() -> int:
    """CPUs this process may run on (its affinity where the system tells it)."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity is not None else os.cpu_count() or 1


def _start_warmup() -> None:
    """Start ``kernel_warmup.py`` on a second core, once, unless it has run on this cache.

    ``REGOPACK_TEST_WARMUP=0`` turns it off.
    """
    if _warmup or _usable_cpus() < 2 or os.environ.get("REGOPACK_TEST_WARMUP") == "0":
        return
    marker = _warmup_marker()
    if marker is None or marker.exists():
        return
    script = Path(__file__).with_name("kernel_warmup.py")
    _warmup.append(
        subprocess.Popen(
            [sys.executable, str(script), str(os.getpid()), str(marker)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    )


def pytest_configure(config: pytest.Config) -> None:
    """Start the warm-up before collection (12 s) when the whole suite is asked for.

    A selection by keyword (``-k``) waits for the collection: it may pick a few tests.
    """
    here = Path(__file__).resolve().parent
    if config.getoption("keyword", ""):
        return
    if config.args and all(Path(arg).resolve() == here for arg in config.args):
        _start_warmup()


def pytest_collection_finish(session: pytest.Session) -> None:
    """Start the warm-up for any other session of at least ``WARMUP_MIN_TESTS`` tests."""
    if len(session.items) >= WARMUP_MIN_TESTS:
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
        "run/test_summary_counts.py",
        "test_doctests.py",
    ),
    # three dimensions (and the modules that run every kind of scene)
    (
        "plugins/inserters/available_surface/test_*.py",
        "plugins/shapes/polyhedra/test_*.py",
        "plugins/analyzers/test_contacts.py",
        "plugins/analyzers/test_coordination.py",
        "plugins/analyzers/test_density.py",
        "plugins/analyzers/test_network.py",
        "plugins/exporters/test_slice_export.py",
        "plugins/exporters/test_solid_export_common.py",
        "plugins/exporters/test_stl_export.py",
        "plugins/shapes/solid_templates/test_*.py",
        "*/test_*3d*.py",
        "geometry/test_solids.py",
        "cli/test_cli_end_to_end.py",
        "run/test_compilation.py",
        "test_howto_export.py",
        "test_benchmarks_suite.py",
    ),
)
"""Test modules by the kernels they compile first, in the order the warm-up compiles them.

Patterns are matched against the whole path below ``tests/`` (``fnmatch``). A
session of at least ``WARMUP_MIN_TESTS`` tests runs the other modules first
(they need the paper's loop for sharp polygons, which the test process
compiles itself, and the analyses), then each stage in turn: by the time a
stage starts, ``kernel_warmup.py`` is expected to have compiled its kernels in
the second process (nothing waits for it: a kernel not yet in the cache is
compiled by the test that needs it, with the same result). Within a stage,
and among the other modules, the tests keep their order; a smaller session
keeps the order it was given.
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


def pytest_unconfigure(config: pytest.Config) -> None:
    """Stop the warm-up if it is still compiling (also after ``--markers`` or a failed start)."""
    for proc in _warmup:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
