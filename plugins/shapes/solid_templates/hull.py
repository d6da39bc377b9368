"""The convex hull of a point cloud as a polyhedron with polygon faces, normalised.

:func:`normalised_hull` takes the vertices of a mesh (any triangles: open,
non-convex, badly oriented), computes their convex hull with Qhull
(:class:`scipy.spatial.ConvexHull`), merges the hull's coplanar triangles
into polygon faces, orients every face counter-clockwise seen from outside,
and moves and scales the hull so that its volume centroid is the origin and
its volume is 1. The checks that make a hull usable as a particle (enough
distinct points, a precision of the coordinates that resolves the shape, a
hull that is not flat) are one-line
:class:`~regopack.plugins.shapes.polygons.TemplateError` messages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from regopack.plugins.shapes.polygons import TemplateError

__all__ = ["COPLANAR_TOL", "FLAT_RTOL", "RESOLUTION", "ConvexSolid", "normalised_hull"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

RESOLUTION = 1e-4
"""Largest spacing of the representable coordinates, relative to the mesh's size.

Float numbers near a coordinate ``c`` are ``spacing(c)`` apart (about
``6e-8 c`` in float32, the binary STL format's); a mesh lying far from the
origin compared with its size keeps only that grid of its shape. A mesh whose
largest coordinate's spacing exceeds ``RESOLUTION`` times its size (for
float32, one lying more than about 800 of its sizes away from the origin) is
refused: move it to the origin when exporting it.
"""

COPLANAR_TOL = 1e-10
"""Two neighbouring hull triangles whose unit normals differ by less than this, and whose
planes' offsets differ by less than this times the mesh's size, form one face."""

CONSISTENCY_RTOL = 1e-10
"""Largest distance of a face's vertex from the face's plane, relative to the hull's size,
and smallest distance between two vertices: a hull that rounding leaves outside these
bounds is computed again from snapped points (see :data:`SNAP_STEPS`)."""

SNAP_STEPS = (0.0, 2.0**-30, 2.0**-26, 2.0**-22, 2.0**-18, 2.0**-14)
"""Grids (relative to the mesh's size) that the points are rounded to, in turn, until the
hull is consistent; 0 keeps them exact, which suffices for all but meshes of nearly
coincident points, whose thin hull triangles have normals spoilt by rounding. The last
grid moves a point by at most 3e-5 of the size."""

FLAT_RTOL = 1e-6
"""A hull is flat when the distance from its centroid to its nearest face is at most this
fraction of the distance to its farthest vertex."""


@dataclass(frozen=True, eq=False)
class ConvexSolid:
    """A convex polyhedron of volume 1 with its volume centroid at the origin.

    Attributes
    ----------
    vertices
        ``(k, 3)`` vertices; every one is a corner of some face.
    face_vertices
        Vertex loops of all faces, counter-clockwise seen from outside.
    face_vertex_offsets
        ``(F + 1,)``: face ``f``'s loop is ``face_vertices[face_vertex_offsets[f]:
        face_vertex_offsets[f + 1]]``.
    normals
        ``(F, 3)`` unit outward normals.
    support
        ``(F,)`` the support value along each normal, ``max_v normals[f] . v``
        over all vertices: the distance of the face's plane from the centroid.
    """

    vertices: FloatArray
    face_vertices: IntArray
    face_vertex_offsets: IntArray
    normals: FloatArray
    support: FloatArray

    @property
    def n_faces(self) -> int:
        """Number of faces."""
        return int(self.normals.shape[0])


def _check_precision(points: FloatArray, dtype: type[np.floating], label: str) -> float:
    """Return the mesh's size (largest side of its bounding box); refuse a lost precision."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    with np.errstate(over="ignore"):
        size = float(np.max(hi - lo))
    if not math.isfinite(size):
        raise TemplateError(
            f"{label}: the mesh's size overflows 64-bit floats; scale the mesh down"
        )
    largest = float(np.max(np.abs(points)))
    with np.errstate(over="ignore", invalid="ignore"):
        step = float(np.spacing(dtype(largest)))  # NaN when ``largest`` overflows ``dtype``
    if not step <= RESOLUTION * size:
        raise TemplateError(
            f"{label}: the coordinates resolve only {step / size:.1e} of the mesh's size "
            f"{size:.6g} (largest |coordinate| {largest:.6g}, {np.dtype(dtype).name}); at most "
            f"{RESOLUTION:g} is allowed: move the mesh near the origin or scale it up"
        )
    return size


