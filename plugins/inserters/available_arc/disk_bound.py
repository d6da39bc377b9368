"""A certified bound on the disks a disk candidate can still take.

In a scene of disks, a disk of radius ``r`` touching candidate ``k`` at polar
angle ``θ`` contains every smaller disk touching ``k`` at ``θ`` (their centres
lie on the same ray, ``R - r`` apart, which is the difference of their
radii). So the angles where a disk of radius ``r`` is free of the other
particles can only shrink as ``r`` grows: once no disk of radius ``r`` fits
anywhere around ``k``, no larger one does, whatever comes to lie next to
``k`` later (particles are only added).

When an analysis of ``k`` finds no arc, :func:`disk_bound` looks for the
smallest radius ``ρ`` at which the interferers of that analysis alone, walls
left out, cover the whole circle of possible centres, each by more than
:data:`MARGIN` radians; any later analysis of ``k`` for a disk of radius
``ρ`` or more would then find no arc either (leaving out walls and particles
only uncovers angles, so the bound is an upper one). The kernel skips those
analyses. The packing is the same bit for bit: a skipped analysis is one
that finds nothing.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]

MARGIN = 1e-6
"""Angle (radians) by which each interferer must overlap the next for a circle to count as
covered, so that rounding in a later analysis cannot open a gap the bound says is shut
(an overlap only deepens as the disk grows)."""
STEPS = 6
"""Halvings of the logarithmic interval between the smallest radius and the failed one."""
SORT_IN_PLACE = 32
"""Up to this many covers are sorted by insertion; more (a large disk among many small ones)
by Shell's passes first (:data:`SHELL_GAPS`), in place as well."""
SHELL_GAPS = (
    1, 4, 10, 23, 57, 132, 301, 701, 1577, 3548, 7983, 17961, 40412, 90927, 204585, 460316,
    1035711, 2330349, 5243285, 11797391,
)  # fmt: skip
"""Gaps of the passes before the last (Ciura's, then 2.25 times the one before)."""


@numba.njit(cache=True, inline="always")
def _insertion_pass(lo: FloatArray, hi: FloatArray, k: int, gap: int) -> None:
    """Sort every ``gap``-th pair of ``(lo, hi)[:k]`` by ``lo``, by insertion."""
    for idx in range(gap, k):
        x = lo[idx]
        y = hi[idx]
        j = idx
        while j >= gap and lo[j - gap] > x:
            lo[j] = lo[j - gap]
            hi[j] = hi[j - gap]
            j -= gap
        lo[j] = x
        hi[j] = y


@numba.njit(cache=True)
def sort_covers(lo: FloatArray, hi: FloatArray, k: int) -> None:
    """Sort the intervals ``(lo[m], hi[m])``, ``m < k``, by their lower ends, in place.

    Up to :data:`SORT_IN_PLACE` by insertion; more by Shell's passes, the last
    of which is that insertion (no allocation). Which of two equal lower ends
    comes first is left open: the sweeps over the sorted covers do not depend
    on it.
    """
    if k > SORT_IN_PLACE:
        for m in range(len(SHELL_GAPS) - 1, 0, -1):
            gap = SHELL_GAPS[m]
            if gap < k:
                _insertion_pass(lo, hi, k, gap)
    _insertion_pass(lo, hi, k, 1)


@numba.njit(cache=True)
def covered(
    rk: float,
    r: float,
    nf: int,
    dist: FloatArray,
    angle: FloatArray,
    orad: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
) -> bool:
    """Whether the disks of radii ``orad[f] + r`` cover the circle of radius ``rk + r`` about 0.

    Interferer ``f`` lies at distance ``dist[f]`` and polar angle ``angle[f]``
    from the origin. Each cover must exceed :data:`MARGIN` at both ends (a
    disk holding the whole circle, by ``MARGIN`` times its radius);
    ``lo`` and ``hi`` are scratch of length ``2 * nf``.
    """
    e = rk + r
    k = 0
    for f in range(nf):
        # as rounded._circle_cover, with the interferer's distance and direction known
        d = dist[f]
        r2 = orad[f] + r
        if d + e <= r2 - MARGIN * e:
            return True  # the whole circle lies inside, deeper than the margin
        if d >= e + r2 or d + r2 <= e or d == 0.0:
            continue
        c = (e * e + d * d - r2 * r2) / (2.0 * e * d)
        half = math.acos(min(max(c, -1.0), 1.0)) - MARGIN
        if half <= 0.0:
            continue
        a = angle[f] - half
        a -= 2.0 * math.pi * math.floor(a / (2.0 * math.pi))
        lo[k] = a
        hi[k] = a + 2.0 * half
        k += 1
        if a + 2.0 * half > 2.0 * math.pi:  # its copy one turn lower covers the start
            lo[k] = a - 2.0 * math.pi
            hi[k] = a + 2.0 * half - 2.0 * math.pi
            k += 1
    if k == 0:
        return False
    sort_covers(lo, hi, k)
    start = lo[0]
    reach = hi[0]
    for idx in range(1, k):
        if lo[idx] >= reach:
            return False  # a gap (open covers: a shared end is not covered)
        if hi[idx] > reach:
            reach = hi[idx]
    return reach > start + 2.0 * math.pi


@numba.njit(cache=True)
def disk_bound(
    rk: float,
    r_fail: float,
    r_floor: float,
    nf: int,
    ocx: FloatArray,
    ocy: FloatArray,
    orad: FloatArray,
    scratch: FloatArray | None = None,
) -> float:
    """Radius from which no disk touching the candidate fits; ``inf`` if none is shown.

    Parameters
    ----------
    rk
        The candidate's radius; it lies at the origin.
    r_fail
        Radius of the disk its analysis has just refused.
    r_floor
        The smallest radius of the scene: a candidate covered there is shut for all.
    nf, ocx, ocy, orad
        That analysis's interferers: centres relative to the candidate and radii.
    scratch
        Rows 6 to 9 serve as the covers, distances and angles when they fit (see
        ``kernel.Work.fs``).
    """
    if nf < 2:
        return math.inf
    if scratch is not None and 2 * nf <= scratch.shape[1]:
        lo = scratch[6]
        hi = scratch[7]
        dist = scratch[8]
        angle = scratch[9]
    else:
        lo = np.empty(2 * nf)
        hi = np.empty(2 * nf)
        dist = np.empty(nf)
        angle = np.empty(nf)
    for f in range(nf):
        dist[f] = math.hypot(ocx[f], ocy[f])
        angle[f] = math.atan2(ocy[f], ocx[f])
    if not covered(rk, r_fail, nf, dist, angle, orad, lo, hi):
        return math.inf  # a wall shut it, or the overlaps are too thin to certify
    if r_floor >= r_fail:
        return r_fail
    if covered(rk, r_floor, nf, dist, angle, orad, lo, hi):
        return r_floor
    a = math.log(r_floor)  # open
    b = math.log(r_fail)  # shut
    shut = r_fail
    for _ in range(STEPS):
        mid = 0.5 * (a + b)
        r = math.exp(mid)
        if covered(rk, r, nf, dist, angle, orad, lo, hi):
            b = mid
            shut = r
        else:
            a = mid
    return shut
