"""Compiled geometry of contact detection between grown convex polyhedra.

Each particle is grown by ``s = tol / 2`` along every face normal: its face
``k`` moves from the plane ``n_k . x = b_k`` to ``n_k . x = b_k + s`` (a
mitred offset that keeps the face directions). Two grown particles share
volume exactly when ``s`` exceeds the pair's threshold

    t* = min over (x, t) of t  subject to  n_k . x - t <= b_k  for the faces of both,

a linear program in four unknowns: ``t*`` is the smallest growth at which a
point lies inside both grown solids (negative when they overlap). It is
solved here through its dual (find weights ``w_k >= 0`` of the face normals
with ``sum w_k n_k = 0`` and ``sum w_k = 1`` that minimise ``sum w_k b_k``;
then ``t* = -min``) by a dense two-phase simplex with Bland's rule. The
optimal weights of the first particle's faces add up to the normal of a plane
that separates the two solids grown by ``t*`` (and so the solids themselves
when ``t* >= 0``): the contact normal.

The contact region at ``s`` (the intersection of the grown solids) is built
by clipping a box with the face planes of both, one plane at a time; its
volume, its area projected on the plane normal to the contact normal, the
longest chord of that projection and its centroid follow.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SIMPLEX_EPS = 1e-12
"""Pivot and reduced-cost tolerance of the simplex, in the pair's scaled frame."""
CLIP_EPS = 1e-12
"""Distance (scaled frame) within which a vertex counts as lying on a clipping plane."""


@numba.njit(cache=True)
def _pivot(tab: FloatArray, basis: IntArray, row: int, col: int) -> None:
    rows, cols = tab.shape
    piv = tab[row, col]
    for c in range(cols):
        tab[row, c] /= piv
    for r in range(rows):
        if r != row:
            f = tab[r, col]
            if f != 0.0:
                for c in range(cols):
                    tab[r, c] -= f * tab[row, c]
    basis[row] = col


@numba.njit(cache=True)
def _simplex(tab: FloatArray, basis: IntArray, allowed: int, eps: float) -> bool:
    """Minimise with the reduced costs in the last row; columns ``< allowed`` may enter.

    Bland's rule (smallest entering index, smallest basic index among ties)
    cannot cycle. Returns False when the iteration cap is reached.
    """
    rows = tab.shape[0] - 1
    rhs = tab.shape[1] - 1
    for _ in range(50 * (allowed + rows) + 100):
        col = -1
        for c in range(allowed):
            if tab[rows, c] < -eps:
                col = c
                break
        if col < 0:
            return True
        row = int(np.int64(-1))  # not a literal -1 (a second compilation of _pivot)
        best = np.inf
        for r in range(rows):
            a = tab[r, col]
            if a > eps:
                ratio = tab[r, rhs] / a
                if ratio < best - eps or (abs(ratio - best) <= eps and basis[r] < basis[row]):
                    best = ratio
                    row = r
        if row < 0:
            return False  # unbounded: impossible for this program
        _pivot(tab, basis, row, col)
    return False


