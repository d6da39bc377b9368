from __future__ import annotations

import importlib.metadata
import os
import subprocess
import sys
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


def _sweep_cached() -> bool:
    """Whether the kernel cache of the current sources already holds the sweep."""
    import regopack.jit  # noqa: F401  (sets NUMBA_CACHE_DIR)

    folder = os.environ.get("NUMBA_CACHE_DIR")
    if not folder:
        return False
    return any(Path(folder).rglob("*sweep_range*.nbi"))


def _usable_cpus() -> int:
    """CPUs this process may run on (its affinity where the system tells it)."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity is not None else os.cpu_count() or 1


def _start_warmup() -> None:
    """Start ``kernel_warmup.py`` on a second core, once, unless the cache holds the sweep.

    ``REGOPACK_TEST_WARMUP=0`` turns it off.
    """
    if (
        _warmup
        or _usable_cpus() < 2
        or os.environ.get("REGOPACK_TEST_WARMUP") == "0"
        or _sweep_cached()
    ):
        return
    script = Path(__file__).with_name("kernel_warmup.py")
    _warmup.append(
        subprocess.Popen(
            [sys.executable, str(script), str(os.getpid())],
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


LATE_MODULES = "plugins/analysis/test_*3d.py"
"""Tests run after all others, so that the warm-up has compiled their kernels (the 3D
scan) by then; every other test keeps its place."""


def pytest_collection_modifyitems(session: pytest.Session, items: list[pytest.Item]) -> None:
    """Move the tests of :data:`LATE_MODULES` to the end of the session."""
    here = Path(__file__).resolve().parent
    late = [
        item
        for item in items
        if here in item.path.parents and item.path.relative_to(here).match(LATE_MODULES)
    ]
    if late:
        late_ids = {id(item) for item in late}
        items[:] = [item for item in items if id(item) not in late_ids] + late


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
