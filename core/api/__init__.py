"""The Python API and the ahead-of-time compilation of the kernels.

:mod:`regopack.api.functions` holds the functions behind ``regopack.pack``,
``analyze``, ``export``, ``verify`` and the rest; :mod:`regopack.api.warmup` compiles.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.api.functions import analyze as analyze
    from regopack.api.functions import export as export
    from regopack.api.functions import pack as pack
    from regopack.api.functions import pack_and_summarise as pack_and_summarise
    from regopack.api.functions import scene as scene
    from regopack.api.functions import settled as settled
    from regopack.api.functions import sweep as sweep
    from regopack.api.functions import verify as verify

__all__ = [
    "analyze",
    "export",
    "pack",
    "pack_and_summarise",
    "scene",
    "settled",
    "sweep",
    "verify",
]

__getattr__, __dir__ = lazy_exports(globals(), "regopack.api.functions")
