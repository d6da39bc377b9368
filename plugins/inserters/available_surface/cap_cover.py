r"""Whether caps cover a sphere, certified from the vertices of their arrangement.

The caps are open, ``{u : n_q · u > h_q}`` on the sphere ``|u| = R``, each
read shrunk by ``shrink`` and by a further ``margin``: ``D_q = {n_q · u >
h_q + shrink + margin}``. When the sphere is not covered, the uncovered set
``S \ ∪ D_q`` is closed, not the whole sphere (there is a cap left after the
shrinking: when every cap shrinks to nothing the whole sphere is free and the
answer is :data:`OPEN`), and so has a
boundary; that boundary is made of arcs of the caps' circles and either
passes through a *vertex* (a point where two circles meet) or is a whole
circle that meets no other. Hence the sphere is covered when

- every vertex lies in a third cap ``D_p``, and
- every circle that meets no other has a point in another cap (the whole
  circle is then inside it).

Half the vertices suffice. Walk a boundary cycle of the uncovered set with
the set on the left: at each corner the walk leaves circle ``a`` for circle
``b`` at the one of their two common points where ``det(n_a, n_b, v)`` has a
sign ``sigma`` that does not depend on the corner (the local picture is the
same wedge between two caps). Of a pair ``j < q``, call the common point with
``det(n_j, n_q, v) > 0`` (the side of ``n_j x n_q``) its *first* vertex.
The circles' indices along a cycle of two corners or more rise somewhere and
fall somewhere, so some corner leaves a circle for one of a higher index and
some for one of a lower: whatever ``sigma``, one of them is a first vertex.
The uncovered set, when there is one, thus has a first vertex on its
boundary (or a circle that meets no other), and only first vertices are
checked.

:func:`cover_by_vertices` checks this in ``O(n^2)`` vertices, each against
the caps until one holds it: no trigonometry and no sorting, several times
cheaper than following every circle's covered arcs (:func:`.spheres.covers`,
:func:`.spheres.free_arcs`) on the fully covered spheres that most analyses
of a dense packing meet. Each vertex is computed with a bound on its
rounding error and must lie in its cap by more than that bound; a pair of
circles too close to tangent, or to the same plane, for the bound to be
small leaves the answer :data:`UNSURE`, as does a vertex on the edge of the
cap that would hold it. The answer :data:`COVERED` is therefore certain:
every point of the sphere lies deeper than ``margin`` in some cap shrunk by
``shrink``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]

COVERED, OPEN, UNSURE = 1, 0, -1
"""Answers of :func:`cover_by_vertices`: covered for certain, a point left free, not decided."""

ROUNDING = 64.0 * np.finfo(np.float64).eps
"""Relative rounding unit of a vertex's error bound (a generous multiple of the machine's)."""
NEAR_PARALLEL = 1e-8
"""Below this ``1 - cos^2`` of the angle between two caps' axes their circles' vertices are not
computed: the circles are told apart by their angular radii, or the answer is unsure."""
PARALLEL_GAP = 1e-6
"""Angle (radians) by which two nearly parallel circles must miss each other to count as apart."""
WORST = 1e-9
"""Largest error bound of a vertex, relative to ``R``, that :func:`cover_by_vertices` accepts."""


@numba.njit(cache=True)
def _held(
    caps: FloatArray, ncaps: int, lift: float, a: int, b: int, x: float, y: float, z: float,
    err: float, first: int,
) -> int:  # fmt: skip
    """Return a cap other than ``a`` and ``b`` holding ``(x, y, z)`` deeper than ``err``, or -1.

    The caps are tried from ``first`` on (round), so that the cap that held the
    last vertex, likely near, is tried first.
    """
    for m in range(ncaps):
        p = first + m
        if p >= ncaps:
            p -= ncaps
        if p == a or p == b:
            continue
        if caps[p, 0] * x + caps[p, 1] * y + caps[p, 2] * z > caps[p, 3] + lift + err:
            return p
    return -1


@numba.njit(cache=True)
def cover_by_vertices(
    caps: FloatArray, ncaps: int, big_r: float, shrink: float, margin: float
) -> int:
    """Certify that the caps, shrunk by ``shrink + margin``, cover the sphere of radius ``big_r``.

    ``caps`` rows are ``(nx, ny, nz, h)`` with unit normals. Returns
    :data:`COVERED` (certain), :data:`OPEN` (a vertex, or a circle, lies in
    no other cap: not covered, up to rounding) or :data:`UNSURE` (a pair of
    circles too near tangency for the rounding bound, or a vertex within its
    error of a cap's edge). Without caps, or with every cap shrunk to nothing:
    :data:`OPEN`.
    """
    if ncaps == 0:
        return OPEN
    lift = shrink + margin
    r2 = big_r * big_r
    unit = ROUNDING * big_r
    live = False
    for q in range(ncaps):
        if caps[q, 3] + lift < -big_r - unit:
            return COVERED  # one cap holds the whole sphere
        live = live or caps[q, 3] + lift < big_r
    if not live:
        return OPEN  # every cap shrunk to nothing: the whole sphere is left
    met = np.zeros(ncaps, dtype=np.bool_)
    answer = COVERED
    hint = 0
    for j in range(ncaps):
        hj = caps[j, 3] + lift
        if hj >= big_r:
            continue  # shrunk to nothing
        nxj, nyj, nzj = caps[j, 0], caps[j, 1], caps[j, 2]
        for q in range(j + 1, ncaps):
            hq = caps[q, 3] + lift
            if hq >= big_r:
                continue
            nxq, nyq, nzq = caps[q, 0], caps[q, 1], caps[q, 2]
            c = nxj * nxq + nyj * nyq + nzj * nzq
            s2 = 1.0 - c * c
            # w = n_j x n_q, |w|^2 = s2; a vertex is alpha n_j + beta n_q + gamma w
            wx = nyj * nzq - nzj * nyq
            wy = nzj * nxq - nxj * nzq
            wz = nxj * nyq - nyj * nxq
            if not s2 > NEAR_PARALLEL:
                # (nearly) parallel planes: two circles of angular radii tj, tq whose
                # axes are ``apart`` meet when |tj - tq| <= apart <= min(tj + tq,
                # 2 pi - tj - tq); clearly outside that, they do not
                apart = math.atan2(math.sqrt(max(s2, 0.0)), c)
                tj = math.acos(min(max(hj / big_r, -1.0), 1.0))
                tq = math.acos(min(max(hq / big_r, -1.0), 1.0))
                low = abs(tj - tq)
                high = min(tj + tq, 2.0 * math.pi - tj - tq)
                if apart < low - PARALLEL_GAP or apart > high + PARALLEL_GAP:
                    continue
                return UNSURE
            alpha = (hj - c * hq) / s2
            beta = (hq - c * hj) / s2
            rest = r2 - (alpha * hj + beta * hq)  # gamma^2 s2
            err_rest = 16.0 * unit * big_r / s2
            if rest < -err_rest:
                continue  # the circles do not meet
            if rest <= err_rest:
                return UNSURE  # tangent, within rounding
            root = math.sqrt(rest)
            err = unit * (8.0 / s2 + 8.0 * big_r / (s2 * math.sqrt(s2) * root) + 2.0)
            if err > WORST * big_r:
                return UNSURE
            met[j] = True
            met[q] = True
            gamma = root / math.sqrt(s2)
            bx = alpha * nxj + beta * nxq
            by = alpha * nyj + beta * nyq
            bz = alpha * nzj + beta * nzq
            # the vertex on the side of n_j x n_q only (see the module docstring)
            x = bx + gamma * wx
            y = by + gamma * wy
            z = bz + gamma * wz
            p = _held(caps, ncaps, lift, j, q, x, y, z, err, hint)
            if p >= 0:
                hint = p
            elif _held(caps, ncaps, lift, j, q, x, y, z, -err, 0) < 0:
                return OPEN
            else:
                answer = UNSURE  # on a cap's edge, within rounding
    for j in range(ncaps):
        hj = caps[j, 3] + lift
        if met[j] or hj >= big_r:
            continue
        # a circle that meets no other: inside another cap, or a boundary of the free set
        nx, ny, nz = caps[j, 0], caps[j, 1], caps[j, 2]
        if abs(nx) < 0.9:
            ex, ey, ez = 0.0, -nz, ny
        else:
            ex, ey, ez = nz, 0.0, -nx
        inv = 1.0 / math.sqrt(ex * ex + ey * ey + ez * ez)
        rc = math.sqrt(max(r2 - hj * hj, 0.0))
        x = hj * nx + rc * ex * inv
        y = hj * ny + rc * ey * inv
        z = hj * nz + rc * ez * inv
        if _held(caps, ncaps, lift, j, j, x, y, z, 4.0 * unit, 0) < 0:
            return OPEN if answer == COVERED else UNSURE
    return answer
