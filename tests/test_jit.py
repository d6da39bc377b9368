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
    assert [root.name for root in jit._roots()] == ["plugins"]


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
    assert jit._package_dir("regopack_no_such_package") is None
    assert jit._package_dir("regopack.jit") is None  # a module, not a package
