"""Compiled vertex enumeration of the polyhedra ``{x : n_k . x <= s_k}`` of a direction set.

Every vertex of such a polyhedron is the meeting point of three planes whose
normals are linearly independent. The direction set is shared by the whole
batch, so the inverse of the ``3 x 3`` matrix of every independent triple of
normals is computed once (:func:`direction_triples`); for each particle a
triple's meeting point is then one matrix-vector product, kept when it
satisfies every inequality. Points closer than a relative tolerance are merged
into one vertex, which keeps the union of the planes through them, so a vertex
where more than three planes meet is found once and knows all its planes.

The face of direction ``k`` is the set of vertices on plane ``k``; it is a
proper face (positive area) when it has at least three vertices. The cost per
particle is ``O(C(m, 3) m)``, a few microseconds for the 14 directions of the
truncated octahedron; it grows as ``m⁴`` and suits small sets (``m ≲ 30``).
"""

from __future__ import annotations

import itertools
import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

DET_MIN = 1e-9
"""Triples of unit normals whose determinant is at most this are treated as dependent."""
FEAS = 1e-11
"""A meeting point satisfies inequality ``l`` when ``n_l . v <= s_l + FEAS L κ``, with
``L = max |s_k|`` and ``κ`` the infinity norm of the triple's inverse matrix."""
MERGE = 1e-10
"""Vertices closer than ``MERGE L`` in every coordinate are merged (``L = max |s_k|``)."""
VOLUME_MIN = 1e-24
"""A polyhedron whose volume is at most ``VOLUME_MIN L³`` is flat or empty."""

OK = 0
OVERFLOW = 1
NOT_CLOSED = 2
NO_VOLUME = 3


class Triples(NamedTuple):
    """The independent triples of a direction set and their inverse matrices."""

    members: IntArray
    """``(T, 3)`` direction indices ``i < j < k``."""
    inverse: FloatArray
    """``(T, 3, 3)`` inverse of the matrix whose rows are ``n_i, n_j, n_k``."""
    kappa: FloatArray
    """``(T,)`` infinity norm of each inverse (how much rounding it amplifies)."""


def direction_triples(d: FloatArray) -> Triples:
    """Independent triples of the directions ``d`` and their inverse matrices.

    Parameters
    ----------
    d
        ``(m, 3)`` unit directions.

    Returns
    -------
    Triples
        Every triple ``i < j < k`` whose normals have ``|det| > DET_MIN``, in
        lexicographic order.
    """
    m = d.shape[0]
    combos = np.array(list(itertools.combinations(range(m), 3)), dtype=np.int64).reshape(-1, 3)
    mats = d[combos]
    keep = np.abs(np.linalg.det(mats)) > DET_MIN
    inverse = np.ascontiguousarray(np.linalg.inv(mats[keep]))
    kappa = np.abs(inverse).sum(axis=2).max(axis=1)
    return Triples(np.ascontiguousarray(combos[keep]), inverse, np.ascontiguousarray(kappa))


