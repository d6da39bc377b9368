"""Compiled Minkowski envelope ``E = P ⊕ (-Q)`` of two convex polyhedra.

``E`` is the set of centres of ``Q`` (relative to ``P``'s reference point)
at which ``Q`` meets ``P``; its boundary is where they touch.

Method
------
The facets of ``E`` are the vertices of the overlay of the Gauss maps of
``P`` and ``-Q`` on the unit sphere: the face normals of ``P``, those of
``-Q``, and the points where an edge arc of one map crosses an edge arc of
the other. An edge of ``P`` with unit direction ``t`` (as it runs
counter-clockwise in its left face ``f``, its twin face being ``g``) maps to
the great-circle arc from ``n_f`` to ``n_g``; a direction ``d`` perpendicular to
``t`` lies on the arc when ``d · (t × n_f) >= 0`` and ``d · (n_g × t) >= 0``. An
edge ``t`` of ``P`` and an edge ``s`` of ``-Q`` can only give a facet with normal
``± t × s``; a pair is tested only when the ends of each arc are not
strictly on one side of the other's great circle (two tables of signs: the
faces of ``-Q`` against the edges of ``P``, and the reverse).

Every candidate direction ``n`` is then checked the same way: the support
sets ``F_P(n)`` and ``F_{-Q}(n)`` (vertices within the tolerance of the
maximum of ``n · x``, always including the face or the edges the candidate
comes from) are summed pairwise and the 2D convex hull of the sums in the
plane normal to ``n`` is the face polygon ``F_P(n) ⊕ F_{-Q}(n)``. The candidate
is a facet when that hull has at least 3 corners; a candidate whose corners
are those of a facet already found (parallel faces of ``P`` and ``-Q``, or a
crossing at an arc's end) is dropped, so each facet appears once, with the
normal of the first candidate (faces of ``P``, then of ``-Q``, then edge
pairs). The support value is ``h_P(n) + h_Q(-n)``.

Every vertex of ``E`` is a sum ``p_i - q_j`` and is identified by the pair
``(i, j)``, so the faces share their corners exactly and the output is a
closed polyhedral surface (``V - E + F = 2``) whenever the decisions above
are consistent.

Tolerance
---------
One length, ``tau = ENVELOPE_EPS * (R_P + R_Q)`` with ``R`` the circumradii
about the reference points, decides support-set ties and whether a hull
point is a corner (its distance to the line through its neighbours); arc
tests on unit vectors use :data:`ANGLE_EPS`. Features of ``P`` or ``Q``
smaller than ``tau`` (faces within ``tau`` of coplanar, edges within
``tau / length`` of parallel) are merged, so the result is exact up to
``tau`` for any absolute scale and for size ratios well above ``1e3``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.inserters.available_surface.polygon import convex_hull_2d, plane_frame
from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

ENVELOPE_EPS = 1e-10
"""Length tolerance of the envelope, relative to ``R_P + R_Q``."""
ANGLE_EPS = 1e-12
"""Tolerance of the arc tests (dot products of unit vectors)."""
PARALLEL_EPS = 1e-14
"""Edge pairs with ``|t × s|`` below this are parallel and give no facet."""
HASH_MULT = -7046029254386353131  # 0x9E3779B97F4A7C15 as a signed 64-bit integer


class Candidates(NamedTuple):
    """The candidate directions of the facets of ``E`` (see :func:`_build_faces`)."""

    cand: FloatArray
    """``(nc, 3)`` unit directions."""
    kind: IntArray
    """0: a face of ``P``, 1: a face of ``-Q``, 2: an edge pair."""
    ca: IntArray
    """The face, or the edge of ``P`` (of the edges ``pa -> pb``)."""
    cb: IntArray
    """The edge of ``-Q`` of an edge pair (of the edges ``qa -> qb``)."""
    dp: FloatArray
    """``(nc, kp)``: ``n · p_i``."""
    dq: FloatArray
    """``(nc, kq)``: ``n · q_j``."""
    pa: IntArray
    pb: IntArray
    qa: IntArray
    qb: IntArray


class FaceTable(NamedTuple):
    """The faces found so far: normal, support, loop of vertex keys, and a hash table of them."""

    normals: FloatArray
    support: FloatArray
    offsets: IntArray
    fhash: IntArray
    table: IntArray
    keys: IntArray


class FaceScratch(NamedTuple):
    """Scratch of a face: the support sets, their projections, their sums and hull."""

    sets: IntArray
    plane: FloatArray
    sums: FloatArray
    hull: IntArray


class EdgeArcs(NamedTuple):
    """The edges of a polyhedron (``P``, or ``-Q``) as arcs of its Gauss map."""

    left: IntArray
    right: IntArray
    t: FloatArray
    u: FloatArray


@numba.njit(cache=True)
def polyhedron_edges(
    face_vertices: IntArray, face_offsets: IntArray, n_vertices: int
) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """Return the edges of a closed polyhedral surface.

    Returns
    -------
    a, b
        End vertices, ``a < b``: the edge runs ``a -> b`` in its left face's loop.
    left, right
        The face whose loop runs ``a -> b``, and its twin (``b -> a``).

    Raises
    ------
    ValueError
        If an edge is not shared by exactly two faces in opposite directions.
    """
    total = face_vertices.shape[0]
    nf = face_offsets.shape[0] - 1
    # directed edges a -> b grouped by a (compressed rows)
    start = np.zeros(n_vertices + 1, dtype=np.int64)
    for k in range(total):
        start[face_vertices[k] + 1] += 1
    for v in range(n_vertices):
        start[v + 1] += start[v]
    fill = start[:n_vertices].copy()
    dst = np.empty(total, dtype=np.int64)
    face = np.empty(total, dtype=np.int64)
    for f in range(nf):
        s = face_offsets[f]
        m = face_offsets[f + 1] - s
        for i in range(m):
            a = face_vertices[s + i]
            b = face_vertices[s + i + 1] if i + 1 < m else face_vertices[s]
            dst[fill[a]] = b
            face[fill[a]] = f
            fill[a] += 1
    if total % 2 != 0:
        raise ValueError("the faces do not form a closed surface")
    ne = total // 2
    ea = np.empty(ne, dtype=np.int64)
    eb = np.empty(ne, dtype=np.int64)
    left = np.empty(ne, dtype=np.int64)
    right = np.empty(ne, dtype=np.int64)
    e = 0
    for a in range(n_vertices):
        for k in range(start[a], start[a + 1]):
            b = dst[k]
            twin = -1
            for k2 in range(start[b], start[b + 1]):
                if dst[k2] == a:
                    if twin >= 0:
                        raise ValueError("an edge is shared by more than two faces")
                    twin = k2
            if twin < 0:
                raise ValueError("an edge is not shared by two faces in opposite directions")
            if a < b:
                if e >= ne:
                    raise ValueError("an edge is shared by more than two faces")
                ea[e] = a
                eb[e] = b
                left[e] = face[k]
                right[e] = face[twin]
                e += 1
    if e != ne:
        raise ValueError("an edge is not shared by exactly two faces")
    return ea, eb, left, right


@numba.njit(cache=True)
def _edge_arcs(
    vertices: FloatArray,
    normals: FloatArray,
    sign: float,
    ea: IntArray,
    eb: IntArray,
    left: IntArray,
    right: IntArray,
) -> tuple[FloatArray, FloatArray]:
    """Per edge, the unit direction ``t`` and the arc bounds ``t × n_f``, ``n_g × t``.

    ``sign = -1`` describes the reflected polyhedron (its normals negated;
    its edge directions, taken from the loops reversed, are unchanged).
    Returns ``t`` ``(ne, 3)`` and the two bounds side by side ``(ne, 6)``.
    """
    ne = ea.shape[0]
    t = np.empty((ne, 3))
    u = np.empty((ne, 6))
    for e in range(ne):
        tx = vertices[eb[e], 0] - vertices[ea[e], 0]
        ty = vertices[eb[e], 1] - vertices[ea[e], 1]
        tz = vertices[eb[e], 2] - vertices[ea[e], 2]
        inv = 1.0 / math.sqrt(tx * tx + ty * ty + tz * tz)
        tx *= inv
        ty *= inv
        tz *= inv
        fx = sign * normals[left[e], 0]
        fy = sign * normals[left[e], 1]
        fz = sign * normals[left[e], 2]
        gx = sign * normals[right[e], 0]
        gy = sign * normals[right[e], 1]
        gz = sign * normals[right[e], 2]
        t[e, 0] = tx
        t[e, 1] = ty
        t[e, 2] = tz
        u[e, 0] = ty * fz - tz * fy
        u[e, 1] = tz * fx - tx * fz
        u[e, 2] = tx * fy - ty * fx
        u[e, 3] = gy * tz - gz * ty
        u[e, 4] = gz * tx - gx * tz
        u[e, 5] = gx * ty - gy * tx
    return t, u


@numba.njit(cache=True)
def edge_arcs(p: Polyhedron, sign: float) -> EdgeArcs:
    """Edge arcs of ``P`` (``sign = 1``) or of ``-P`` (``sign = -1``), to reuse across pairs."""
    a, b, left, right = polyhedron_edges(p.face_vertices, p.face_offsets, p.vertices.shape[0])
    t, u = _edge_arcs(p.vertices, p.normals, sign, a, b, left, right)
    return EdgeArcs(left, right, t, u)


@numba.njit(cache=True)
def dots3(a: FloatArray, b: FloatArray) -> FloatArray:
    """Return ``a @ b.T`` for rows of three coordinates, summed in a plain loop.

    Not ``np.dot``: the BLAS it calls costs more than the sum for such small
    matrices, its threads wait spinning on a core after each call, and its
    rounding depends on the CPU's kernel.
    """
    out = np.empty((a.shape[0], b.shape[0]))
    for i in range(a.shape[0]):
        x, y, z = a[i, 0], a[i, 1], a[i, 2]
        for j in range(b.shape[0]):
            out[i, j] = x * b[j, 0] + y * b[j, 1] + z * b[j, 2]
    return out


@numba.njit(cache=True)
def _sides(t: FloatArray, normals: FloatArray, sign: float) -> NDArray[np.int8]:
    """Side (``-1, 0, +1``, within :data:`ANGLE_EPS`) of each ``sign * normal`` for each ``t``."""
    dots = dots3(t, normals)
    out = np.empty(dots.shape, dtype=np.int8)
    for e in range(dots.shape[0]):
        for g in range(dots.shape[1]):
            v = sign * dots[e, g]
            out[e, g] = 1 if v > ANGLE_EPS else (-1 if v < -ANGLE_EPS else 0)
    return out


@numba.njit(cache=True)
def _build_faces(
    first: int,
    nfaces: int,
    cands: Candidates,
    p: Polyhedron,
    q: Polyhedron,
    tau: float,
    faces: FaceTable,
    scratch: FaceScratch,
) -> tuple[int, int, int, int]:
    """Turn the candidate directions from ``first`` on into faces.

    For candidate ``c``: the support sets of ``P`` and ``-Q`` in direction
    ``n`` (``dp[c] = n · p_i``, ``dq[c] = n · q_j``; the vertices within ``tau`` of
    the maximum, plus the face or edges the candidate comes from), the face
    polygon (the 2D hull of their pairwise sums, or a face's own loop when the
    other support set is one vertex), then the face unless it has fewer than 3
    corners or repeats a face already found (same corners). Faces are
    appended to ``faces`` (``normals, support, offsets, keys`` and the hash ``table``).

    Returns
    -------
    nfaces, next_candidate
        Faces so far and the candidate to go on with (``len(cand)``: done).
    need_keys, need_sums
        Nonzero when ``keys`` or ``sums``/``hull`` are too small (the size needed).
    """
    cand, kind, ca, cb, dp, dq, pa, pb, qa, qb = cands
    normals, support, offsets, fhash, table, keys = faces
    sets, plane, sums, hull = scratch
    vp = p.vertices
    vq = q.vertices
    kp = vp.shape[0]
    kq = vq.shape[0]
    nc = cand.shape[0]
    table_size = table.shape[0]
    for c in range(first, nc):
        nx = cand[c, 0]
        ny = cand[c, 1]
        nz = cand[c, 2]
        # support sets: the vertices within tau of the maximum, and the candidate's own
        hp = -np.inf
        for i in range(kp):
            hp = max(hp, dp[c, i])
        hq = -np.inf
        for j in range(kq):
            hq = max(hq, -dq[c, j])
        np_ = 0
        for i in range(kp):
            if dp[c, i] >= hp - tau:
                sets[np_] = i
                np_ += 1
        nq_ = 0
        for j in range(kq):
            if -dq[c, j] >= hq - tau:
                sets[kp + nq_] = j
                nq_ += 1
        # the members the candidate comes from (almost always within tau already)
        if kind[c] == 0:
            for k in range(p.face_offsets[ca[c]], p.face_offsets[ca[c] + 1]):
                v = p.face_vertices[k]
                if dp[c, v] < hp - tau:
                    sets[np_] = v
                    np_ += 1
        elif kind[c] == 1:
            for k in range(q.face_offsets[ca[c]], q.face_offsets[ca[c] + 1]):
                v = q.face_vertices[k]
                if -dq[c, v] < hq - tau:
                    sets[kp + nq_] = v
                    nq_ += 1
        else:
            for v in (pa[ca[c]], pb[ca[c]]):
                if dp[c, v] < hp - tau:
                    sets[np_] = v
                    np_ += 1
            for v in (qa[cb[c]], qb[cb[c]]):
                if -dq[c, v] < hq - tau:
                    sets[kp + nq_] = v
                    nq_ += 1
        if np_ * nq_ < 3:
            continue
        start = offsets[nfaces]
        if start + np_ + nq_ > keys.shape[0]:
            return nfaces, c, start + np_ + nq_, 0
        fsize = p.face_offsets[ca[c] + 1] - p.face_offsets[ca[c]] if kind[c] == 0 else 0
        gsize = q.face_offsets[ca[c] + 1] - q.face_offsets[ca[c]] if kind[c] == 1 else 0
        if kind[c] == 0 and nq_ == 1 and np_ == fsize:
            # a face of P plus a vertex of -Q: the face's loop
            corners = np_
            f0 = p.face_offsets[ca[c]]
            for k in range(corners):
                keys[start + k] = p.face_vertices[f0 + k] * kq + sets[kp]
        elif kind[c] == 1 and np_ == 1 and nq_ == gsize:
            # a vertex of P plus a face of -Q: the face's loop, reversed
            corners = nq_
            g1 = q.face_offsets[ca[c] + 1] - 1
            for k in range(corners):
                keys[start + k] = sets[0] * kq + q.face_vertices[g1 - k]
        else:
            # the 2D convex hull of the pairwise sums in the face's plane
            m = np_ * nq_
            if m > sums.shape[1] or 2 * m + 1 > hull.shape[0]:
                return nfaces, c, 0, m
            e1x, e1y, e1z, e2x, e2y, e2z = plane_frame(nx, ny, nz)
            for a in range(np_):
                i = sets[a]
                plane[0, a] = e1x * vp[i, 0] + e1y * vp[i, 1] + e1z * vp[i, 2]
                plane[1, a] = e2x * vp[i, 0] + e2y * vp[i, 1] + e2z * vp[i, 2]
            for b in range(nq_):
                j = sets[kp + b]
                plane[2, b] = -(e1x * vq[j, 0] + e1y * vq[j, 1] + e1z * vq[j, 2])
                plane[3, b] = -(e2x * vq[j, 0] + e2y * vq[j, 1] + e2z * vq[j, 2])
            for a in range(np_):
                for b in range(nq_):
                    sums[0, a * nq_ + b] = plane[0, a] + plane[2, b]
                    sums[1, a * nq_ + b] = plane[1, a] + plane[3, b]
            corners = convex_hull_2d(sums[0], sums[1], m, tau, hull)
            if corners < 3:
                continue
            for k in range(corners):
                keys[start + k] = sets[hull[k] // nq_] * kq + sets[kp + hull[k] % nq_]
        # the face's key set: an order-free hash, then an exact comparison
        h = 0
        for k in range(corners):
            x = keys[start + k] * HASH_MULT
            h += x ^ (x >> 29)
        slot = h & (table_size - 1)
        duplicate = False
        while table[slot] >= 0:
            other = table[slot]
            if fhash[other] == h and offsets[other + 1] - offsets[other] == corners:
                duplicate = True
                for k in range(corners):
                    found = False
                    for k2 in range(offsets[other], offsets[other + 1]):
                        if keys[k2] == keys[start + k]:
                            found = True
                            break
                    if not found:
                        duplicate = False
                        break
                if duplicate:
                    break
            slot = (slot + 1) & (table_size - 1)
        if duplicate:
            continue
        table[slot] = nfaces
        fhash[nfaces] = h
        normals[nfaces, 0] = nx
        normals[nfaces, 1] = ny
        normals[nfaces, 2] = nz
        support[nfaces] = hp + hq
        offsets[nfaces + 1] = start + corners
        nfaces += 1
    return nfaces, nc, 0, 0


@numba.njit(cache=True)
def edge_pair_directions(
    tp: FloatArray,
    up: FloatArray,
    pl: IntArray,
    pr: IntArray,
    tq: FloatArray,
    uq: FloatArray,
    ql: IntArray,
    qr: IntArray,
    side_p: NDArray[np.int8],
    side_q: NDArray[np.int8],
    cand: FloatArray,
    kind: IntArray,
    ca: IntArray,
    cb: IntArray,
    nc: int,
) -> int:
    """Append the directions where an edge arc of ``P`` crosses one of ``-Q``.

    Each crossing goes to ``cand[nc]`` (unit normal ``± t × s``) with
    ``kind = 2`` and the two edges in ``ca``, ``cb``; returns the new count.
    For each edge of ``P`` the edges of ``-Q`` that pass both sign tables are
    first listed without branches (most pairs fail one, at random), then
    tested in ascending order.
    """
    nep = tp.shape[0]
    neq = tq.shape[0]
    near = np.empty(neq, dtype=np.int64)
    for e in range(nep):
        m = 0
        for e2 in range(neq):
            near[m] = e2
            m += 1 if side_p[e, ql[e2]] * side_p[e, qr[e2]] <= 0 else 0
        left = pl[e]
        right = pr[e]
        kept = 0
        for c in range(m):
            e2 = near[c]
            near[kept] = e2
            kept += 1 if side_q[e2, left] * side_q[e2, right] <= 0 else 0
        tx = tp[e, 0]
        ty = tp[e, 1]
        tz = tp[e, 2]
        for c in range(kept):
            e2 = near[c]
            sx = tq[e2, 0]
            sy = tq[e2, 1]
            sz = tq[e2, 2]
            dx = ty * sz - tz * sy
            dy = tz * sx - tx * sz
            dz = tx * sy - ty * sx
            dn = math.sqrt(dx * dx + dy * dy + dz * dz)
            if dn < PARALLEL_EPS:
                continue
            dx /= dn
            dy /= dn
            dz /= dn
            a1 = dx * up[e, 0] + dy * up[e, 1] + dz * up[e, 2]
            a2 = dx * up[e, 3] + dy * up[e, 4] + dz * up[e, 5]
            b1 = dx * uq[e2, 0] + dy * uq[e2, 1] + dz * uq[e2, 2]
            b2 = dx * uq[e2, 3] + dy * uq[e2, 4] + dz * uq[e2, 5]
            lo = min(min(a1, a2), min(b1, b2))
            hi = max(max(a1, a2), max(b1, b2))
            if lo >= -ANGLE_EPS:
                sgn = 1.0
            elif hi <= ANGLE_EPS:
                sgn = -1.0
            else:
                continue
            cand[nc, 0] = sgn * dx
            cand[nc, 1] = sgn * dy
            cand[nc, 2] = sgn * dz
            kind[nc] = 2
            ca[nc] = e
            cb[nc] = e2
            nc += 1
    return nc


@numba.njit(cache=True)
def candidate_directions(
    p: Polyhedron, ep: EdgeArcs, q: Polyhedron, eq: EdgeArcs
) -> tuple[FloatArray, IntArray, IntArray, IntArray, int]:
    """Directions in which ``P ⊕ (-Q)`` may have a facet, from the edge arcs of ``P`` and ``-Q``.

    The face normals of ``P`` (``kind`` 0, the face in ``ca``), those of
    ``-Q`` (``kind`` 1), then the crossings of their edge arcs
    (:func:`edge_pair_directions`, ``kind`` 2). Returns ``(cand, kind, ca, cb,
    nc)``, the directions in the first ``nc`` rows of ``cand``.
    """
    pl, pr, tp, up = ep
    ql, qr, tq, uq = eq
    fp = p.normals.shape[0]
    fq = q.normals.shape[0]
    cap = fp + fq + pl.shape[0] * ql.shape[0]
    cand = np.empty((cap, 3))
    kind = np.empty(cap, dtype=np.int64)
    ca = np.empty(cap, dtype=np.int64)
    cb = np.empty(cap, dtype=np.int64)
    # counters start as int(np.int64(0)), not 0: numba would type a literal 0 and compile
    # a second specialization of the kernels they are passed to
    nc = int(np.int64(0))
    for f in range(fp):
        cand[nc, 0] = p.normals[f, 0]
        cand[nc, 1] = p.normals[f, 1]
        cand[nc, 2] = p.normals[f, 2]
        kind[nc] = 0
        ca[nc] = f
        nc += 1
    for g in range(fq):
        cand[nc, 0] = -q.normals[g, 0]
        cand[nc, 1] = -q.normals[g, 1]
        cand[nc, 2] = -q.normals[g, 2]
        kind[nc] = 1
        ca[nc] = g
        nc += 1
    # two arcs can only cross if each one's ends are not strictly on one side of
    # the other's great circle
    side_p = _sides(tp, q.normals, -1.0)  # faces of -Q against the edges of P
    side_q = _sides(tq, p.normals, 1.0)  # faces of P against the edges of -Q
    nc = edge_pair_directions(
        tp, up, pl, pr, tq, uq, ql, qr, side_p, side_q, cand, kind, ca, cb, nc
    )
    return cand, kind, ca, cb, nc


@numba.njit(cache=True)
def minkowski_envelope(p: Polyhedron, q: Polyhedron) -> Polyhedron:
    """Return the envelope ``E = P ⊕ (-Q)`` as a :class:`Polyhedron`.

    Parameters
    ----------
    p, q
        Convex polyhedra relative to their reference points.

    Returns
    -------
    Polyhedron
        ``E`` relative to ``P``'s reference point: ``Q``'s reference point at
        ``x`` makes ``Q`` touch ``P`` exactly when ``x`` is on ``E``'s boundary.
        Vertices are sums ``p_i - q_j``; see the module docstring for the
        method and the tolerance.
    """
    vp = p.vertices
    vq = q.vertices
    kp = vp.shape[0]
    kq = vq.shape[0]
    rp = 0.0
    for i in range(kp):
        rp = max(rp, math.sqrt(vp[i, 0] ** 2 + vp[i, 1] ** 2 + vp[i, 2] ** 2))
    rq = 0.0
    for j in range(kq):
        rq = max(rq, math.sqrt(vq[j, 0] ** 2 + vq[j, 1] ** 2 + vq[j, 2] ** 2))
    tau = ENVELOPE_EPS * (rp + rq)

    pa, pb, pl, pr = polyhedron_edges(p.face_vertices, p.face_offsets, kp)
    qa, qb, ql, qr = polyhedron_edges(q.face_vertices, q.face_offsets, kq)
    tp, up = _edge_arcs(vp, p.normals, 1.0, pa, pb, pl, pr)
    tq, uq = _edge_arcs(vq, q.normals, -1.0, qa, qb, ql, qr)
    cand, kind, ca, cb, nc = candidate_directions(
        p, EdgeArcs(pl, pr, tp, up), q, EdgeArcs(ql, qr, tq, uq)
    )

    # support values of P and -Q in every candidate direction
    dp = dots3(cand[:nc], vp)
    dq = dots3(cand[:nc], vq)

    # faces: normal, support, loop of vertex keys i * kq + j
    normals = np.empty((nc, 3))
    support = np.empty(nc)
    offsets = np.zeros(nc + 1, dtype=np.int64)
    fhash = np.empty(nc, dtype=np.int64)
    table_size = 16
    while table_size < 2 * nc:
        table_size *= 2
    table = np.full(table_size, -1, dtype=np.int64)
    keys = np.empty(4 * nc + 8, dtype=np.int64)
    sets = np.empty(kp + kq, dtype=np.int64)  # support sets of P, then of -Q
    plane = np.empty((4, kp + kq))  # their projections on a face's plane
    sums = np.empty((2, 64))  # pairwise sums of the projections
    hull = np.empty(129, dtype=np.int64)
    nfaces = int(np.int64(0))
    c = int(np.int64(0))
    cands = Candidates(cand[:nc], kind, ca, cb, dp, dq, pa, pb, qa, qb)
    while c < nc:
        nfaces, c, need_keys, need_sums = _build_faces(
            c, nfaces, cands, p, q, tau,
            FaceTable(normals, support, offsets, fhash, table, keys),
            FaceScratch(sets, plane, sums, hull),
        )  # fmt: skip
        if need_keys > 0:
            grown = np.empty(max(need_keys, 2 * keys.shape[0]), dtype=np.int64)
            grown[: keys.shape[0]] = keys
            keys = grown
        if need_sums > 0:
            sums = np.empty((2, 2 * need_sums))
            hull = np.empty(4 * need_sums + 1, dtype=np.int64)

    # number the vertices in order of first use
    total = offsets[nfaces]
    index = np.full(kp * kq, -1, dtype=np.int64)
    face_vertices = np.empty(total, dtype=np.int64)
    nv = 0
    for k in range(total):
        key = keys[k]
        if index[key] < 0:
            index[key] = nv
            nv += 1
        face_vertices[k] = index[key]
    vertices = np.empty((nv, 3))
    for k in range(total):
        key = keys[k]
        v = index[key]
        i = key // kq
        j = key % kq
        vertices[v, 0] = vp[i, 0] - vq[j, 0]
        vertices[v, 1] = vp[i, 1] - vq[j, 1]
        vertices[v, 2] = vp[i, 2] - vq[j, 2]
    return Polyhedron(
        vertices,
        normals[:nfaces].copy(),
        support[:nfaces].copy(),
        face_vertices,
        offsets[: nfaces + 1].copy(),
    )
