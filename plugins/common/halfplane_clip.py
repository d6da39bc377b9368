"""Compiled clipping of a convex polygon by a half-plane (shared by several plugins)."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]


@numba.njit(cache=True)
def clip_halfplane(
    px: FloatArray,
    py: FloatArray,
    count: int,
    a: float,
    b: float,
    c: float,
    qx: FloatArray,
    qy: FloatArray,
) -> int:
    """Clip the polygon ``p[:count]`` by ``a x + b y <= c`` into ``q``; return the new count.

    One Sutherland-Hodgman step; ``q`` needs room for ``count + 1`` vertices.
    """
    out = 0
    for j in range(count):
        j2 = j + 1 if j + 1 < count else 0
        f1 = c - (a * px[j] + b * py[j])
        f2 = c - (a * px[j2] + b * py[j2])
        if f1 >= 0.0:
            qx[out] = px[j]
            qy[out] = py[j]
            out += 1
        if (f1 >= 0.0) != (f2 >= 0.0):
            u = f1 / (f1 - f2)
            qx[out] = px[j] + u * (px[j2] - px[j])
            qy[out] = py[j] + u * (py[j2] - py[j])
            out += 1
    return out
