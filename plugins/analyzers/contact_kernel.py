"""Compiled geometry of contact detection between grown convex polygons.

Each particle is grown by ``s = tol / 2`` along every edge normal (a mitred
offset that keeps the edge directions). The grown outline's vertex ``e``
moves along its mitre vector ``m_e`` (``n_{e-1} . m_e = n_e . m_e = 1``), so
every support value is linear in ``s`` and the separating-axis test gives,
per pair, the exact threshold ``s*`` above which the grown polygons overlap
with positive area. Contacts at any tolerance then follow without a new
search: a pair is in contact at ``tol`` when ``s* < tol / 2``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.halfplane_clip import clip_halfplane

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
DEGENERATE_EDGE = 1e-12


@numba.njit(cache=True)
def edge_normals_and_mitres(
    vertices: FloatArray, offsets: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Compute unit outward edge normals, vertex mitres and the largest mitre per particle.

    Edge ``e`` runs from vertex ``e`` to ``e + 1``. Edges shorter than
    ``1e-12`` of the circumradius take normals spaced evenly between their
    proper neighbours (exact for the octagon plugin's collapsed edges).

    Returns
    -------
    nx, ny
        Normal of every edge.
    mx, my
        Mitre vector of every vertex (between edges ``e - 1`` and ``e``).
    mitre_max
        Largest mitre length of every particle.
    """
    total = vertices.shape[0]
    n = offsets.shape[0] - 1
    nx = np.empty(total)
    ny = np.empty(total)
    mx = np.empty(total)
    my = np.empty(total)
    mitre_max = np.zeros(n)
    for p in range(n):
        s = offsets[p]
        m = offsets[p + 1] - s
        if m == 0:
            continue
        rad = 0.0
        for j in range(m):
            rad = max(rad, math.hypot(vertices[s + j, 0], vertices[s + j, 1]))
        ang = np.empty(m)
        good = np.zeros(m, dtype=np.bool_)
        ngood = 0
        for j in range(m):
            j2 = j + 1 if j + 1 < m else 0
            dx = vertices[s + j2, 0] - vertices[s + j, 0]
            dy = vertices[s + j2, 1] - vertices[s + j, 1]
            ang[j] = math.atan2(-dx, dy)  # outward normal of a counter-clockwise edge
            if math.hypot(dx, dy) > DEGENERATE_EDGE * rad:
                good[j] = True
                ngood += 1
        if ngood < m and ngood > 0:
            # fill runs of degenerate edges by even spacing between proper neighbours
            for j in range(m):
                if good[j]:
                    continue
                b = j
                while not good[b % m]:
                    b -= 1
                f = j
                while not good[f % m]:
                    f += 1
                a0 = ang[b % m]
                a1 = ang[f % m]
                while a1 <= a0:
                    a1 += 2.0 * math.pi
                ang[j] = a0 + (a1 - a0) * (j - b) / (f - b)
        for j in range(m):
            nx[s + j] = math.cos(ang[j])
            ny[s + j] = math.sin(ang[j])
        for j in range(m):
            jp = j - 1 if j > 0 else m - 1
            c = 1.0 + nx[s + jp] * nx[s + j] + ny[s + jp] * ny[s + j]
            if c < 1e-12:
                c = 1e-12
            mx[s + j] = (nx[s + jp] + nx[s + j]) / c
            my[s + j] = (ny[s + jp] + ny[s + j]) / c
            mitre_max[p] = max(mitre_max[p], math.hypot(mx[s + j], my[s + j]))
    return nx, ny, mx, my, mitre_max


@numba.njit(cache=True)
def _support(
    p: int,
    ux: float,
    uy: float,
    vertices: FloatArray,
    offsets: IntArray,
    mx: FloatArray,
    my: FloatArray,
    big: float,
) -> tuple[float, float]:
    """Return the support of particle ``p`` (local frame) along ``u`` and its growth rate."""
    h0 = -np.inf
    h1 = -np.inf
    for e in range(offsets[p], offsets[p + 1]):
        a = ux * vertices[e, 0] + uy * vertices[e, 1]
        b = ux * mx[e] + uy * my[e]
        if a > h0:
            h0 = a
        if a + big * b > h1:
            h1 = a + big * b
    return h0, (h1 - h0) / big


