"""Where compiled kernels are cached, keyed by the source of every kernel.

numba invalidates a cached function only when its own file changes, not when
a jitted function it calls from another file does, so an edited helper could
run as stale machine code. Importing this module before numba points
``NUMBA_CACHE_DIR`` at a folder named after a hash of all kernel sources (and
the numba version), unless the user chose a folder already. Any change to a
kernel then compiles afresh into a new folder.

The kernel sources are the Python files of the packages that installed
distributions name in the entry-point group :data:`KERNEL_SOURCES_GROUP`;
regopack names its built-in plugins there (see ``pyproject.toml``). Each
package is found by path (:func:`importlib.util.find_spec`), without
importing it, so this module never imports a plugin.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

from regopack.base.threads import configure_threads

__all__ = ["configure_cache", "configure_threads", "kernel_cache_dir", "lock_cache_saves"]

KERNEL_SOURCES_GROUP = "regopack.kernel_sources"
"""Entry-point group whose values name packages holding numba kernels."""

BUILTIN_KERNEL_PACKAGES: tuple[str, ...] = ("regopack.plugins",)
"""Packages hashed whatever the entry points say, so that an install whose
entry points are stale (an old editable install) still keys the cache by the
built-in kernels."""


def _source_files(name: str) -> list[Path]:
    """Python files of the package or module ``name`` (none if it is not found).

    The package itself is found by path, not run; for a dotted name, Python
    imports the packages above it (``regopack`` for ``regopack.plugins``).
    """
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return []
    if spec is None:
        return []
    if spec.submodule_search_locations:
        roots = [Path(p).resolve() for p in spec.submodule_search_locations]
        return [path.resolve() for root in roots for path in root.rglob("*.py")]
    if spec.origin and spec.origin.endswith(".py"):
        return [Path(spec.origin).resolve()]
    return []


def _names() -> list[str]:
    """Return the built-in kernel packages and the modules named in the entry points."""
    names = {*BUILTIN_KERNEL_PACKAGES}
    names |= {entry.module for entry in metadata.entry_points(group=KERNEL_SOURCES_GROUP)}
    return sorted(names)


def _sources() -> list[Path]:
    """Python files of the kernel packages and modules (the built-in plugins and others)."""
    return sorted({path for name in _names() for path in _source_files(name)})


def kernel_cache_dir() -> Path:
    """Cache folder for the current kernel sources and numba version."""
    digest = hashlib.sha256()
    for path in _sources():
        try:
            digest.update(path.read_bytes())
        except OSError:
            continue
    try:
        digest.update(metadata.version("numba").encode())
    except metadata.PackageNotFoundError:
        pass
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "regopack" / "numba" / digest.hexdigest()[:16]


def configure_cache() -> None:
    """Point numba's cache at :func:`kernel_cache_dir` unless the user set one.

    Has no effect once numba has been imported with its own setting.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    folder = kernel_cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return  # numba falls back to its own choice
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    if "numba" in sys.modules:
        from numba.core import config

        # read when a cached function is decorated
        config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]
        # numba re-reads every NUMBA_* variable when one changes, undoing what the user set
        # in numba.config (a threading layer, say): this change is known to it already
        seen = getattr(getattr(config, "_env_reloader", None), "old_environ", None)
        if isinstance(seen, dict):
            seen["NUMBA_CACHE_DIR"] = str(folder)


def lock_cache_saves() -> None:
    """Make numba's cache saves exclusive between processes, on POSIX systems.

    numba saves a compiled signature by reading the function's cache index,
    choosing a data file name that the index does not use, writing the index and
    then the data. Two processes that save different signatures of one function
    at the same moment can choose the same name, and the index may then point
    one signature at the other's machine code. A lock file beside each index
    (``fcntl.flock``) makes each save whole; loading is unchanged. Without
    ``fcntl``, or with a numba whose cache class differs, nothing changes.
    """
    try:
        import fcntl

        from numba.core import caching
    except ImportError:
        return
    cls = getattr(caching, "IndexDataCacheFile", None)
    original = getattr(cls, "save", None)
    if cls is None or original is None or getattr(original, "regopack_locked", False):
        return

    def save(self: Any, key: Any, data: Any) -> None:
        path = getattr(self, "_index_path", None)
        if not isinstance(path, str):
            original(self, key, data)
            return
        with open(path + ".lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                original(self, key, data)
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    save.regopack_locked = True  # type: ignore[attr-defined]
    cls.save = save


configure_cache()
lock_cache_saves()
