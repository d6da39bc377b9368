"""Cores of rounded polyhedra that fit inside sharp ones: a polyhedron eroded by a radius.

A rounded polyhedron is every point within ``r`` of a convex core. For a
sharp convex polyhedron ``P = {x : n_f · x <= s_f}`` the core
``C = {x : n_f · x <= s_f - r}`` (every face plane moved inward by ``r``)
gives a rounded body ``C ⊕ B(r)`` that lies inside ``P`` and differs from it
only along the edges and at the corners: every point of the body is within
``r`` of a point ``x`` of the core, and ``n_f · x + r <= s_f`` for every face.
Erosion may drop small faces and merge vertices, so the core's faces, edges
and vertices are computed afresh from the moved planes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["CORE_TOLERANCE", "Core", "erode_polyhedron"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

CORE_TOLERANCE = 1e-6
"""Core vertices closer than this times the core's extent are one vertex; a vertex
this close (relative) to a moved plane lies on that face."""


@dataclass(frozen=True)
class Core:
    """A convex core: its vertices, its faces as outward loops and its edges.

    Attributes
    ----------
    vertices
        ``(k, 3)`` vertices, in the frame of the polyhedron that was eroded.
    loops
        Faces as loops of vertex indices, counter-clockwise seen from outside.
    edges
        ``(e, 2)`` vertex indices of every edge, the smaller first, sorted.
    """

    vertices: FloatArray
    loops: list[IntArray]
    edges: IntArray


def _merge(points: FloatArray, tol: float) -> FloatArray:
    """Points with those closer than ``tol`` to an earlier kept point dropped."""
    close = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=2) <= tol
    keep = np.ones(points.shape[0], dtype=bool)
    for i in range(points.shape[0]):
        if keep[i]:
            keep[i + 1 :] &= ~close[i, i + 1 :]
    out: FloatArray = points[keep]
    return out


def erode_polyhedron(normals: FloatArray, support: FloatArray, r: float) -> Core | None:
    """Erode ``{x : normals · x <= support}`` by ``r``: its core, or ``None`` if it is flat.

    Parameters
    ----------
    normals
        ``(F, 3)`` unit outward face normals.
    support
        ``(F,)`` plane offsets, all greater than ``r`` (the origin lies inside
        the core).
    r
        Erosion radius, ``>= 0``.

    Returns
    -------
    Core or None
        ``None`` when the core has no volume left, or when its faces do not
        close into a polyhedron (V - E + F != 2) after merging vertices.

    Examples
    --------
    >>> n = np.vstack([np.eye(3), -np.eye(3)])
    >>> core = erode_polyhedron(n, np.ones(6), 0.25)
    >>> np.abs(core.vertices).max(), len(core.loops), core.edges.shape
    (0.75, 6, (12, 2))
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    offsets = support - r
    if np.any(offsets <= 0):
        return None
    try:
        hs = HalfspaceIntersection(np.column_stack([normals, -offsets]), np.zeros(3))
    except (QhullError, ValueError):
        return None
    points = hs.intersections
    extent = float(np.abs(points).max()) if points.size else 0.0
    if not extent > 0:
        return None
    tol = CORE_TOLERANCE * extent
    verts = _merge(points, tol)
    if verts.shape[0] < 4:
        return None
    loops: list[IntArray] = []
    for n, s in zip(normals, offsets, strict=True):
        on = np.flatnonzero(np.abs(verts @ n - s) <= tol)
        if on.size < 3:
            continue
        centre = verts[on].mean(axis=0)
        u = verts[on[0]] - centre
        u -= (u @ n) * n
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        rel = verts[on] - centre
        order = np.argsort(np.arctan2(rel @ v, rel @ u))
        loops.append(on[order].astype(np.int64))
    pairs = {
        (int(min(a, b)), int(max(a, b)))
        for loop in loops
        for a, b in zip(loop, np.roll(loop, -1), strict=True)
    }
    edges = np.array(sorted(pairs), dtype=np.int64).reshape(-1, 2)
    if verts.shape[0] - edges.shape[0] + len(loops) != 2:
        return None
    return Core(verts, loops, edges)
