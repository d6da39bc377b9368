"""Convex polyhedra in the form the available-surface kernels read.

A polyhedron is given relative to its reference point, which lies strictly
inside it, by

- ``vertices`` ``(k, 3)``;
- its face planes, unit outward ``normals`` ``(f, 3)`` and ``support`` values
  ``(f,)``: face ``i`` lies in the plane ``normals[i] · x = support[i]``;
- its faces as vertex-index loops, counter-clockwise seen from outside, in
  flat form: face ``i`` is ``face_vertices[face_offsets[i]:face_offsets[i + 1]]``.

:class:`Polyhedron` bundles the five arrays; it is a plain tuple, so compiled
kernels take and return it. :func:`polyhedron_from_points` builds one from a
point cloud (scipy's convex hull, coplanar triangles merged into polygons).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

COPLANAR_EPS = 1e-9
"""Adjacent hull triangles whose planes agree within this fraction of the
circumradius (offsets, and normals times the circumradius) form one face."""


class Polyhedron(NamedTuple):
    """A convex polyhedron relative to its reference point (see the module docstring)."""

    vertices: FloatArray
    normals: FloatArray
    support: FloatArray
    face_vertices: IntArray
    face_offsets: IntArray


def polyhedron_from_points(points: ArrayLike) -> Polyhedron:
    """Return the convex hull of ``points`` as a :class:`Polyhedron`.

    Parameters
    ----------
    points
        ``(k, 3)`` coordinates relative to the reference point, which must lie
        strictly inside their convex hull.

    Returns
    -------
    Polyhedron
        ``(vertices, normals, support, face_vertices, face_offsets)``: only the
        extreme points are kept (renumbered); adjacent hull triangles that are
        coplanar within :data:`COPLANAR_EPS` are merged into one polygon face,
        whose vertices in the interior of a straight side are dropped. Normals
        are the area-weighted mean of the merged triangles' normals, support
        values the largest ``normal · vertex`` over the face.

    Raises
    ------
    ValueError
        If the points do not span a volume or the origin is not strictly inside.

    Examples
    --------
    >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    >>> poly = polyhedron_from_points(cube)
    >>> len(poly.vertices), len(poly.normals), len(poly.face_vertices)
    (8, 6, 24)
    """
    from scipy.spatial import ConvexHull, QhullError

    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 4:
        raise ValueError(f"points must be (k >= 4, 3), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points must be finite")
    try:
        hull = ConvexHull(pts)
    except QhullError as exc:
        raise ValueError(f"the points do not span a volume: {exc}") from None
    radius = float(np.max(np.linalg.norm(pts, axis=1)))
    tol = COPLANAR_EPS * radius
    tri = hull.simplices
    eq = hull.equations
    # union-find over adjacent coplanar triangles
    parent = np.arange(len(tri))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = int(parent[i])
        return i

    for i, nbrs in enumerate(hull.neighbors):
        for j in nbrs:
            if j < i:
                continue
            same_normal = np.linalg.norm(eq[i, :3] - eq[j, :3]) * radius <= tol
            if same_normal and abs(eq[i, 3] - eq[j, 3]) <= tol:
                parent[root(i)] = root(int(j))
    groups: dict[int, list[int]] = {}
    for i in range(len(tri)):
        groups.setdefault(root(i), []).append(i)
    loops: list[list[int]] = []
    normals: list[FloatArray] = []
    for members in groups.values():
        area_normal = np.zeros(3)
        for i in members:
            a, b, c = pts[tri[i]]
            area_normal += np.abs(np.linalg.norm(np.cross(b - a, c - a))) * eq[i, :3]
        normal = area_normal / np.linalg.norm(area_normal)
        loop = _face_loop(pts, np.unique(tri[members]), normal, tol)
        loops.append(loop)
        normals.append(normal)
    used = np.unique(np.concatenate([np.asarray(loop) for loop in loops]))
    index = np.full(len(pts), -1, dtype=np.int64)
    index[used] = np.arange(len(used))
    vertices = pts[used]
    normal_arr = np.array(normals)
    face_vertices = np.concatenate([index[np.asarray(loop)] for loop in loops])
    face_offsets = np.concatenate([[0], np.cumsum([len(loop) for loop in loops])])
    support = np.array(
        [
            np.max(vertices[face_vertices[s:e]] @ n)
            for n, s, e in zip(normal_arr, face_offsets[:-1], face_offsets[1:], strict=True)
        ]
    )
    if not np.all(support > 0.0):
        raise ValueError("the reference point (the origin) must lie strictly inside the hull")
    return Polyhedron(
        vertices=np.ascontiguousarray(vertices),
        normals=np.ascontiguousarray(normal_arr),
        support=support,
        face_vertices=face_vertices.astype(np.int64),
        face_offsets=face_offsets.astype(np.int64),
    )


def _face_loop(pts: FloatArray, members: IntArray, normal: FloatArray, tol: float) -> list[int]:
    """Order the points ``members`` of one face counter-clockwise about ``normal``.

    Points closer than ``tol`` to the segment between their neighbours are dropped.
    """
    e1, e2 = plane_basis(normal)
    rel = pts[members] - pts[members].mean(axis=0)
    angle = np.arctan2(rel @ e2, rel @ e1)
    loop = [int(i) for i in members[np.argsort(angle)]]
    changed = True
    while changed and len(loop) > 3:
        changed = False
        for k in range(len(loop)):
            a = pts[loop[k - 1]]
            b = pts[loop[k]]
            c = pts[loop[(k + 1) % len(loop)]]
            chord = c - a
            length = max(float(np.linalg.norm(chord)), 1e-300)
            dist = float(np.linalg.norm(np.cross(chord, b - a))) / length
            if dist <= tol:
                del loop[k]
                changed = True
                break
    return loop


def plane_basis(normal: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return unit vectors ``e1, e2`` with ``e1 × e2 = normal`` (for a unit ``normal``)."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(normal)))] = 1.0
    e1 = np.cross(normal, axis)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    return e1, e2


def reflect(poly: Polyhedron) -> Polyhedron:
    """Return ``-P``, the point reflection of ``poly`` through its reference point.

    The loops are reversed so that they stay counter-clockwise seen from outside.
    """
    loops = [
        poly.face_vertices[s:e][::-1]
        for s, e in zip(poly.face_offsets[:-1], poly.face_offsets[1:], strict=True)
    ]
    return Polyhedron(
        vertices=-poly.vertices,
        normals=-poly.normals,
        support=poly.support.copy(),
        face_vertices=np.concatenate(loops).astype(np.int64),
        face_offsets=poly.face_offsets.copy(),
    )


def circumradius(poly: Polyhedron) -> float:
    """Largest distance from the reference point to a vertex."""
    return float(np.max(np.linalg.norm(poly.vertices, axis=1)))


def volume(poly: Polyhedron) -> float:
    """Volume, summed over the pyramids from the reference point to the faces."""
    return float(sum(poly.support[i] * face_area(poly, i) for i in range(len(poly.support))) / 3.0)


def face_area(poly: Polyhedron, face: int) -> float:
    """Area of face ``face`` (its loop is planar and convex)."""
    loop = poly.vertices[poly.face_vertices[poly.face_offsets[face] : poly.face_offsets[face + 1]]]
    rel = loop - loop[0]
    cross = np.cross(rel[1:-1], rel[2:]).sum(axis=0)
    return float(0.5 * abs(cross @ poly.normals[face]))
