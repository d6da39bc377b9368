"""Sieve classes of equivalent diameter and the particles of each class.

The classes are √2 wide: their bounds are ``d_ref · √2^k``, with ``d_ref`` the
scene's ``size.d_min`` (or the smallest drawn diameter), for the ``k`` that
cover the drawn diameters. A class holds ``lo <= d < hi``; the last one also
its upper bound. Diameters are equivalent diameters, ``d = 2 r`` with
``π r²`` the particle's area.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.packing.core import Packing

__all__ = ["SIEVE_RATIO", "class_of", "reference_diameter", "sieve_edges", "unplaced_per_class"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SIEVE_RATIO = math.sqrt(2.0)
"""Ratio of the upper to the lower bound of every class."""


def reference_diameter(packing: Packing) -> float | None:
    """Return the scene's ``size.d_min`` of a 2D or 3D packing, when it has one."""
    size = packing.scene.get("size") if isinstance(packing.scene, dict) else None
    value = size.get("d_min") if isinstance(size, dict) else None
    return float(value) if isinstance(value, int | float) and value > 0 else None


def sieve_edges(diameter: ArrayLike, d_ref: float | None = None) -> FloatArray:
    """Class bounds ``d_ref · √2^k`` covering ``diameter``.

    Parameters
    ----------
    diameter
        Equivalent diameters (at least one, all positive).
    d_ref
        A class bound; default: the smallest diameter.

    Examples
    --------
    >>> sieve_edges([2.0, 3.0, 5.9], d_ref=2.0).round(3).tolist()
    [2.0, 2.828, 4.0, 5.657, 8.0]
    """
    d = np.asarray(diameter, dtype=np.float64)
    if d.size == 0 or not np.all(np.isfinite(d) & (d > 0)):
        raise ValueError("sieve classes need at least one finite, positive diameter")
    lo, hi = float(d.min()), float(d.max())
    ref = lo if d_ref is None else float(d_ref)
    step = math.log(SIEVE_RATIO)
    k0 = math.floor(math.log(lo / ref) / step + 1e-9)
    k1 = max(k0 + 1, math.ceil(math.log(hi / ref) / step - 1e-9))
    return np.asarray(ref * SIEVE_RATIO ** np.arange(k0, k1 + 1), dtype=np.float64)


def class_of(diameter: ArrayLike, edges: FloatArray) -> IntArray:
    """Class of each diameter: ``k`` with ``edges[k] <= d < edges[k + 1]`` (last class closed).

    Diameters below the first or above the last bound (within rounding) go
    to the first or the last class.
    """
    d = np.asarray(diameter, dtype=np.float64)
    k = np.searchsorted(edges, d, side="right") - 1
    return np.clip(k, 0, len(edges) - 2).astype(np.int64)


def _arrays(
    source: Packing | tuple[ArrayLike, ArrayLike], d_ref: float | None
) -> tuple[FloatArray, NDArray[np.bool_], float | None]:
    if isinstance(source, Packing):
        ref = d_ref if d_ref is not None else reference_diameter(source)
        return 2.0 * source.radius, source.placed, ref
    diameter, placed = source
    return np.asarray(diameter, dtype=np.float64), np.asarray(placed, dtype=bool), d_ref


def unplaced_per_class(
    source: Packing | tuple[ArrayLike, ArrayLike], d_ref: float | None = None
) -> list[dict[str, Any]]:
    """Drawn, placed and not placed particles of every sieve class.

    Parameters
    ----------
    source
        A packing, or a pair ``(diameters, placed)`` of the equivalent
        diameters of all drawn particles and the mask of the placed ones.
    d_ref
        A class bound; default: the scene's ``size.d_min`` for a packing
        (if it has one), else the smallest drawn diameter.

    Returns
    -------
    list of dict
        One record per class, finest first: ``d_lo``, ``d_hi`` (length unit),
        ``drawn``, ``placed``, ``not_placed``. Empty without particles.

    Examples
    --------
    >>> rows = unplaced_per_class(([2.0, 2.5, 3.0, 5.0], [True, False, True, False]), 2.0)
    >>> [(round(r["d_lo"], 2), r["drawn"], r["not_placed"]) for r in rows]
    [(2.0, 2, 1), (2.83, 1, 0), (4.0, 1, 1)]
    """
    diameter, placed, ref = _arrays(source, d_ref)
    if diameter.size == 0:
        return []
    edges = sieve_edges(diameter, ref)
    k = class_of(diameter, edges)
    n = len(edges) - 1
    drawn = np.bincount(k, minlength=n)
    done = np.bincount(k[placed], minlength=n)
    return [
        {
            "d_lo": float(edges[j]),
            "d_hi": float(edges[j + 1]),
            "drawn": int(drawn[j]),
            "placed": int(done[j]),
            "not_placed": int(drawn[j] - done[j]),
        }
        for j in range(n)
    ]