@numba.njit(cache=True)
def pair_threshold(
    i: int,
    j: int,
    centre: FloatArray,
    vertices: FloatArray,
    offsets: IntArray,
    nx: FloatArray,
    ny: FloatArray,
    mx: FloatArray,
    my: FloatArray,
    scale: float,
) -> float:
    """Growth ``s*`` above which particles ``i`` and ``j`` overlap with positive area.

    Separating-axis test over the edge normals of both grown outlines; every
    gap is linear in the growth ``s``. Negative when they already overlap.
    """
    dx = centre[j, 0] - centre[i, 0]
    dy = centre[j, 1] - centre[i, 1]
    best = -np.inf
    for side in range(2):
        p = i if side == 0 else j
        sign = 1.0 if side == 0 else -1.0
        for e in range(offsets[p], offsets[p + 1]):
            ux = sign * nx[e]
            uy = sign * ny[e]
            hi, ri = _support(i, ux, uy, vertices, offsets, mx, my, scale)
            hj, rj = _support(j, -ux, -uy, vertices, offsets, mx, my, scale)
            gap = ux * dx + uy * dy - hi - hj
            rate = ri + rj
            if rate > 0.0:
                v = gap / rate
                if v > best:
                    best = v
            elif gap >= 0.0:
                return np.inf
    return best


@numba.njit(cache=True)
def candidate_pairs(
    centre: FloatArray, reach: FloatArray, bounds: FloatArray
) -> tuple[IntArray, IntArray]:
    """All pairs ``i < j`` whose disks of radius ``reach`` overlap (cell grid over ``bounds``)."""
    n = centre.shape[0]
    if n < 2:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    width = bounds[1] - bounds[0]
    height = bounds[3] - bounds[2]
    med = np.median(reach)
    cell = max(2.0 * med, math.sqrt(width * height / (4.0 * n)), 1e-300)
    gnx = max(1, math.ceil(width / cell))
    gny = max(1, math.ceil(height / cell))
    # count registrations
    counts = np.zeros(gnx * gny + 1, dtype=np.int64)
    lo_x = np.empty(n, dtype=np.int64)
    hi_x = np.empty(n, dtype=np.int64)
    lo_y = np.empty(n, dtype=np.int64)
    hi_y = np.empty(n, dtype=np.int64)
    for p in range(n):
        lo_x[p] = min(max(math.floor((centre[p, 0] - reach[p] - bounds[0]) / cell), 0), gnx - 1)
        hi_x[p] = min(max(math.floor((centre[p, 0] + reach[p] - bounds[0]) / cell), 0), gnx - 1)
        lo_y[p] = min(max(math.floor((centre[p, 1] - reach[p] - bounds[2]) / cell), 0), gny - 1)
        hi_y[p] = min(max(math.floor((centre[p, 1] + reach[p] - bounds[2]) / cell), 0), gny - 1)
        for gy in range(lo_y[p], hi_y[p] + 1):
            for gx in range(lo_x[p], hi_x[p] + 1):
                counts[gy * gnx + gx + 1] += 1
    start = np.cumsum(counts)
    fill = start[:-1].copy()
    items = np.empty(start[-1], dtype=np.int64)
    for p in range(n):
        for gy in range(lo_y[p], hi_y[p] + 1):
            for gx in range(lo_x[p], hi_x[p] + 1):
                c = gy * gnx + gx
                items[fill[c]] = p
                fill[c] += 1
    stamp = np.full(n, -1, dtype=np.int64)
    out_i = np.empty(16 * n, dtype=np.int64)
    out_j = np.empty(16 * n, dtype=np.int64)
    k = 0
    for p in range(n):
        for gy in range(lo_y[p], hi_y[p] + 1):
            for gx in range(lo_x[p], hi_x[p] + 1):
                c = gy * gnx + gx
                for e in range(start[c], start[c + 1]):
                    q = items[e]
                    if q <= p or stamp[q] == p:
                        continue
                    stamp[q] = p
                    ddx = centre[q, 0] - centre[p, 0]
                    ddy = centre[q, 1] - centre[p, 1]
                    lim = reach[p] + reach[q]
                    if ddx * ddx + ddy * ddy < lim * lim:
                        if k == out_i.shape[0]:
                            gi = np.empty(2 * k, dtype=np.int64)
                            gj = np.empty(2 * k, dtype=np.int64)
                            gi[:k] = out_i
                            gj[:k] = out_j
                            out_i = gi
                            out_j = gj
                        out_i[k] = p
                        out_j[k] = q
                        k += 1
    return out_i[:k].copy(), out_j[:k].copy()


