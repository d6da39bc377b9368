"""Compiled pair histogram of the radial distribution function of 3D centres."""

from __future__ import annotations

import numba
import numpy as np

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.geometry.population import FloatArray, IntArray
from regopack.plugins.analyzers.rdf_kernel import add_pair


@numba.njit(cache=True)
def weighted_pair_histogram3d(
    points: FloatArray,
    kind: IntArray,
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    side: FloatArray,
    periodic: bool,
) -> FloatArray:
    """Pair-distance histogram of ``(n, 3)`` points, weighted by the box's translation correction.

    A pair at separation ``(dx, dy, dz)`` weighs ``1 / ((a - |dx|)(b - |dy|)(c - |dz|))``
    for a walled box of sides ``side = (a, b, c)``; in a periodic box it is
    taken at its nearest image and weighs ``1 / (a b c)``. Bins are
    ``[r_lo + k width, r_lo + (k + 1) width)``. Unordered pairs are counted
    once, in cell ``[min(kind), max(kind)]`` of the ``(n_kinds, n_kinds, bins)`` result.
    """
    out = np.zeros((n_kinds, n_kinds, bins))
    r_hi = r_lo + width * bins
    r_lo2 = r_lo * r_lo
    r_hi2 = r_hi * r_hi
    a, b, c = side[0], side[1], side[2]
    n = points.shape[0]
    order = np.argsort(points[:, 0])
    xs = points[order, 0]
    ys = points[order, 1]
    zs = points[order, 2]
    ks = kind[order]
    volume = a * b * c
    for p in range(n):
        xp, yp, zp, kp = xs[p], ys[p], zs[p], ks[p]
        for q in range(p + 1, n):
            dx = xs[q] - xp  # >= 0: sorted along x
            if not periodic and dx >= r_hi:
                break
            dy = abs(ys[q] - yp)
            dz = abs(zs[q] - zp)
            if periodic:
                dx = min(dx, a - dx)
                dy = min(dy, b - dy)
                dz = min(dz, c - dz)
            d2 = dx * dx + dy * dy + dz * dz
            if d2 >= r_hi2 or d2 < r_lo2:
                continue
            if periodic:
                w = 1.0 / volume
            else:
                if dx >= a or dy >= b or dz >= c:
                    continue
                w = 1.0 / ((a - dx) * (b - dy) * (c - dz))
            add_pair(out, kp, ks[q], d2, r_lo, width, bins, w)
    return out
