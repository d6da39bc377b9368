"""Contacts between convex polyhedra (and spheres) at a tolerance, and the equivalent spherical cap.

Each particle is grown by ``tol / 2`` along every face normal (its support
values plus ``tol / 2``); two particles are in contact at ``tol`` when their
grown solids share volume. Every pair gets, once, its *threshold*: twice the
smallest growth at which the grown solids meet (a linear program, see
:mod:`regopack.plugins.analyzers.contact3d_kernel`). A pair is in contact at
any ``tol`` above its threshold, so ``Z(tol)`` needs no new search.

The threshold ``tau`` relates to the Euclidean gap ``g`` between the two
solids (:func:`regopack.verification.polyhedra.separating_gap`) by
``tau <= g <= tau * (R_i / h_i + R_j / h_j) / 2`` (``R`` the circumradius
and ``h`` the smallest support value about the centre), with ``tau = g``
when the closest features are a face and a point that projects into it
(face-face, edge-face and vertex-face contacts): a growth along the face
normals covers at least the ball of the same radius, and at most the solid
scaled about its centre by ``1 + s / h``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import FoundContacts
from regopack.plugins.analyzers.spherical_cap import equivalent_cap

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _reach(packing: Packing[Box], placed: IntArray, s_max: float) -> FloatArray:
    """Radius about its centre of the ball that holds each solid ``placed`` grown by ``s_max``.

    A solid grown by ``s`` along its face normals lies in the ball of radius
    ``R (1 + s / h)`` (``R`` its circumradius, ``h`` its smallest support
    value), a sphere (no faces) in that of radius ``R + s``; widened by a
    relative 1e-9.
    """
    counts = np.diff(packing.face_offsets)
    smallest = np.full(packing.n_particles, np.inf)
    smallest[counts > 0] = np.minimum.reduceat(
        packing.support, packing.face_offsets[:-1][counts > 0]
    )
    circum = packing.solids.circumradius
    grown = np.where(counts > 0, circum * (1.0 + s_max / smallest), circum + s_max)
    return np.asarray(grown[placed] * (1.0 + 1e-9), dtype=np.float64)


def candidate_pairs(packing: Packing[Box], s_max: float) -> tuple[IntArray, IntArray]:
    """Pairs ``i < j`` of placed solids whose solids grown by ``s_max`` may meet.

    A solid grown by ``s`` along its face normals lies in the ball about its
    centre of radius ``R (1 + s / h)`` (``R`` its circumradius, ``h`` its
    smallest support value); pairs whose balls meet are returned, from a k-d
    tree of the centres.
    """
    from scipy.spatial import cKDTree

    placed = np.flatnonzero(packing.placed).astype(np.int64)
    if placed.shape[0] < 2:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    reach = _reach(packing, placed, s_max)
    centre = packing.centre[placed]
    tree = cKDTree(centre)
    found = tree.query_pairs(2.0 * float(reach.max()), output_type="ndarray")
    a, b = found[:, 0], found[:, 1]
    d = np.linalg.norm(centre[b] - centre[a], axis=1)
    near = d <= reach[a] + reach[b]
    i, j = placed[a[near]], placed[b[near]]
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    order = np.lexsort((hi, lo))
    return lo[order].astype(np.int64), hi[order].astype(np.int64)


def periodic_pairs(packing: Packing[Box], s_max: float) -> tuple[IntArray, IntArray, FloatArray]:
    """:func:`candidate_pairs` in a periodic box: pairs ``(i, j)`` and the shift of ``j``.

    Every image ``centre[j] + shift`` (among the 27 about the cell) whose ball
    meets ``i``'s is a pair, so in a box a few particles wide a pair may meet
    through two images, and a particle its own image (``i == j``). Pairs have
    ``i <= j`` and appear once.
    """
    import itertools

    from scipy.spatial import cKDTree

    placed = np.flatnonzero(packing.placed).astype(np.int64)
    if placed.shape[0] < 1:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    reach = _reach(packing, placed, s_max)
    box = packing.domain
    lo = np.array([box.xmin, box.ymin, box.zmin])
    period = np.array(box.size)
    wrapped = np.mod(packing.centre[placed] - lo, period)
    wrapped[wrapped >= period] = 0.0
    tree = cKDTree(wrapped)
    rows: list[tuple[IntArray, IntArray, FloatArray]] = []
    for s in itertools.product((-1, 0, 1), repeat=3):
        image = np.array(s, dtype=float) * period
        found = tree.sparse_distance_matrix(
            cKDTree(wrapped + image), 2.0 * float(reach.max()), output_type="ndarray"
        )
        a = found["i"].astype(np.int64)
        b = found["j"].astype(np.int64)
        d = found["v"]
        # each contact once: (a, b, s) is (b, a, -s); a particle's own image once
        first = (a < b) | ((a == b) & (s > (0, 0, 0)))
        near = first & (d <= reach[a] + reach[b])
        a, b = a[near], b[near]
        shift = (wrapped[b] + image + lo - packing.centre[placed[b]]) - (
            wrapped[a] + lo - packing.centre[placed[a]]
        )
        rows.append((a, b, shift))
    a = np.concatenate([r[0] for r in rows])
    b = np.concatenate([r[1] for r in rows])
    shift = np.concatenate([r[2] for r in rows])
    i, j = placed[a], placed[b]
    swap = i > j
    i, j = np.where(swap, j, i), np.where(swap, i, j)
    shift[swap] = -shift[swap]
    order = np.lexsort((shift[:, 2], shift[:, 1], shift[:, 0], j, i))
    return i[order].astype(np.int64), j[order].astype(np.int64), shift[order]


class _Solids(NamedTuple):
    """The arrays the contact kernels read."""

    centre: FloatArray
    vertices: FloatArray
    offsets: IntArray
    normals: FloatArray
    support: FloatArray
    face_offsets: IntArray
    size: FloatArray


def _own_solids(p3: Packing[Box]) -> _Solids:
    """Return the packing's solids as the kernels read them."""
    return _Solids(
        np.ascontiguousarray(np.nan_to_num(p3.centre), dtype=np.float64),
        np.ascontiguousarray(p3.vertices),
        np.ascontiguousarray(p3.offsets),
        np.ascontiguousarray(p3.normals),
        np.ascontiguousarray(p3.support),
        np.ascontiguousarray(p3.face_offsets),
        np.ascontiguousarray(p3.solids.circumradius, dtype=np.float64),
    )


