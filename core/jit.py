"""Where compiled kernels are cached, keyed by the source of every kernel.

numba invalidates a cached function only when its own file changes, not when
a jitted function it calls from another file does, so an edited helper could
run as stale machine code. Importing this module before numba points
``NUMBA_CACHE_DIR`` at a folder named after a hash of all kernel sources of
regopack (and the numba version), unless the user chose a folder already. Any
change to a kernel then compiles afresh into a new folder.
"""

from __future__ import annotations

import hashlib
import os
import sys
from importlib import metadata
from pathlib import Path


def _sources() -> list[Path]:
    """Python files of the built-in plugins (where every kernel lives)."""
    import regopack.plugins

    root = Path(str(regopack.plugins.__file__)).resolve().parent
    return sorted(root.rglob("*.py"))


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


configure_cache()
