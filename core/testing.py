"""Helpers for testing regopack and its plugins.

Examples
--------
>>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 1, 0, 1))
>>> assert_valid_packing(p).ok
True
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from regopack.domain import Rectangle
from regopack.manager import BUILTIN_PLUGINS, Registry, build_plugin_manager
from regopack.packing import Packing
from regopack.verify import VerifyReport, assert_valid_packing, verify

__all__ = [
    "VerifyReport",
    "assert_valid_packing",
    "make_registry",
    "packing_from_polygons",
    "verify",
]


def make_registry(*plugins: object, builtins: Sequence[str] = BUILTIN_PLUGINS) -> Registry:
    """Registry of the given plugin objects (plus ``builtins``), without entry points.

    Parameters
    ----------
    *plugins
        Modules or objects with ``@hookimpl`` methods.
    builtins
        Built-in plugin modules to register as well; pass ``()`` for none.
    """
    return Registry.from_manager(
        build_plugin_manager(autoload=False, extra=plugins, builtins=builtins)
    )


def packing_from_polygons(
    polygons: Sequence[ArrayLike],
    domain: Rectangle | tuple[float, float, float, float] | None = None,
    *,
    placed: Sequence[bool] | None = None,
) -> Packing:
    """Build a :class:`~regopack.packing.Packing` from absolute polygon outlines.

    Each particle's centre is the mean of its vertices. Useful to construct
    packings with known defects.

    Parameters
    ----------
    polygons
        One ``(k, 2)`` array of counter-clockwise vertices per particle.
    domain
        The container as a rectangle or ``(xmin, xmax, ymin, ymax)``; by
        default the bounding box of the polygons.
    placed
        Which particles count as placed (default: all), in order.
    """
    outlines = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in polygons]
    n = len(outlines)
    if domain is None:
        allv = np.concatenate(outlines) if n else np.zeros((1, 2))
        domain = Rectangle(
            float(allv[:, 0].min()),
            float(allv[:, 0].max()),
            float(allv[:, 1].min()),
            float(allv[:, 1].max()),
        )
    elif not isinstance(domain, Rectangle):
        domain = Rectangle(*(float(v) for v in domain))
    centre = np.array([o.mean(axis=0) for o in outlines]).reshape(n, 2)
    counts = np.array([len(o) for o in outlines], dtype=np.int64)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    vertices = (
        np.concatenate([o - c for o, c in zip(outlines, centre, strict=True)])
        if n
        else np.zeros((0, 2))
    )
    mask = np.ones(n, dtype=bool) if placed is None else np.asarray(placed, dtype=bool)
    insertion_index = np.where(mask, np.cumsum(mask) - 1, -1).astype(np.int64)
    centre = np.where(mask[:, None], centre, np.nan)
    area = np.array(
        [
            0.5 * abs(np.sum(o[:, 0] * np.roll(o[:, 1], -1) - np.roll(o[:, 0], -1) * o[:, 1]))
            for o in outlines
        ]
    )
    return Packing(
        radius=np.sqrt(area / np.pi),
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("test",),
        vertices=vertices,
        offsets=offsets,
        orientation=np.zeros(n, dtype=np.float64),
        centre=centre,
        insertion_index=insertion_index,
        domain=domain,
        scene={"name": "test"},
        seed=0,
    )
