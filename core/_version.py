"""The installed version of regopack (``0.0.0`` in a source tree that is not installed)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

__all__ = ["__version__"]

try:
    __version__: str = version("regopack")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"
