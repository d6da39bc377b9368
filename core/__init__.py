"""regopack: dense 2D packings of lunar regolith particles.

The package root stays light to import: it exposes the version and the
packing file functions. Everything else lives in submodules
(:mod:`regopack.scene`, :mod:`regopack.run`, :mod:`regopack.verify`, ...).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__: str = version("regopack")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"

from regopack.packing import Packing, load, save

__all__ = ["Packing", "__version__", "load", "save"]
