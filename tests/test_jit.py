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