def _with_ghosts(p3: Packing[Box], pj: IntArray, shift: FloatArray) -> tuple[IntArray, _Solids]:
    """Append copies of the solids ``pj``, moved by ``shift``, after the packing's own.

    Returns the copies' indices and the extended ``centre, vertices, offsets,
    normals, support, face_offsets, size`` arrays the kernels read.
    """
    n = p3.n_particles
    solids = p3.solids

    def ranges(offsets: IntArray) -> tuple[IntArray, IntArray]:
        sizes = offsets[pj + 1] - offsets[pj]
        starts = np.repeat(offsets[pj] - np.concatenate([[0], np.cumsum(sizes)[:-1]]), sizes)
        return starts + np.arange(int(sizes.sum())), sizes

    vidx, vsizes = ranges(solids.offsets)
    fidx, fsizes = ranges(solids.face_offsets)
    centre = np.concatenate([np.nan_to_num(p3.centre), p3.centre[pj] + shift])
    vertices = np.concatenate([p3.vertices, p3.vertices[vidx]])
    offsets = np.concatenate([solids.offsets, solids.offsets[-1] + np.cumsum(vsizes)])
    normals = np.concatenate([p3.normals, p3.normals[fidx]])
    support = np.concatenate([p3.support, p3.support[fidx]])
    face_offsets = np.concatenate(
        [solids.face_offsets, solids.face_offsets[-1] + np.cumsum(fsizes)]
    )
    size = np.concatenate([solids.circumradius, solids.circumradius[pj]])
    ghosts = np.arange(n, n + pj.shape[0], dtype=np.int64)
    c = np.ascontiguousarray
    return ghosts, _Solids(
        c(centre), c(vertices), c(offsets), c(normals), c(support), c(face_offsets), c(size)
    )


