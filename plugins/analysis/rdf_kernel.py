"""Compiled pair histogram of the radial distribution function."""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@numba.njit(cache=True)
def weighted_pair_histogram(
    x: FloatArray,
    y: FloatArray,
    kind: IntArray,
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    a: float,
    b: float,
) -> FloatArray:
    """Pair-distance histogram weighted by the translation correction ``1/((a-|dx|)(b-|dy|))``.

    Bins are ``[r_lo + k width, r_lo + (k + 1) width)``. Unordered pairs are
    counted once, in cell ``[min(kind), max(kind)]`` of the result, whose shape
    is ``(n_kinds, n_kinds, bins)``.
    """
    out = np.zeros((n_kinds, n_kinds, bins))
    r_hi = r_lo + width * bins
    r_lo2 = r_lo * r_lo
    r_hi2 = r_hi * r_hi
    n = x.shape[0]
    order = np.argsort(x)
    xs = x[order]
    ys = y[order]
    ks = kind[order]
    for p in range(n):
        xp = xs[p]
        yp = ys[p]
        kp = ks[p]
        for q in range(p + 1, n):
            dx = xs[q] - xp
            if dx >= r_hi:
                break
            dy = ys[q] - yp
            d2 = dx * dx + dy * dy
            if d2 >= r_hi2 or d2 < r_lo2:
                continue
            k = int((math.sqrt(d2) - r_lo) / width)
            if k >= bins:
                k = bins - 1
            w = 1.0 / ((a - dx) * (b - abs(dy)))
            kq = ks[q]
            if kp <= kq:
                out[kp, kq, k] += w
            else:
                out[kq, kp, k] += w
    return out
