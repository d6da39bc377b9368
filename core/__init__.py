"""regopack: dense packings of lunar regolith particles.

The Python API mirrors the commands (see :mod:`regopack.api.functions`)::

    import regopack

    scene = regopack.scene("table1", domain__width=400)
    packing = regopack.pack(scene, seed=3)
    results = regopack.analyze(packing, ["density", "coordination"])
    report = regopack.verify(packing)
    regopack.export(packing, "lammps", "runs/sample/packing.data")

The package root stays light to import: the functions are loaded on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import regopack.base.threads  # noqa: F401  (numba's threading layer, before any kernel runs)
from regopack import _compat
from regopack._version import __version__
from regopack.packing.core import Packing, load, save

if TYPE_CHECKING:
    from regopack.api.functions import (
        analyze,
        export,
        pack,
        pack_and_summarise,
        scene,
        settled,
        sweep,
        verify,
    )

__all__ = [
    "Packing",
    "__version__",
    "analyze",
    "export",
    "load",
    "pack",
    "pack_and_summarise",
    "save",
    "scene",
    "settled",
    "sweep",
    "verify",
]

_compat.install()  # old module names (regopack.domain3d, ...) as deprecated aliases

_API = frozenset(
    {"analyze", "export", "pack", "pack_and_summarise", "scene", "settled", "sweep", "verify"}
)


def __getattr__(name: str) -> Any:
    """Load the API functions on first use (PEP 562); ``Packing3D`` is deprecated."""
    if name == "Packing3D":
        _compat.warn_moved("regopack.Packing3D", "regopack.Packing")
        return Packing
    if name in _API:
        from regopack.api import functions as api

        value = getattr(api, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'regopack' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