@numba.njit(cache=True)
def _pair_threshold(
    normals: FloatArray, offsets: FloatArray, first: int
) -> tuple[float, float, float, float]:
    """Threshold ``t*`` and the separating normal of one pair, in its scaled frame.

    ``normals`` and ``offsets`` hold the face planes of both particles, the
    first particle's ``first`` faces first. Returns NaNs when the simplex fails.
    """
    m = normals.shape[0]
    rows = 4
    tab = np.zeros((rows + 1, m + rows + 1))
    rhs = m + rows
    for k in range(m):
        tab[0, k] = normals[k, 0]
        tab[1, k] = normals[k, 1]
        tab[2, k] = normals[k, 2]
        tab[3, k] = 1.0
    tab[3, rhs] = 1.0
    basis = np.empty(rows, dtype=np.int64)
    for r in range(rows):
        tab[r, m + r] = 1.0
        basis[r] = m + r
    # phase 1: minimise the sum of the artificial variables
    for c in range(m):
        tab[rows, c] = -(tab[0, c] + tab[1, c] + tab[2, c] + tab[3, c])
    tab[rows, rhs] = -1.0
    if not _simplex(tab, basis, m, SIMPLEX_EPS):
        return math.nan, math.nan, math.nan, math.nan
    if tab[rows, rhs] < -1e-9:
        return math.nan, math.nan, math.nan, math.nan
    # drive the artificial variables out of the basis where a structural column can replace them
    for r in range(rows):
        if basis[r] >= m:
            best = int(np.int64(-1))  # not a literal -1 (see _simplex)
            big = SIMPLEX_EPS
            for c in range(m):
                if abs(tab[r, c]) > big:
                    big = abs(tab[r, c])
                    best = c
            if best >= 0:
                _pivot(tab, basis, r, best)
    # phase 2: minimise sum w_k b_k
    for c in range(m + rows + 1):
        tab[rows, c] = 0.0
    for c in range(m):
        tab[rows, c] = offsets[c]
    for r in range(rows):
        cb = offsets[basis[r]] if basis[r] < m else 0.0
        if cb != 0.0:
            for c in range(m + rows + 1):
                tab[rows, c] -= cb * tab[r, c]
    if not _simplex(tab, basis, m, SIMPLEX_EPS):
        return math.nan, math.nan, math.nan, math.nan
    t_star = tab[rows, rhs]  # the last row holds -z at its right-hand side; t* = -z_min
    wx = 0.0
    wy = 0.0
    wz = 0.0
    for r in range(rows):
        k = basis[r]
        if k < first:
            lam = tab[r, rhs]
            wx += lam * normals[k, 0]
            wy += lam * normals[k, 1]
            wz += lam * normals[k, 2]
    return t_star, wx, wy, wz


@numba.njit(cache=True)
def _planes(
    i: int,
    j: int,
    origin: FloatArray,
    scale: float,
    grow: float,
    centre: FloatArray,
    normals: FloatArray,
    support: FloatArray,
    face_offsets: IntArray,
) -> tuple[FloatArray, FloatArray, int]:
    """Face planes of particles ``i`` then ``j`` in the frame ``(x - origin) / scale``.

    Every plane is pushed out by ``grow`` (in the frame's unit). Returns the
    normals, the offsets and the number of faces of ``i``.
    """
    fi0, fi1 = face_offsets[i], face_offsets[i + 1]
    fj0, fj1 = face_offsets[j], face_offsets[j + 1]
    m = (fi1 - fi0) + (fj1 - fj0)
    nrm = np.empty((m, 3))
    off = np.empty(m)
    k = 0
    for p, f0, f1 in ((i, fi0, fi1), (j, fj0, fj1)):
        dx = centre[p, 0] - origin[0]
        dy = centre[p, 1] - origin[1]
        dz = centre[p, 2] - origin[2]
        for f in range(f0, f1):
            nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
            nrm[k, 0] = nx
            nrm[k, 1] = ny
            nrm[k, 2] = nz
            off[k] = (support[f] + nx * dx + ny * dy + nz * dz) / scale + grow
            k += 1
    return nrm, off, fi1 - fi0