def _fallback_threshold(
    packing: Packing[Box], i: int, j: int, shift: FloatArray | None = None, name: str = "contacts"
) -> tuple[float, FloatArray]:
    """Threshold and normal of one pair by HiGHS, for a pair the compiled simplex gave up on."""
    from scipy.optimize import linprog

    solids = packing.solids
    parts = []
    for p, moved in ((i, np.zeros(3)), (j, np.zeros(3) if shift is None else shift)):
        f0, f1 = int(solids.face_offsets[p]), int(solids.face_offsets[p + 1])
        nrm = solids.normals[f0:f1]
        parts.append((nrm, solids.support[f0:f1] + nrm @ (packing.centre[p] + moved)))
    a_ub = np.vstack([np.column_stack([n, -np.ones(len(n))]) for n, _ in parts])
    b_ub = np.concatenate([b for _, b in parts])
    res = linprog(np.array([0.0, 0.0, 0.0, 1.0]), A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 4)
    if res.status != 0:
        raise ConfigError(f"{name}: the threshold of particles {i} and {j} was not found")
    lam = -np.asarray(res.ineqlin.marginals)[: len(parts[0][0])]
    w = lam @ parts[0][0]
    norm = float(np.linalg.norm(w))
    return float(res.fun), (w / norm if norm > 0 else np.zeros(3))


def find_contacts(p3: Packing[Box], tol: float, tol_max: float, name: str) -> FoundContacts:
    """Find the candidate pairs, their thresholds and normals, and the regions at ``tol``.

    ``name`` (the analyzer's) starts the messages refusing a packing.
    """
    from regopack.plugins.analyzers import contact3d_kernel as ck

    if p3.rounded:
        if p3.solids.normals.shape[0] != 0:
            raise ConfigError(
                f"{name}: rounded polyhedra are not analysed yet (sharp polyhedra and spheres only)"
            )
        return _sphere_contacts(p3, tol, tol_max)
    s_max = 0.5 * tol_max
    if p3.domain.periodic:
        # each pair through the image of j nearest to i: a moved copy of j
        pi, pj, shift = periodic_pairs(p3, s_max)
        qj, sol = _with_ghosts(p3, pj, shift)
    else:
        pi, pj = candidate_pairs(p3, s_max)
        shift = np.zeros((pi.shape[0], 3))
        qj, sol = pj, _own_solids(p3)
    faces = (sol.normals, sol.support, sol.face_offsets)
    thr, nrm = ck.pair_thresholds(pi, qj, sol.centre, *faces, sol.size)
    for k in np.flatnonzero(np.isnan(thr)).tolist():
        thr[k], nrm[k] = _fallback_threshold(p3, int(pi[k]), int(pj[k]), shift[k], name)
    keep = 2.0 * thr < tol_max
    pairs = np.column_stack([pi[keep], pj[keep]]).astype(np.int64)
    threshold = 2.0 * thr[keep]
    pair_normal = nrm[keep]
    at = threshold < tol
    ci, cj = pairs[at, 0].copy(), pairs[at, 1].copy()
    qcj = qj[keep][at].copy()
    normal = np.ascontiguousarray(pair_normal[at])
    volume, area, width, point = ck.contact_regions(
        ci, qcj, 0.5 * tol, normal, sol.centre, sol.vertices, sol.offsets, *faces, sol.size
    )
    ok = (volume > 0) & (area > 0)
    columns = _cap_columns(ci[ok], cj[ok], threshold[at][ok], volume[ok], area[ok], width[ok])
    return FoundContacts(pairs, threshold, columns, normal[ok], point[ok], pair_normal)