def face_bases(d: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Two unit vectors ``u, w`` in the plane of each direction with ``u × w = n``.

    Angles measured from ``u`` towards ``w`` increase counter-clockwise as seen
    from the tip of ``n`` (from outside the face).

    Parameters
    ----------
    d
        ``(m, 3)`` unit directions.

    Returns
    -------
    u, w
        ``(m, 3)`` each.
    """
    axis = np.zeros_like(d)
    axis[np.arange(d.shape[0]), np.argmin(np.abs(d), axis=1)] = 1.0
    u = np.cross(d, axis)
    u /= np.linalg.norm(u, axis=1)[:, None]
    w = np.cross(d, u)
    return np.ascontiguousarray(u), np.ascontiguousarray(w)


class Enumerated(NamedTuple):
    """Polyhedra in padded per-particle arrays (what :func:`enumerate_polyhedra` returns)."""

    nvert: IntArray
    """``(n,)`` vertex count."""
    verts: FloatArray
    """``(n, vcap, 3)`` vertices, the first ``nvert[p]`` rows valid."""
    nface: IntArray
    """``(n,)`` proper face count."""
    fdir: IntArray
    """``(n, m)`` direction of each proper face, ascending; the first ``nface[p]`` valid."""
    fsize: IntArray
    """``(n, m)`` vertex count of each proper face."""
    fverts: IntArray
    """``(n, fcap)`` vertex indices of the faces one after another, each counter-clockwise."""
    support: FloatArray
    """``(n, m)`` true support value ``max_v n_k . v`` along every direction."""
    volume: FloatArray
    """``(n,)`` volume."""
    centroid: FloatArray
    """``(n, 3)`` volume centroid."""
    status: IntArray
    """``(n,)`` ``OK``, or why the particle failed."""


@numba.njit(cache=True)
def enumerate_polyhedra(
    s: FloatArray,
    d: FloatArray,
    tri: IntArray,
    inv: FloatArray,
    kappa: FloatArray,
    u: FloatArray,
    w: FloatArray,
    vcap: int,
    fcap: int,
) -> tuple[
    IntArray,
    FloatArray,
    IntArray,
    IntArray,
    IntArray,
    IntArray,
    FloatArray,
    FloatArray,
    FloatArray,
    IntArray,
]:
    """Vertices, faces, true supports, volume and centroid of ``{x : d_k . x <= s[p, k]}``.

    See :class:`Enumerated` for the outputs, in that order. ``vcap`` and
    ``fcap`` bound the vertices and the face-vertex entries of one particle.
    """
    n, m = s.shape
    nt = tri.shape[0]
    nvert = np.zeros(n, np.int64)
    verts = np.zeros((n, vcap, 3))
    nface = np.zeros(n, np.int64)
    fdir = np.full((n, m), -1, np.int64)
    fsize = np.zeros((n, m), np.int64)
    fverts = np.zeros((n, fcap), np.int64)
    support = np.zeros((n, m))
    volume = np.zeros(n)
    centroid = np.zeros((n, 3))
    status = np.zeros(n, np.int64)
    inc = np.zeros((vcap, m), np.bool_)
    members = np.empty(vcap, np.int64)
    angle = np.empty(vcap)
    for p in range(n):
        scale = 0.0
        for k in range(m):
            scale = max(scale, abs(s[p, k]))
        merge = MERGE * scale
        nv = 0
        inc[:, :] = False
        for t in range(nt):
            i, j, k = tri[t, 0], tri[t, 1], tri[t, 2]
            si, sj, sk = s[p, i], s[p, j], s[p, k]
            x = inv[t, 0, 0] * si + inv[t, 0, 1] * sj + inv[t, 0, 2] * sk
            y = inv[t, 1, 0] * si + inv[t, 1, 1] * sj + inv[t, 1, 2] * sk
            z = inv[t, 2, 0] * si + inv[t, 2, 1] * sj + inv[t, 2, 2] * sk
            tol = FEAS * scale * kappa[t]
            feasible = True
            for q in range(m):
                if d[q, 0] * x + d[q, 1] * y + d[q, 2] * z > s[p, q] + tol:
                    feasible = False
                    break
            if not feasible:
                continue
            found = -1
            for q in range(nv):
                if (
                    abs(verts[p, q, 0] - x) <= merge
                    and abs(verts[p, q, 1] - y) <= merge
                    and abs(verts[p, q, 2] - z) <= merge
                ):
                    found = q
                    break
            if found < 0:
                if nv == vcap:
                    status[p] = OVERFLOW
                    break
                found = nv
                verts[p, nv, 0] = x
                verts[p, nv, 1] = y
                verts[p, nv, 2] = z
                nv += 1
            inc[found, i] = True
            inc[found, j] = True
            inc[found, k] = True
        nvert[p] = nv
        if status[p] != OK:
            continue
        for k in range(m):
            best = -np.inf
            for q in range(nv):
                dot = d[k, 0] * verts[p, q, 0] + d[k, 1] * verts[p, q, 1] + d[k, 2] * verts[p, q, 2]
                best = max(best, dot)
            support[p, k] = best
        nf = 0
        pos = 0
        vol6 = 0.0
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for k in range(m):
            cnt = 0
            mx = 0.0
            my = 0.0
            mz = 0.0
            for q in range(nv):
                if inc[q, k]:
                    members[cnt] = q
                    cnt += 1
                    mx += verts[p, q, 0]
                    my += verts[p, q, 1]
                    mz += verts[p, q, 2]
            if cnt < 3:
                continue
            if pos + cnt > fcap:
                status[p] = OVERFLOW
                break
            mx /= cnt
            my /= cnt
            mz /= cnt
            for c in range(cnt):
                q = members[c]
                ex = verts[p, q, 0] - mx
                ey = verts[p, q, 1] - my
                ez = verts[p, q, 2] - mz
                angle[c] = math.atan2(
                    ex * w[k, 0] + ey * w[k, 1] + ez * w[k, 2],
                    ex * u[k, 0] + ey * u[k, 1] + ez * u[k, 2],
                )
            for c in range(1, cnt):  # insertion sort by angle: counter-clockwise from outside
                ang = angle[c]
                q = members[c]
                b = c - 1
                while b >= 0 and angle[b] > ang:
                    angle[b + 1] = angle[b]
                    members[b + 1] = members[b]
                    b -= 1
                angle[b + 1] = ang
                members[b + 1] = q
            fdir[p, nf] = k
            fsize[p, nf] = cnt
            for c in range(cnt):
                fverts[p, pos + c] = members[c]
            pos += cnt
            nf += 1
            a0 = members[0]
            for c in range(1, cnt - 1):  # tetrahedra (origin, a, b, e) of a fan of the face
                b1 = members[c]
                e1 = members[c + 1]
                ax, ay, az = verts[p, a0, 0], verts[p, a0, 1], verts[p, a0, 2]
                bx, by, bz = verts[p, b1, 0], verts[p, b1, 1], verts[p, b1, 2]
                qx, qy, qz = verts[p, e1, 0], verts[p, e1, 1], verts[p, e1, 2]
                v6 = ax * (by * qz - bz * qy) - ay * (bx * qz - bz * qx) + az * (bx * qy - by * qx)
                vol6 += v6
                cx += v6 * (ax + bx + qx)
                cy += v6 * (ay + by + qy)
                cz += v6 * (az + bz + qz)
        nface[p] = nf
        if status[p] != OK:
            continue
        if not vol6 > 6.0 * VOLUME_MIN * scale**3:
            status[p] = NO_VOLUME
            continue
        volume[p] = vol6 / 6.0
        centroid[p, 0] = cx / (4.0 * vol6)
        centroid[p, 1] = cy / (4.0 * vol6)
        centroid[p, 2] = cz / (4.0 * vol6)
        if pos % 2 != 0 or nv - pos // 2 + nf != 2:  # Euler's formula V - E + F = 2
            status[p] = NOT_CLOSED
    return nvert, verts, nface, fdir, fsize, fverts, support, volume, centroid, status
