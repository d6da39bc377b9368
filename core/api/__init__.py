"""The Python API and the ahead-of-time compilation of the kernels.

:mod:`regopack.api.functions` holds the functions behind ``regopack.pack``,
``analyze``, ``export``, ``verify`` and the rest; :mod:`regopack.api.warmup` compiles.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from regopack._exports import load_export

if TYPE_CHECKING:
    from regopack.api.functions import analyze as analyze
    from regopack.api.functions import export as export
    from regopack.api.functions import pack as pack
    from regopack.api.functions import pack_and_summarise as pack_and_summarise
    from regopack.api.functions import scene as scene
    from regopack.api.functions import sweep as sweep
    from regopack.api.functions import verify as verify

__all__ = ["analyze", "export", "pack", "pack_and_summarise", "scene", "sweep", "verify"]

_SOURCES = dict.fromkeys(__all__, "regopack.api.functions")


def __getattr__(name: str) -> Any:
    """Load the names of :mod:`regopack.api.functions` on first use (PEP 562)."""
    return load_export(globals(), _SOURCES, name)


def __dir__() -> list[str]:
    return sorted(__all__)