def _cap_columns(
    i: IntArray,
    j: IntArray,
    threshold: FloatArray,
    volume: FloatArray,
    area: FloatArray,
    width: FloatArray,
) -> dict[str, NDArray[Any]]:
    """Return the columns of the contacts at ``tol``, with their equivalent spherical caps."""
    depth, radius = equivalent_cap(volume, area)
    return {
        "i": i,
        "j": j,
        "threshold": threshold,
        "area": area,
        "volume": volume,
        "width": width,
        "depth": depth,
        "cap_radius": radius,
        "thickness": volume / area,
    }


def _sphere_contacts(p3: Packing[Box], tol: float, tol_max: float) -> FoundContacts:
    """:func:`find_contacts` for spheres, in closed form.

    Two spheres grown by ``s`` each meet when their gap ``g = d - r_i - r_j``
    is below ``2 s``: the threshold is ``g``, the normal the unit vector
    between the centres. At ``tol`` the grown spheres share a lens
    (:func:`regopack.geometry.sphere_volume.lens_volume`) whose projection on the
    contact plane is the disk where their surfaces cross.
    """
    from scipy.spatial import cKDTree

    from regopack.geometry.sphere_volume import lens_volume

    placed = np.flatnonzero(p3.placed)
    solids = p3.solids
    r_all = solids.rounding_radius
    c_all = np.nan_to_num(p3.centre) + solids.vertices[solids.offsets[:-1]]
    if p3.domain.periodic:
        # every image among the 27 about the cell, as for polyhedra: a pair may meet
        # through two images in a box a few spheres wide, a sphere its own image
        pi, pj, shift = periodic_pairs(p3, 0.5 * tol_max)
        pairs = np.column_stack([pi, pj]).astype(np.int64)
        delta = c_all[pj] + shift - c_all[pi]
    else:
        c, r = c_all[placed], r_all[placed]
        reach = 2.0 * float(r.max()) + tol_max if len(placed) else 0.0
        found = np.array(sorted(cKDTree(c).query_pairs(reach)), dtype=np.int64).reshape(-1, 2)
        pairs = placed[found]
        delta = c[found[:, 1]] - c[found[:, 0]]
    dist = np.linalg.norm(delta, axis=1)
    gap = dist - r_all[pairs[:, 0]] - r_all[pairs[:, 1]]
    keep = gap < tol_max
    pairs, delta, dist, gap = pairs[keep], delta[keep], dist[keep], gap[keep]
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    pairs, delta, dist, gap = pairs[order], delta[order], dist[order], gap[order]
    pair_normal = delta / dist[:, None]
    at = gap < tol
    ci, cj = pairs[at, 0].copy(), pairs[at, 1].copy()
    r1 = r_all[ci] + 0.5 * tol
    r2 = r_all[cj] + 0.5 * tol
    d = dist[at]
    volume = np.array([lens_volume(a, b, e) for a, b, e in zip(r1, r2, d, strict=True)])
    x = (d * d + r1 * r1 - r2 * r2) / (2.0 * d)  # from centre i to the lens's disk
    radius2 = np.maximum(r1 * r1 - x * x, 0.0)
    area = np.pi * radius2
    normal = np.ascontiguousarray(pair_normal[at])
    point = c_all[ci] + x[:, None] * normal
    ok = (volume > 0) & (area > 0)
    width = 2.0 * np.sqrt(radius2[ok])
    columns = _cap_columns(ci[ok], cj[ok], gap[at][ok], volume[ok], area[ok], width)
    pairs = np.ascontiguousarray(pairs, dtype=np.int64)
    return FoundContacts(pairs, gap, columns, normal[ok], point[ok], pair_normal)