def _merged_faces(hull: ConvexHull, tol: float) -> IntArray:
    """Label of the face each hull triangle belongs to (coplanar neighbours share one)."""
    eq = hull.equations
    f = np.repeat(np.arange(eq.shape[0]), 3)
    g = hull.neighbors.ravel()
    same = (np.abs(eq[f, :3] - eq[g, :3]).max(axis=1) <= COPLANAR_TOL) & (
        np.abs(eq[f, 3] - eq[g, 3]) <= tol
    )
    graph = coo_matrix((np.ones(int(same.sum())), (f[same], g[same])), shape=(len(eq), len(eq)))
    _, labels = connected_components(graph, directed=False)
    return np.asarray(labels, dtype=np.int64)


def _loop(triangles: IntArray) -> list[int]:
    """Boundary loop of coplanar triangles, each counter-clockwise seen from outside."""
    edges = {
        (int(a), int(b)) for t in triangles for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))
    }
    after = {a: b for a, b in edges if (b, a) not in edges}
    start = min(after)
    loop = [start]
    while (nxt := after[loop[-1]]) != start:
        loop.append(nxt)
        if len(loop) > len(after):  # not one simple loop; cannot happen for a convex face
            raise RuntimeError("the coplanar hull triangles do not bound one polygon")
    return loop


