"""Compiled pair histogram of the radial distribution function."""

from __future__ import annotations

import math

import numba
import numpy as np

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.geometry.population import FloatArray, IntArray


@numba.njit(cache=True)
def add_pair(
    out: FloatArray, kp: int, kq: int, d2: float, r_lo: float, width: float, bins: int, w: float
) -> None:
    """Add weight ``w`` of a pair at squared distance ``d2`` to its bin of ``out``.

    The bin is ``(sqrt(d2) - r_lo) / width``, the last one for a distance at
    the upper end; the cell is ``[min(kp, kq), max(kp, kq)]``.
    """
    k = int((math.sqrt(d2) - r_lo) / width)
    if k >= bins:
        k = bins - 1
    if kp <= kq:
        out[kp, kq, k] += w
    else:
        out[kq, kp, k] += w


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
    translation: bool = True,
    n_real: int = -1,
) -> FloatArray:
    """Pair-distance histogram weighted by the translation correction ``1/((a-|dx|)(b-|dy|))``.

    Bins are ``[r_lo + k width, r_lo + (k + 1) width)``. Unordered pairs are
    counted once, in cell ``[min(kind), max(kind)]`` of the result, whose shape
    is ``(n_kinds, n_kinds, bins)``. With ``translation`` false every pair
    weighs 1. Points from index ``n_real`` on (``-1``: none) are periodic
    ghosts: a pair of two ghosts is not counted and a pair of a point and a
    ghost weighs half (it is found once from each side).
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
    ghost = order >= n_real if n_real >= 0 else np.zeros(n, dtype=np.bool_)
    for p in range(n):
        xp = xs[p]
        yp = ys[p]
        kp = ks[p]
        gp = ghost[p]
        for q in range(p + 1, n):
            dx = xs[q] - xp
            if dx >= r_hi:
                break
            dy = ys[q] - yp
            d2 = dx * dx + dy * dy
            if d2 >= r_hi2 or d2 < r_lo2:
                continue
            if gp and ghost[q]:
                continue
            w = 1.0 / ((a - dx) * (b - abs(dy))) if translation else 1.0
            if gp or ghost[q]:
                w *= 0.5
            add_pair(out, kp, ks[q], d2, r_lo, width, bins, w)
    return out
