"""Compiled area of the intersection of convex cells and convex particles."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.halfplane_clip import clip_halfplane

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@numba.njit(cache=True)
def overlap_areas(
    ci: IntArray,
    pj: IntArray,
    cx: FloatArray,
    cy: FloatArray,
    coff: IntArray,
    px: FloatArray,
    py: FloatArray,
    poff: IntArray,
) -> FloatArray:
    """Area of the intersection of convex cell ``ci[k]`` and convex particle ``pj[k]``, each ``k``.

    Cells and particles are counter-clockwise rings, vertices ``coff[c]:coff[c + 1]``
    of ``cx, cy`` and ``poff[p]:poff[p + 1]`` of ``px, py``; the particle is
    clipped by the half-plane of every cell edge in turn.
    """
    room = 3
    for c in range(len(coff) - 1):
        room = max(room, coff[c + 1] - coff[c])
    big = 3
    for p in range(len(poff) - 1):
        big = max(big, poff[p + 1] - poff[p])
    room += big + 2
    ax = np.empty(room)
    ay = np.empty(room)
    bx = np.empty(room)
    by = np.empty(room)
    out = np.zeros(len(ci))
    for k in range(len(ci)):
        c, p = ci[k], pj[k]
        n = poff[p + 1] - poff[p]
        for t in range(n):
            ax[t] = px[poff[p] + t]
            ay[t] = py[poff[p] + t]
        first, last = coff[c], coff[c + 1]
        for e in range(first, last):
            e2 = e + 1 if e + 1 < last else first
            ex = cx[e2] - cx[e]
            ey = cy[e2] - cy[e]
            if ex == 0.0 and ey == 0.0:
                continue
            n = clip_halfplane(ax, ay, n, ey, -ex, ey * cx[e] - ex * cy[e], bx, by)
            ax, bx = bx, ax
            ay, by = by, ay
            if n < 3:
                break
        if n < 3:
            continue
        acc = 0.0
        for t in range(n):
            t2 = t + 1 if t + 1 < n else 0
            acc += ax[t] * ay[t2] - ax[t2] * ay[t]
        out[k] = max(0.5 * acc, 0.0)
    return out