def _support(verts: FloatArray, normals: FloatArray) -> FloatArray:
    """``max_v normals[f] . v`` over all vertices, in blocks of about a million products."""
    out = np.empty(normals.shape[0])
    block = max(1, (1 << 20) // verts.shape[0])
    for f in range(0, normals.shape[0], block):
        out[f : f + block] = (normals[f : f + block] @ verts.T).max(axis=1)
    return out


def normalised_hull(
    points: FloatArray, label: str, dtype: type[np.floating] = np.float64
) -> ConvexSolid:
    """Convex hull of ``points``, with polygon faces, centred on its centroid, of volume 1.

    Parameters
    ----------
    points
        ``(m, 3)`` finite coordinates (repeats allowed), e.g. all triangle
        corners of a mesh.
    label
        How to name the points' file in messages.
    dtype
        Type the coordinates were stored in (float32 for a binary STL); it
        sets the precision check (:data:`RESOLUTION`).

    Returns
    -------
    ConvexSolid
        The hull, translated so that its volume centroid is the origin and
        scaled to the volume 1 (rotation and shape kept).

    Raises
    ------
    TemplateError
        When there are fewer than 4 distinct points, the coordinates do not
        resolve the shape (:data:`RESOLUTION`), the hull is flat
        (:data:`FLAT_RTOL`), or no grid of :data:`SNAP_STEPS` makes it
        consistent.

    Notes
    -----
    The hull is checked after it is built (:data:`CONSISTENCY_RTOL`): a mesh
    with nearly coincident points (twins a rounding error apart, common in
    noisy exports) gives thin hull triangles whose computed normals are off
    by more than the contract of a solid allows. Such a mesh is hulled again
    from its points rounded to a grid, finer grids first, so that an exact
    mesh keeps its exact coordinates.

    Examples
    --------
    >>> cube = np.array([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)], float)
    >>> solid = normalised_hull(cube, "cube")
    >>> solid.n_faces, solid.vertices.shape, bool(np.allclose(solid.support, 0.5))
    (6, (8, 3), True)
    """
    unique = np.unique(np.asarray(points, dtype=np.float64).reshape(-1, 3), axis=0)
    if unique.shape[0] < 4:
        raise TemplateError(
            f"{label}: {unique.shape[0]} distinct points; a solid needs at least 4 that do "
            "not lie in one plane"
        )
    size = _check_precision(unique, dtype, label)
    lo, hi = unique.min(axis=0), unique.max(axis=0)
    # work in coordinates of size about 1, so that tolerances are relative
    q = (unique - (0.5 * lo + 0.5 * hi)) / size
    for step in SNAP_STEPS:
        pts = q if step == 0.0 else np.unique(np.round(q / step) * step, axis=0)
        try:
            solid = _hull(pts, label)
        except RuntimeError:  # coplanar triangles that bound no single polygon
            continue
        if _consistent(solid):
            return solid
    raise TemplateError(
        f"{label}: the convex hull cannot be computed to {CONSISTENCY_RTOL:g} of its size, "
        f"even with the points snapped to {SNAP_STEPS[-1]:.1e} of it (a mesh of nearly "
        "coincident, noisy points); simplify the mesh"
    )


def _consistent(solid: ConvexSolid) -> bool:
    """Whether rounding left the hull a closed convex polyhedron to :data:`CONSISTENCY_RTOL`.

    Every face's vertices lie on its plane (the plane of the support value
    along its normal, over all vertices), every edge runs once each way, and
    no two vertices are closer than ``CONSISTENCY_RTOL`` times the largest
    distance from the centroid.
    """
    v, fv, fvo = solid.vertices, solid.face_vertices, solid.face_vertex_offsets
    if not (np.isfinite(solid.normals).all() and np.isfinite(v).all()):
        return False  # a face of no area
    reach = float(np.max(np.linalg.norm(v, axis=1)))
    owner = np.repeat(np.arange(solid.n_faces), np.diff(fvo))
    off_plane = np.abs(np.einsum("ij,ij->i", v[fv], solid.normals[owner]) - solid.support[owner])
    if float(off_plane.max()) > CONSISTENCY_RTOL * reach:
        return False
    after = np.arange(fv.shape[0]) + 1
    last = np.diff(fvo) - 1
    after[fvo[1:] - 1] -= last + 1  # the last vertex of a loop runs back to the first
    edges = set(zip(fv.tolist(), fv[after].tolist(), strict=True))
    if len(edges) != fv.shape[0] or any((b, a) not in edges for a, b in edges):
        return False
    return not cKDTree(v).query_pairs(CONSISTENCY_RTOL * reach)


def _hull(q: FloatArray, label: str) -> ConvexSolid:
    """Hull of points of size about 1, with merged faces, moved and scaled (no checks)."""
    if q.shape[0] < 4:
        raise TemplateError(
            f"{label}: {q.shape[0]} distinct points; a solid needs at least 4 that do "
            "not lie in one plane"
        )
    try:
        hull = ConvexHull(q)
    except QhullError:
        raise TemplateError(
            f"{label}: the convex hull of the mesh is flat (its points lie in one plane, or "
            "in one line); a solid template needs a volume"
        ) from None
    labels = _merged_faces(hull, COPLANAR_TOL)
    tri = np.asarray(hull.simplices, dtype=np.int64).copy()
    a, b, c = q[tri[:, 0]], q[tri[:, 1]], q[tri[:, 2]]
    backwards = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    tri[backwards, 1], tri[backwards, 2] = tri[backwards, 2], tri[backwards, 1].copy()
    order = np.argsort(labels, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(labels[order]) != 0])
    groups = np.split(order, starts[1:])
    loops = [tri[g[0]].tolist() if g.size == 1 else _loop(tri[g]) for g in groups]
    # keep only the loops' vertices (Qhull may leave a point inside a merged face)
    used, flat_loops = np.unique(np.concatenate(loops), return_inverse=True)
    verts = q[used]
    sizes = np.array([len(loop) for loop in loops], dtype=np.int64)
    fvo = np.zeros(len(loops) + 1, dtype=np.int64)
    np.cumsum(sizes, out=fvo[1:])
    fv = np.asarray(flat_loops, dtype=np.int64).ravel()
    # volume and centroid of the fan triangles of every face with the origin
    owner = np.repeat(np.arange(len(loops)), sizes - 2)
    first = np.repeat(fvo[:-1], sizes - 2)
    k = np.arange(int(np.sum(sizes - 2))) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    p0, p1, p2 = verts[fv[first]], verts[fv[first + k + 1]], verts[fv[first + k + 2]]
    det = np.einsum("ij,ij->i", p0, np.cross(p1, p2))
    volume = float(det.sum()) / 6.0
    centroid = (det[:, None] * (p0 + p1 + p2)).sum(axis=0) / (24.0 * volume)
    scale = 1.0 / np.cbrt(volume)
    verts = (verts - centroid) * scale
    # unit normals of the faces from their (fan) area vectors
    area = np.zeros((len(loops), 3))
    np.add.at(area, owner, np.cross(p1 - p0, p2 - p0))
    with np.errstate(invalid="ignore", divide="ignore"):  # a face of no area: NaN, refused
        normals = area / np.linalg.norm(area, axis=1)[:, None]
    support = _support(verts, normals)
    reach = float(np.max(np.linalg.norm(verts, axis=1)))
    thinness = float(support.min()) / reach
    if not thinness > FLAT_RTOL:
        raise TemplateError(
            f"{label}: the convex hull of the mesh is flat: its centroid lies {thinness:.1e} "
            f"of its size from a face (more than {FLAT_RTOL:g} is needed); a solid template "
            "needs a volume"
        )
    return ConvexSolid(
        vertices=np.ascontiguousarray(verts),
        face_vertices=fv,
        face_vertex_offsets=fvo,
        normals=np.ascontiguousarray(normals),
        support=support,
    )
