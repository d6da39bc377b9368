"""Compiling every kernel ahead of time (the command ``regopack compile``).

:func:`compile_kernels` packs, analyses and exports a few tiny scenes that
use every built-in kernel, which fills numba's on-disk cache (see
:mod:`regopack.base.jit`), e.g. when building a cluster image.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from regopack.api import functions as api
from regopack.base.errors import RegopackError
from regopack.exports.pipeline import exporter_dimensions
from regopack.registry import manager
from regopack.run import compilation
from regopack.run.compilation import CompileTime
from regopack.scenes.analysis_plan import dimensions_of

__all__ = ["TINY", "VARIANTS", "compile_kernels"]

TINY: dict[str, Any] = {"domain.width": 60.0, "domain.height": 60.0, "count": 60}
"""Overrides that make the ``small`` scene tiny (a fraction of a second once compiled)."""


def _tiny_box(shape: str) -> dict[str, Any]:
    """Return overrides that make the tiny scene a box of twelve particles of one 3D ``shape``."""
    return {
        "domain.kind": "box",
        "domain.depth": 60.0,
        "domain.center": [0.0, 0.0, 0.0],
        "phases": [{"name": "glass", "fraction": 1.0, "shape": {"kind": shape}}],
        "insertion": {"kind": "available-surface"},
        "count": 12,
    }


VARIANTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("polygons in a walled rectangle", {}),
    ("a circle", {"domain": {"kind": "circle", "radius": 30.0}}),
    (
        "a convex polygon",
        {"domain": {"kind": "polygon", "vertices": [[-30, -30], [30, -30], [30, 30], [-30, 20]]}},
    ),
    (
        "a periodic rectangle",
        {"domain.kind": "periodic", "domain.width": 80.0, "domain.height": 80.0},
    ),
    ("disks among polygons", {"phases.0.shape": {"kind": "disk"}}),
    (
        "disks in a periodic rectangle",
        {
            "phases.0.shape": {"kind": "disk"},
            "domain.kind": "periodic",
            "domain.width": 80.0,
            "domain.height": 80.0,
        },
    ),
    (
        "disks in a circle",
        {"phases.0.shape": {"kind": "disk"}, "domain": {"kind": "circle", "radius": 30.0}},
    ),
    (
        "disks in a convex polygon",
        {
            "phases.0.shape": {"kind": "disk"},
            "domain": {"kind": "polygon", "vertices": [[-30, -30], [30, -30], [30, 30], [-30, 20]]},
        },
    ),
    ("the sweep order", {"insertion.order": "sweep"}),
    (
        "disks among polygons, the sweep order",
        {"insertion.order": "sweep", "phases.0.shape": {"kind": "disk"}},
    ),
    ("polyhedra in a box (3D)", _tiny_box("polyhedron")),
    ("spheres in a box (3D)", _tiny_box("sphere")),
    ("exact refusals", {"insertion.screening": "exact"}),
    ("random sequential addition", {"insertion": {"kind": "rsa"}}),
)
"""Scenes :func:`compile_kernels` packs: ``small`` made tiny, then changed by these fields."""


def compile_kernels(report: Callable[[str, float], None] | None = None) -> CompileTime:
    """Compile (or load from the cache) every built-in kernel by using it once.

    Packs the tiny variants of :data:`VARIANTS` whose plugins are registered,
    runs every registered analyzer of its dimension on each and writes each
    2D one with every registered exporter into a temporary folder, which is
    then removed.

    Parameters
    ----------
    report
        Called as ``report(step, seconds)`` after each step.

    Returns
    -------
    CompileTime
        The compilation time of the whole call (zero when everything was cached).
    """
    # looked up when called, as before the move out of compilation.py (tests patch them)
    registry = manager.default_registry()
    by_dimension = {
        d: [n for n in sorted(registry.names("analysis")) if d in dimensions_of(registry, n)]
        for d in (2, 3)
    }
    analyzers = by_dimension[2]

    # the 3D exporters compile nothing (plain numpy); 3D variants are only packed and analysed
    exporters = [
        n for n in sorted(registry.names("export")) if 2 in exporter_dimensions(registry, n)
    ]
    with (
        compilation.compile_timer() as total,
        tempfile.TemporaryDirectory(prefix="regopack-") as folder,
    ):
        for k, (label, changes) in enumerate(VARIANTS):
            start = time.perf_counter()
            try:
                resolved = api.scene("small", registry=registry, **{**TINY, **changes})
            except RegopackError:
                continue  # a plugin of this variant is not installed
            packing = api.pack(resolved)
            if packing.dimension == 3:  # 3D packings have no exports yet
                api.analyze(packing, by_dimension[3], registry=registry)
                if report is not None:
                    report(f"{label}: packed, analysed", time.perf_counter() - start)
                continue
            # the analyses and exports of every variant: some kernels have a
            # signature per domain kind (periodic images) or per particle kind
            results = api.analyze(packing, analyzers, registry=registry)
            for name in exporters:
                target = Path(folder) / f"{k}-{name}"
                target.mkdir()
                api.export(packing, name, target, analyses=results, registry=registry)
            if report is not None:
                report(f"{label}: packed, analysed, exported", time.perf_counter() - start)
    return total
