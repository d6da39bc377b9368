"""The kernel cache folder follows the kernel sources."""

from __future__ import annotations

from pathlib import Path

import pytest

from regopack import jit


def test_cache_folder_changes_with_the_sources(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = tmp_path / "kernel.py"
    src.write_text("x = 1\n")
    monkeypatch.setattr(jit, "_sources", lambda: [src])
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    first = jit.kernel_cache_dir()
    assert first.parent == tmp_path / "cache" / "regopack" / "numba"
    assert jit.kernel_cache_dir() == first
    src.write_text("x = 2\n")
    assert jit.kernel_cache_dir() != first


def test_a_folder_chosen_by_the_user_is_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    jit.configure_cache()
    import os

    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "mine")


def test_sources_are_the_plugin_modules() -> None:
    names = {p.name for p in jit._sources()}
    assert {"kernel.py", "geometry.py", "octagon.py", "contact_kernel.py"} <= names


def test_the_kernel_packages_come_from_the_distribution_metadata() -> None:
    from importlib import metadata

    values = {e.value for e in metadata.entry_points(group=jit.KERNEL_SOURCES_GROUP)}
    assert "regopack.plugins" in values
    assert jit._names() == ["regopack.plugins"]


def test_the_cache_key_is_found_without_importing_a_plugin() -> None:
    import subprocess
    import sys

    code = (
        "import sys, regopack.jit as jit; "
        "assert jit._sources(); "
        "assert not [m for m in sys.modules if m.startswith('regopack.plugins')], sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_an_unknown_kernel_package_adds_no_sources(monkeypatch: pytest.MonkeyPatch) -> None:
    assert jit._source_files("regopack_no_such_package") == []


def test_a_one_file_module_is_hashed_too() -> None:
    files = jit._source_files("regopack.jit")
    assert [p.name for p in files] == ["jit.py"]


def test_third_party_kernel_modules_change_the_key(tmp_path, monkeypatch) -> None:
    """A package and a one-file module named in the entry points, with the ``module:attr`` form."""
    import sys
    from importlib import metadata

    (tmp_path / "kpkg").mkdir()
    (tmp_path / "kpkg" / "__init__.py").write_text("X = 1\n")
    (tmp_path / "single.py").write_text("Y = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    entries = [
        metadata.EntryPoint("a", "kpkg:plugin", jit.KERNEL_SOURCES_GROUP),
        metadata.EntryPoint("b", "single", jit.KERNEL_SOURCES_GROUP),
    ]
    real = metadata.entry_points
    monkeypatch.setattr(
        metadata,
        "entry_points",
        lambda group=None, **kw: (
            entries if group == jit.KERNEL_SOURCES_GROUP else real(group=group, **kw)
        ),
    )
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    first = jit.kernel_cache_dir()
    (tmp_path / "single.py").write_text("Y = 2\n")
    second = jit.kernel_cache_dir()
    (tmp_path / "kpkg" / "__init__.py").write_text("X = 2\n")
    third = jit.kernel_cache_dir()
    assert len({first, second, third}) == 3
    assert "kpkg" not in sys.modules and "single" not in sys.modules


def test_kernel_threads_sleep_while_they_wait_unless_the_user_chose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import os

    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    jit.configure_threads()
    assert os.environ["OMP_WAIT_POLICY"] == "PASSIVE"
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    jit.configure_threads()
    assert os.environ["OMP_WAIT_POLICY"] == "ACTIVE"


def test_cache_saves_hold_a_lock_and_keep_every_entry(tmp_path) -> None:
    # two processes that save signatures of one function at once could otherwise
    # give both the same data file (regopack.jit.lock_cache_saves)
    import multiprocessing

    from numba.core import caching

    import regopack.jit  # noqa: F401

    pytest.importorskip("fcntl")  # the lock is taken on POSIX systems only

    assert getattr(caching.IndexDataCacheFile.save, "regopack_locked", False)
    ctx = multiprocessing.get_context("fork")
    procs = [ctx.Process(target=_save_entries, args=(str(tmp_path), k)) for k in range(4)]
    for proc in procs:
        proc.start()
    for proc in procs:
        proc.join(60)
        assert proc.exitcode == 0
    cache = caching.IndexDataCacheFile(str(tmp_path), "f", ("stamp", 1))
    for k in range(4):
        for j in range(25):
            assert cache.load(("key", k, j)) == ("data", k, j)
    assert (tmp_path / "f.nbi.lock").exists()


def _save_entries(folder: str, k: int) -> None:
    from numba.core import caching

    cache = caching.IndexDataCacheFile(folder, "f", ("stamp", 1))
    for j in range(25):
        cache.save(("key", k, j), ("data", k, j))