@numba.njit(cache=True)
def pair_thresholds(
    pi: IntArray,
    pj: IntArray,
    centre: FloatArray,
    normals: FloatArray,
    support: FloatArray,
    face_offsets: IntArray,
    size: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """Threshold growth ``t*`` and unit contact normal (from ``i`` to ``j``) of every pair.

    ``size`` is a length per particle (its circumradius): each pair is solved
    in the frame centred between the two centres and scaled by the power of
    two next above the sum of their sizes (so that coordinates exact in
    binary stay exact). A pair whose program fails gets NaN (and a zero normal).
    """
    n = pi.shape[0]
    thr = np.full(n, np.nan)
    nrm = np.zeros((n, 3))
    origin = np.empty(3)
    for p in range(n):
        i, j = pi[p], pj[p]
        for a in range(3):
            origin[a] = 0.5 * (centre[i, a] + centre[j, a])
        scale = 2.0 ** math.ceil(math.log2(size[i] + size[j]))  # exact divisions
        planes, offs, first = _planes(
            i, j, origin, scale, 0.0, centre, normals, support, face_offsets
        )
        t, wx, wy, wz = _pair_threshold(planes, offs, first)
        if math.isnan(t):
            continue
        thr[p] = t * scale
        w = math.sqrt(wx * wx + wy * wy + wz * wz)
        if w > 1e-9:
            nrm[p, 0] = wx / w
            nrm[p, 1] = wy / w
            nrm[p, 2] = wz / w
    return thr, nrm


@numba.njit(cache=True)
def _clip(
    fv: FloatArray,
    fn: IntArray,
    nf: int,
    out: FloatArray,
    out_n: IntArray,
    cap: FloatArray,
    a: FloatArray,
    d: float,
) -> int:
    """Clip the polyhedron ``fv[:nf]`` (faces as vertex loops) by ``a . x <= d`` into ``out``.

    Returns the number of faces of the clipped polyhedron (the cap face
    last). A vertex within :data:`CLIP_EPS` of the plane lies on it.
    """
    ncap = 0
    k = 0
    coplanar = False
    for f in range(nf):
        cnt = fn[f]
        m = 0
        on = 0
        for e in range(cnt):
            q = e + 1 if e + 1 < cnt else 0
            dp = a[0] * fv[f, e, 0] + a[1] * fv[f, e, 1] + a[2] * fv[f, e, 2] - d
            dq = a[0] * fv[f, q, 0] + a[1] * fv[f, q, 1] + a[2] * fv[f, q, 2] - d
            if abs(dp) <= CLIP_EPS:
                dp = 0.0
            if abs(dq) <= CLIP_EPS:
                dq = 0.0
            if dp <= 0.0:
                for c in range(3):
                    out[k, m, c] = fv[f, e, c]
                m += 1
                if dp == 0.0:
                    on += 1
                    for c in range(3):
                        cap[ncap, c] = fv[f, e, c]
                    ncap += 1
            if (dp < 0.0 and dq > 0.0) or (dp > 0.0 and dq < 0.0):
                t = dp / (dp - dq)
                for c in range(3):
                    v = fv[f, e, c] + t * (fv[f, q, c] - fv[f, e, c])
                    out[k, m, c] = v
                    cap[ncap, c] = v
                m += 1
                ncap += 1
        if on == cnt:
            coplanar = True  # a face lies in the plane: it is the cap already
        if m >= 3:
            out_n[k] = m
            k += 1
    if ncap < 3 or coplanar:
        return k
    # order the cap's points by angle about their mean, in a basis (e1, e2) with e1 x e2 = a
    cx = 0.0
    cy = 0.0
    cz = 0.0
    for p in range(ncap):
        cx += cap[p, 0]
        cy += cap[p, 1]
        cz += cap[p, 2]
    cx /= ncap
    cy /= ncap
    cz /= ncap
    if abs(a[0]) < 0.9:
        ux, uy, uz = 1.0, 0.0, 0.0
    else:
        ux, uy, uz = 0.0, 1.0, 0.0
    # e1 = normalise(u - (u.a) a), e2 = a x e1
    ua = ux * a[0] + uy * a[1] + uz * a[2]
    e1x, e1y, e1z = ux - ua * a[0], uy - ua * a[1], uz - ua * a[2]
    ln = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x /= ln
    e1y /= ln
    e1z /= ln
    e2x = a[1] * e1z - a[2] * e1y
    e2y = a[2] * e1x - a[0] * e1z
    e2z = a[0] * e1y - a[1] * e1x
    ang = np.empty(ncap)
    order = np.empty(ncap, dtype=np.int64)
    for p in range(ncap):
        rx, ry, rz = cap[p, 0] - cx, cap[p, 1] - cy, cap[p, 2] - cz
        ang[p] = math.atan2(rx * e2x + ry * e2y + rz * e2z, rx * e1x + ry * e1y + rz * e1z)
        order[p] = p
    for p in range(1, ncap):  # insertion sort: the caps are small
        q = order[p]
        r = p - 1
        while r >= 0 and ang[order[r]] > ang[q]:
            order[r + 1] = order[r]
            r -= 1
        order[r + 1] = q
    m = 0
    for p in range(ncap):
        q = order[p]
        if m > 0:
            prev_x, prev_y, prev_z = out[k, m - 1, 0], out[k, m - 1, 1], out[k, m - 1, 2]
            dx, dy, dz = cap[q, 0] - prev_x, cap[q, 1] - prev_y, cap[q, 2] - prev_z
            if dx * dx + dy * dy + dz * dz <= 1e-20:
                continue
        for c in range(3):
            out[k, m, c] = cap[q, c]
        m += 1
    if m >= 2:
        dx = out[k, m - 1, 0] - out[k, 0, 0]
        dy = out[k, m - 1, 1] - out[k, 0, 1]
        dz = out[k, m - 1, 2] - out[k, 0, 2]
        if dx * dx + dy * dy + dz * dz <= 1e-20:
            m -= 1
    if m >= 3:
        out_n[k] = m
        k += 1
    return k


@numba.njit(cache=True)
def _measure(
    fv: FloatArray, fn: IntArray, nf: int, u: FloatArray
) -> tuple[float, float, float, float, float, float]:
    """Volume, area projected along ``u``, longest projected chord and centroid of a polyhedron."""
    vol = 0.0
    proj = 0.0
    gx = 0.0
    gy = 0.0
    gz = 0.0
    # reference point: the first vertex (the frame is already local and scaled)
    ox, oy, oz = fv[0, 0, 0], fv[0, 0, 1], fv[0, 0, 2]
    for f in range(nf):
        ax = 0.0
        ay = 0.0
        az = 0.0
        x0, y0, z0 = fv[f, 0, 0] - ox, fv[f, 0, 1] - oy, fv[f, 0, 2] - oz
        for e in range(1, fn[f] - 1):
            x1, y1, z1 = fv[f, e, 0] - ox, fv[f, e, 1] - oy, fv[f, e, 2] - oz
            x2, y2, z2 = fv[f, e + 1, 0] - ox, fv[f, e + 1, 1] - oy, fv[f, e + 1, 2] - oz
            cx = (y1 - y0) * (z2 - z0) - (z1 - z0) * (y2 - y0)
            cy = (z1 - z0) * (x2 - x0) - (x1 - x0) * (z2 - z0)
            cz = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
            ax += 0.5 * cx
            ay += 0.5 * cy
            az += 0.5 * cz
            # tetrahedron (reference, v0, v1, v2): six times its signed volume
            v6 = x0 * (y1 * z2 - z1 * y2) - y0 * (x1 * z2 - z1 * x2) + z0 * (x1 * y2 - y1 * x2)
            vol += v6
            gx += v6 * (x0 + x1 + x2)
            gy += v6 * (y0 + y1 + y2)
            gz += v6 * (z0 + z1 + z2)
        proj += abs(ax * u[0] + ay * u[1] + az * u[2])
    if vol <= 0.0:
        return 0.0, 0.0, 0.0, ox, oy, oz
    gx = gx / (4.0 * vol) + ox
    gy = gy / (4.0 * vol) + oy
    gz = gz / (4.0 * vol) + oz
    width = 0.0
    for f in range(nf):
        for e in range(fn[f]):
            for g in range(f, nf):
                for h in range(fn[g]):
                    dx = fv[f, e, 0] - fv[g, h, 0]
                    dy = fv[f, e, 1] - fv[g, h, 1]
                    dz = fv[f, e, 2] - fv[g, h, 2]
                    along = dx * u[0] + dy * u[1] + dz * u[2]
                    w2 = dx * dx + dy * dy + dz * dz - along * along
                    if w2 > width:
                        width = w2
    return vol / 6.0, 0.5 * proj, math.sqrt(width), gx, gy, gz


@numba.njit(cache=True)
def contact_regions(
    pi: IntArray,
    pj: IntArray,
    grow: float,
    normal: FloatArray,
    centre: FloatArray,
    vertices: FloatArray,
    offsets: IntArray,
    normals: FloatArray,
    support: FloatArray,
    face_offsets: IntArray,
    size: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Measure the intersection of every pair of solids grown by ``grow``.

    Returns
    -------
    volume, area, width, point
        Volume of the intersection, its area projected on the plane normal
        to ``normal`` (the pair's contact normal), the longest chord of that
        projection, and its centroid ``(n, 3)``.
    """
    n = pi.shape[0]
    volume = np.zeros(n)
    area = np.zeros(n)
    width = np.zeros(n)
    point = np.full((n, 3), np.nan)
    nfmax = 0
    for p in range(n):
        i, j = pi[p], pj[p]
        m = face_offsets[i + 1] - face_offsets[i] + face_offsets[j + 1] - face_offsets[j]
        nfmax = max(nfmax, m + 6)
    fv = np.zeros((nfmax, nfmax + 2, 3))
    fv2 = np.zeros((nfmax, nfmax + 2, 3))
    fn = np.zeros(nfmax, dtype=np.int64)
    fn2 = np.zeros(nfmax, dtype=np.int64)
    cap = np.zeros(((nfmax + 2) * nfmax, 3))
    origin = np.empty(3)
    lo = np.empty(3)
    hi = np.empty(3)
    u = np.empty(3)
    plane = np.empty(3)
    for p in range(n):
        i, j = pi[p], pj[p]
        for a in range(3):
            origin[a] = 0.5 * (centre[i, a] + centre[j, a])
            u[a] = normal[p, a]
        scale = 2.0 ** math.ceil(math.log2(size[i] + size[j]))  # exact divisions
        g = grow / scale
        # a box that holds both grown solids' intersection: the intersection of their bounding
        # boxes, each solid grown about its centre by (1 + grow / smallest support)
        for a in range(3):
            lo[a] = -np.inf
            hi[a] = np.inf
        for q in (i, j):
            smin = np.inf
            for f in range(face_offsets[q], face_offsets[q + 1]):
                smin = min(smin, support[f])
            stretch = (1.0 + grow / smin) * (1.0 + 1e-9)
            for a in range(3):
                vlo = np.inf
                vhi = -np.inf
                for v in range(offsets[q], offsets[q + 1]):
                    vlo = min(vlo, vertices[v, a])
                    vhi = max(vhi, vertices[v, a])
                c = (centre[q, a] - origin[a]) / scale
                lo[a] = max(lo[a], c + stretch * vlo / scale)
                hi[a] = min(hi[a], c + stretch * vhi / scale)
        if not (lo[0] < hi[0] and lo[1] < hi[1] and lo[2] < hi[2]):
            continue
        # the box as six quadrilaterals, counter-clockwise seen from outside
        nf = int(np.int64(6))  # not a literal 6 (a second compilation of _clip)
        corners = (
            (0, 1, 3, 2),
            (4, 6, 7, 5),
            (0, 4, 5, 1),
            (2, 3, 7, 6),
            (0, 2, 6, 4),
            (1, 5, 7, 3),
        )
        for f in range(6):
            for e in range(4):
                c = corners[f][e]
                fv[f, e, 0] = hi[0] if c & 4 else lo[0]
                fv[f, e, 1] = hi[1] if c & 2 else lo[1]
                fv[f, e, 2] = hi[2] if c & 1 else lo[2]
            fn[f] = 4
        planes, offs, _ = _planes(i, j, origin, scale, g, centre, normals, support, face_offsets)
        cur = 0
        for k in range(planes.shape[0]):
            for a in range(3):
                plane[a] = planes[k, a]
            if cur == 0:
                nf = _clip(fv, fn, nf, fv2, fn2, cap, plane, offs[k])
            else:
                nf = _clip(fv2, fn2, nf, fv, fn, cap, plane, offs[k])
            cur = 1 - cur
            if nf < 4:
                break
        if nf < 4:
            continue
        if cur == 0:
            vol, proj, wid, gx, gy, gz = _measure(fv, fn, nf, u)
        else:
            vol, proj, wid, gx, gy, gz = _measure(fv2, fn2, nf, u)
        volume[p] = vol * scale**3
        area[p] = proj * scale**2
        width[p] = wid * scale
        point[p, 0] = origin[0] + gx * scale
        point[p, 1] = origin[1] + gy * scale
        point[p, 2] = origin[2] + gz * scale
    return volume, area, width, point