@numba.njit(cache=True)
def thresholds(
    pi: IntArray,
    pj: IntArray,
    centre: FloatArray,
    vertices: FloatArray,
    offsets: IntArray,
    nx: FloatArray,
    ny: FloatArray,
    mx: FloatArray,
    my: FloatArray,
    circum: FloatArray,
) -> FloatArray:
    """Contact threshold ``s*`` of every candidate pair."""
    out = np.empty(pi.shape[0])
    for k in range(pi.shape[0]):
        scale = circum[pi[k]] + circum[pj[k]]
        out[k] = pair_threshold(pi[k], pj[k], centre, vertices, offsets, nx, ny, mx, my, scale)
    return out


@numba.njit(cache=True)
def contact_regions(
    pi: IntArray,
    pj: IntArray,
    s: float,
    centre: FloatArray,
    vertices: FloatArray,
    offsets: IntArray,
    nx: FloatArray,
    ny: FloatArray,
    mx: FloatArray,
    my: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Area, width (longest chord), chord midpoint and unit normal of each contact region.

    The region is the intersection of both outlines grown by ``s``; the normal
    is perpendicular to the longest chord and points from ``i`` to ``j``.
    """
    k_all = pi.shape[0]
    area = np.zeros(k_all)
    width = np.zeros(k_all)
    cx = np.zeros(k_all)
    cy = np.zeros(k_all)
    unx = np.zeros(k_all)
    uny = np.zeros(k_all)
    mmax = 0
    for p in range(offsets.shape[0] - 1):
        mmax = max(mmax, offsets[p + 1] - offsets[p])
    cap = 4 * mmax + 8
    ax = np.empty(cap)
    ay = np.empty(cap)
    bx = np.empty(cap)
    by = np.empty(cap)
    for k in range(k_all):
        i = pi[k]
        j = pj[k]
        # grown outline of i relative to i's centre
        cnt = 0
        for e in range(offsets[i], offsets[i + 1]):
            ax[cnt] = vertices[e, 0] + s * mx[e]
            ay[cnt] = vertices[e, 1] + s * my[e]
            cnt += 1
        ox = centre[j, 0] - centre[i, 0]
        oy = centre[j, 1] - centre[i, 1]
        # clip by every grown half-plane of j: n . (x - o) <= h + s
        for e in range(offsets[j], offsets[j + 1]):
            hx = nx[e]
            hy = ny[e]
            lim = hx * (vertices[e, 0] + ox) + hy * (vertices[e, 1] + oy) + s
            cnt = clip_halfplane(ax, ay, cnt, hx, hy, lim, bx, by)
            for q in range(cnt):
                ax[q] = bx[q]
                ay[q] = by[q]
            if cnt == 0:
                break
        if cnt < 3:
            continue
        a2 = 0.0
        for q in range(cnt):
            q2 = q + 1 if q + 1 < cnt else 0
            a2 += ax[q] * ay[q2] - ax[q2] * ay[q]
        area[k] = 0.5 * abs(a2)
        best = -1.0
        b1 = 0
        b2 = 0
        for q in range(cnt):
            for r in range(q + 1, cnt):
                d = (ax[q] - ax[r]) ** 2 + (ay[q] - ay[r]) ** 2
                if d > best:
                    best = d
                    b1 = q
                    b2 = r
        width[k] = math.sqrt(max(best, 0.0))
        cx[k] = centre[i, 0] + 0.5 * (ax[b1] + ax[b2])
        cy[k] = centre[i, 1] + 0.5 * (ay[b1] + ay[b2])
        tx = ax[b2] - ax[b1]
        ty = ay[b2] - ay[b1]
        tl = math.hypot(tx, ty)
        if tl > 0.0:
            vx = -ty / tl
            vy = tx / tl
        else:
            dl = math.hypot(ox, oy)
            vx = ox / dl if dl > 0 else 1.0
            vy = oy / dl if dl > 0 else 0.0
        if vx * ox + vy * oy < 0.0:
            vx = -vx
            vy = -vy
        unx[k] = vx
        uny[k] = vy
    return area, width, cx, cy, unx, uny
