"""Independent check of a 3D packing of convex polyhedra: overlaps and containment.

This module is the oracle that 3D packings will be checked against. It shares
no code with any inserter: it works on plain arrays of vertices (absolute
coordinates, one convex polyhedron per particle) and measures with Qhull
(:class:`scipy.spatial.ConvexHull`, :class:`scipy.spatial.HalfspaceIntersection`)
and HiGHS (:func:`scipy.optimize.linprog`) only.

What is exact and what is tolerance-based
-----------------------------------------
* :func:`separating_gap` is the signed distance from the origin to the
  Minkowski difference ``P - Q``: the Euclidean distance between the two
  polyhedra when they are apart, 0 when they touch, and minus the
  penetration depth (the length of the shortest translation that separates
  them) when they overlap. It is computed in closed form from the convex hull
  of the pairwise vertex differences, without an iterative solver, so it is
  exact up to floating-point rounding.
* :func:`overlap_volume` is the volume of the intersection, computed as the
  convex hull of the vertices of the intersection of the two H-representations.
  It is exact up to rounding, except that an intersection is *flat*
  (volume 0) when a ball of radius ``FLAT_TOL * D`` does not fit in it, ``D``
  being the smaller of the two bounding-box diagonals. That is proven either
  by a slab of width at most ``2 FLAT_TOL D`` that holds the intersection
  (beyond a facet plane of one polyhedron, or the penetration depth), or by a
  largest inscribed ball that HiGHS finds no larger. A flat intersection has
  a volume of at most ``(sqrt(3) pi / 2) FLAT_TOL D**3`` (its width is at
  most ``2 sqrt(3)`` times its inradius, by Steinhagen's theorem, and its
  cross-section at most ``pi D**2 / 4``): 1.4e-11 of the volume of a cube,
  more for flat or elongated particles, in proportion to ``D**3 / volume``.
  This is what makes face-to-face, edge-to-edge and vertex-to-face contacts
  give exactly 0 whatever the rounding in their coordinates.
* :func:`verify_polyhedra` counts a pair as overlapping when its intersection
  volume exceeds ``rel_tol`` times the smaller particle volume, and a particle
  as outside when one of its vertices lies beyond a wall of the box by more than
  ``rel_tol`` times its size (the cube root of its volume). All tolerances are
  relative, so a packing scaled by any factor gives the same report.
* In a walled cylinder (a vertical axis, a side wall, a floor and a lid) a
  convex polyhedron lies inside exactly when all its vertices do, and a
  sphere when ``hypot(centre - axis) + r <= R`` and its z-extent lies between
  the floor and the lid. How far a particle reaches beyond the walls (the
  largest of its radial excess ``hypot - R`` and its excesses below the floor
  and above the lid) is compared with the same ``rel_tol`` times its size as
  in a box. The radial excess is computed with :func:`numpy.hypot`, exact to
  about ``1e-16 R``: a surface the inserter put within ``1e-12`` of the
  particle size of the wall is inside for any ``rel_tol`` above a few
  ``1e-16 R / size``. Before a
  pair is measured, the directions of the separating-axis theorem (the facet
  normals of both and the cross products of an edge of each) are tried on all
  pairs at once: a direction along which the two overlap by at most
  ``2 FLAT_TOL D`` proves the intersection flat by the slab argument above, so
  touching pairs, edge to edge as well as face to face, never reach Qhull.

Every pair computation runs in a frame centred on the first polyhedron and
scaled by a power of two near the particle size, so that the results do not
depend on the length scale and coordinates that are exact in binary stay exact.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError, cKDTree

from regopack.base.errors import ConfigError, GeometryError, PackingError
from regopack.geometry.sphere_volume import lens_volume

__all__ = [
    "FLAT_TOL",
    "SLIVER_TOL",
    "Report3D",
    "overlap_volume",
    "separating_gap",
    "verify_polyhedra",
]

FLAT_TOL = 1e-12
"""Inradius below which an intersection counts as flat, in units of the smaller particle size.

The size of a particle is here the diagonal of its bounding box.
"""

SLIVER_TOL = 1e-11
"""Inradius, in units of the smaller particle size, up to which a Qhull failure means a sliver.

An intersection that a ball of radius ``FLAT_TOL * D`` fits in is measured by
Qhull. Should Qhull fail on it (it was not seen to), the intersection counts
as flat when its inscribed ball is at most ``SLIVER_TOL * D``: the volume
then neglected is at most ``(sqrt(3) pi / 2) SLIVER_TOL D**3``, 1.4e-10 of a
cube's volume. A failure on anything thicker is raised as a
:class:`~regopack.base.errors.GeometryError`.
"""

_LP_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
"""HiGHS tolerances of the largest-inscribed-ball linear program (in the scaled frame)."""

_CHUNK = 2_000_000
"""Number of facet-vertex products evaluated at once by the vectorised separating test."""

_EDGE_BUDGET = 2_000_000
"""Most axis-vertex products the edge directions may cost one pair.

A pair of polyhedra with ``e`` edges and ``v`` vertices (the larger counts of
the two) has ``e**2`` edge cross products to project ``v`` vertices on:
``e**2 v`` grows as the cube of the vertex count (a hull of 200 vertices
costs 7e7, a second of time and 1 GB, where Qhull measures the pair in a few
milliseconds). Pairs above the budget (polyhedra of more than about 60
vertices) go to Qhull directly.
"""

Float = NDArray[np.float64]


# ---------------------------------------------------------------- single polyhedra


def _polyhedron(points: ArrayLike, name: str) -> tuple[Float, ConvexHull]:
    """Return ``points`` as a ``(k, 3)`` float array, and its hull about its bounding-box centre.

    Raises
    ------
    PackingError
        When the array does not have the shape ``(k, 3)`` or holds a non-finite value.
    GeometryError
        When the points are fewer than four or lie in a plane.
    """
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise PackingError(f"{name}: vertices must have the shape (k, 3), not {arr.shape}")
    if not np.isfinite(arr).all():
        raise PackingError(f"{name}: a vertex coordinate is not finite")
    if len(arr) < 4:
        raise GeometryError(f"{name}: a polyhedron needs at least 4 vertices, not {len(arr)}")
    try:
        hull = ConvexHull(arr - _centre(arr))
    except QhullError:
        raise GeometryError(f"{name}: the vertices are flat (they span no volume)") from None
    return arr, hull


def _centre(points: Float) -> Float:
    """Return the centre of the bounding box of ``points``."""
    out: Float = 0.5 * (points.min(axis=0) + points.max(axis=0))
    return out


def _diagonal(points: Float) -> float:
    """Return the diagonal of the bounding box of ``points``."""
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def _power_of_two(length: float) -> float:
    """Return the power of two nearest above ``length`` (dividing by it is exact)."""
    return float(2.0 ** math.ceil(math.log2(length)))


def _frame(p: Float, q: Float) -> tuple[Float, Float, float, float]:
    """Express ``p`` and ``q`` in the frame of a pair computation.

    The frame is centred on the bounding box of ``p`` and scaled by a power
    of two at least as large as both bounding-box diagonals.

    Returns
    -------
    tuple
        ``(p, q, scale, D)``: the two point sets in the frame, the length
        unit of the frame, and the smaller bounding-box diagonal in that unit.
    """
    dp, dq = _diagonal(p), _diagonal(q)
    scale = _power_of_two(max(dp, dq))
    c = _centre(p)
    return (p - c) / scale, (q - c) / scale, scale, min(dp, dq) / scale


# ---------------------------------------------------------------- signed gap


def _triangle_distance(tri: Float) -> Float:
    """Distances from the origin to triangles ``tri`` of shape ``(m, 3, 3)``.

    The closest point of a triangle is either the projection of the origin on
    its plane (when that projection falls inside) or the closest point of one
    of its three edges; each candidate is a point of the triangle.
    """
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    u, v = b - a, c - a
    normal = np.cross(u, v)
    nn = np.einsum("ij,ij->i", normal, normal)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.einsum("ij,ij->i", normal, a) / nn
        foot = along[:, None] * normal - a  # projection of the origin, relative to a
        uu = np.einsum("ij,ij->i", u, u)
        uv = np.einsum("ij,ij->i", u, v)
        vv = np.einsum("ij,ij->i", v, v)
        fu = np.einsum("ij,ij->i", foot, u)
        fv = np.einsum("ij,ij->i", foot, v)
        den = uu * vv - uv * uv
        s = (vv * fu - uv * fv) / den
        t = (uu * fv - uv * fu) / den
        inside = (nn > 0) & (s >= 0) & (t >= 0) & (s + t <= 1)
        plane = np.abs(along) * np.sqrt(nn)

    def segment(p0: Float, p1: Float) -> Float:
        d = p1 - p0
        dd = np.einsum("ij,ij->i", d, d)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.clip(-np.einsum("ij,ij->i", p0, d) / dd, 0.0, 1.0)
        w = np.where(dd > 0, w, 0.0)
        out: Float = np.linalg.norm(p0 + w[:, None] * d, axis=1)
        return out

    edges = np.minimum(np.minimum(segment(a, b), segment(b, c)), segment(c, a))
    out: Float = np.where(inside, plane, edges)
    return out


def _hull_vertices(points: Float) -> Float:
    """Vertices of the convex hull of ``points``."""
    out: Float = points[ConvexHull(points).vertices]
    return out


def _gap(p: Float, q: Float) -> float:
    """Signed distance from the origin to ``hull(p) - hull(q)``, in the units of the input.

    ``p`` and ``q`` are vertices of convex hulls (all their points are used).
    """
    diff = (p[:, None, :] - q[None, :, :]).reshape(-1, 3)
    hull = ConvexHull(diff)
    offset = hull.equations[:, 3]  # n . x + offset <= 0 inside, |n| = 1: offset at the origin
    highest = float(offset.max())
    if highest <= 0.0:
        # the origin is inside: its distance to the boundary is that to the nearest facet plane
        return highest + 0.0  # no negative zero
    # outside: the nearest point lies on a facet whose plane separates the origin
    tri = hull.points[hull.simplices[offset > 0]]
    return float(_triangle_distance(tri).min())


def separating_gap(P: ArrayLike, Q: ArrayLike) -> float:
    """Signed gap between two convex polyhedra given by their vertices.

    The value is the signed distance from the origin to the Minkowski
    difference ``P - Q = {p - q}``, which contains the origin exactly when
    the polyhedra meet:

    * ``> 0``: the polyhedra are apart, and the value is the Euclidean
      distance between them (the largest margin of a plane separating them);
    * ``0``: they touch (a face, an edge or a vertex in contact, no volume shared);
    * ``< 0``: they overlap, and the value is minus the penetration depth,
      the length of the shortest translation of ``Q`` that separates them
      (the overlap of their projections on the best axis).

    The Minkowski difference is the convex hull of the ``k_P * k_Q`` vertex
    differences (of the hull vertices of ``P`` and ``Q``); inside it, the
    distance to its boundary is that to the nearest facet plane; outside, the
    closest point lies on a facet facing the origin and is found in closed form
    on its triangles. No iterative solver is involved: the value is exact up to
    floating-point rounding, and 0 for contacts whose coordinates are exact in
    binary (as for the faces of axis-aligned boxes).

    Parameters
    ----------
    P, Q
        Vertices of the two polyhedra, arrays of shape ``(k, 3)`` in absolute
        coordinates (points inside the hull are allowed and ignored).

    Returns
    -------
    float
        The signed gap, in the units of the coordinates.

    Raises
    ------
    PackingError
        When an array is not ``(k, 3)`` or holds a non-finite value.
    GeometryError
        When a polyhedron has fewer than four vertices or is flat.

    Examples
    --------
    >>> cube = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> separating_gap(cube, cube + (1.5, 0, 0)), separating_gap(cube, cube + (0.75, 0, 0))
    (0.5, -0.25)
    """
    (p, _), (q, _) = _polyhedron(P, "P"), _polyhedron(Q, "Q")
    pn, qn, scale, _ = _frame(p, q)
    return _gap(_hull_vertices(pn), _hull_vertices(qn)) * scale


# ---------------------------------------------------------------- overlap volume


def _face_separation(eq: Float, points: Float) -> float:
    """Largest signed distance by which a facet plane of ``eq`` has all ``points`` beyond it.

    A value ``s >= 0`` proves that the polyhedron of ``eq`` and the hull of
    ``points`` share no volume (they lie on the two closed sides of a plane);
    a value ``s < 0`` confines their intersection to a slab of width ``-s``.
    """
    values = eq[:, :3] @ points.T + eq[:, 3:4]
    return float(values.min(axis=1).max())


def _inscribed_ball(eq: Float) -> tuple[Float, float]:
    """Centre and radius of a largest ball inside ``{x : eq[:, :3] x + eq[:, 3] <= 0}``.

    The centre is found by linear programming (HiGHS); the radius is then
    measured directly at that centre, so it is a true inscribed radius
    whatever the solver's tolerance.
    """
    normals, offset = eq[:, :3], eq[:, 3]
    a_ub = np.column_stack([normals, np.linalg.norm(normals, axis=1)])
    res = linprog(
        c=np.array([0.0, 0.0, 0.0, -1.0]),
        A_ub=a_ub,
        b_ub=-offset,
        bounds=[(-2.0, 2.0)] * 3 + [(None, 1.0)],
        method="highs",
        options=_LP_OPTIONS,
    )
    if res.x is None:
        raise GeometryError(f"the inscribed-ball program failed: {res.message}")
    centre = np.asarray(res.x[:3], dtype=np.float64)
    radius = -float((normals @ centre + offset).max())
    return centre, radius


def _overlap(p: Float, q: Float, small: float) -> float:
    """Intersection volume of ``hull(p)`` and ``hull(q)``, in the units of the input.

    ``small`` is the smaller bounding-box diagonal (see :data:`FLAT_TOL`);
    the input is expected in a frame of :func:`_frame` (sizes near 1).
    """
    hp, hq = ConvexHull(p), ConvexHull(q)
    pv, qv = p[hp.vertices], q[hq.vertices]
    # The intersection lies in a slab as wide as the penetration along any facet
    # normal, and the penetration depth bounds that along every direction; a
    # ball of radius r needs a width of 2 r: when either is at most 2 FLAT_TOL D,
    # the intersection is flat. Both tests are cheaper than the program below.
    flat = FLAT_TOL * small
    face = max(_face_separation(hp.equations, qv), _face_separation(hq.equations, pv))
    if face >= -2.0 * flat or _gap(pv, qv) >= -2.0 * flat:
        return 0.0
    eq = np.vstack([hp.equations, hq.equations])
    centre, radius = _inscribed_ball(eq)
    if radius <= flat:
        return 0.0
    try:
        corners = HalfspaceIntersection(eq, centre).intersections
        return float(ConvexHull(corners).volume)
    except QhullError:
        # the centre lies inside by more than FLAT_TOL D, so Qhull should not fail
        if radius > SLIVER_TOL * small:
            raise GeometryError(
                f"Qhull failed on an intersection of inradius {radius:.3g} "
                f"(the smaller particle's size being {small:.3g})"
            ) from None
        return 0.0


def overlap_volume(P: ArrayLike, Q: ArrayLike) -> float:
    """Volume of the intersection of two convex polyhedra given by their vertices.

    The intersection is the set of points satisfying the facet inequalities
    of both hulls (their H-representations, from Qhull; coplanar facets need
    not be merged for a volume). When a facet plane of one polyhedron leaves
    the other entirely on its outer side, or the penetration depth (see
    :func:`separating_gap`) is at most ``2 * FLAT_TOL * D``, the volume is 0.
    Otherwise a largest inscribed ball is found by linear programming; when
    its radius is at most ``FLAT_TOL * D`` the intersection is flat and the
    volume is 0 (see the module docstring for the bound on what is neglected);
    else its centre is a strictly interior point from which
    :class:`~scipy.spatial.HalfspaceIntersection` finds the vertices of the
    intersection, whose convex hull gives the volume. ``D`` is the smaller of
    the two bounding-box diagonals. Should Qhull fail there, the intersection
    counts as flat if its inscribed ball is at most ``SLIVER_TOL * D``, and
    the failure is raised otherwise.

    Touching polyhedra (face to face, edge to edge, vertex to face) give 0,
    never an exception.

    Parameters
    ----------
    P, Q
        Vertices of the two polyhedra, arrays of shape ``(k, 3)`` in absolute
        coordinates.

    Returns
    -------
    float
        The volume shared by the two polyhedra, in the cube of the units of the coordinates.

    Raises
    ------
    PackingError, GeometryError
        As :func:`separating_gap` does.

    Examples
    --------
    >>> cube = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> overlap_volume(cube, cube + (0.75, 0.5, 0)), overlap_volume(cube, cube + (1, 1, 0))
    (0.125, 0.0)
    """
    (p, _), (q, _) = _polyhedron(P, "P"), _polyhedron(Q, "Q")
    pn, qn, scale, small = _frame(p, q)
    return _overlap(pn, qn, small) * scale**3


# ---------------------------------------------------------------- a whole packing


@dataclass(frozen=True)
class Report3D:
    """Outcome of :func:`verify_polyhedra`; true when the packing is valid.

    Attributes
    ----------
    ok
        True when no pair overlaps and no particle leaves the box (beyond ``rel_tol``).
    n_checked
        Number of polyhedra.
    n_candidate_pairs
        Pairs (with their periodic image) whose bounding boxes overlap.
    n_overlapping_pairs
        Pairs whose intersection volume exceeds ``rel_tol`` times the smaller volume.
    overlapping_pairs
        Those pairs as ``(i, j)`` with ``i <= j``, sorted (``i == j`` is a
        particle overlapping its own periodic image).
    worst_overlap_fraction
        The largest intersection volume of any pair as a fraction of the smaller
        of the two volumes (0.0 when no pair shares volume), whether or not it
        exceeds ``rel_tol``.
    worst_pair
        The pair ``(i, j)`` of :attr:`worst_overlap_fraction`, or ``None`` when it is 0.
    n_outside
        Particles with a vertex beyond a wall by more than ``rel_tol`` times
        their size (the cube root of their volume); always 0 in a periodic box.
    worst_outside
        ``(i, distance / size)`` for the particle reaching farthest beyond a wall,
        or ``None`` when none does.
    periodic
        Whether the box was periodic.
    rel_tol
        Tolerance used.
    kind
        What was checked, as the report names it: ``"convex polyhedra"`` or
        ``"spheres"``.
    domain
        The walls checked: ``"box"``, or ``"cylinder"`` (a side wall, a floor and a lid).
    """

    ok: bool
    n_checked: int
    n_candidate_pairs: int
    n_overlapping_pairs: int
    overlapping_pairs: tuple[tuple[int, int], ...]
    worst_overlap_fraction: float
    worst_pair: tuple[int, int] | None
    n_outside: int
    worst_outside: tuple[int, float] | None
    periodic: bool
    rel_tol: float
    kind: str = "convex polyhedra"
    domain: str = "box"

    def __bool__(self) -> bool:
        """Return whether the packing is valid."""
        return self.ok

    def __str__(self) -> str:
        box = "a periodic box" if self.periodic else f"a walled {self.domain}"
        status = "valid" if self.ok else "INVALID"
        parts = [
            f"Checked {self.n_checked} {self.kind} in {box} "
            f"({self.n_candidate_pairs} pairs with overlapping bounding boxes, "
            f"rel_tol {self.rel_tol:g}): {status}."
        ]
        parts.append(f"{self.n_overlapping_pairs} pairs overlap beyond rel_tol;")
        if self.worst_pair is not None:
            i, j = self.worst_pair
            parts.append(
                f"the largest overlap, particles {i} and {j}, is "
                f"{self.worst_overlap_fraction:.3g} of the smaller volume."
            )
        else:
            parts.append("no two particles share volume.")
        if self.periodic:
            parts.append("Containment is not required in a periodic box.")
        elif self.worst_outside is not None:
            k, frac = self.worst_outside
            parts.append(
                f"{self.n_outside} particles leave the {self.domain} beyond rel_tol; the "
                f"farthest, "
                f"particle {k}, by {frac:.3g} of its size."
            )
        else:
            parts.append(f"Every particle lies inside the {self.domain}.")
        return " ".join(parts)


def _split(
    vertices: ArrayLike | Sequence[ArrayLike], offsets: ArrayLike | None
) -> list[tuple[Float, ConvexHull]]:
    """Per-particle vertex arrays and hulls, from a list of arrays or flat vertices and offsets."""
    if offsets is None:
        if isinstance(vertices, np.ndarray) and vertices.ndim != 3:
            raise PackingError("flat vertices need offsets; or pass a list of (k, 3) arrays")
        return [_polyhedron(v, f"particle {k}") for k, v in enumerate(vertices)]  # type: ignore[arg-type]
    flat = np.asarray(vertices, dtype=np.float64)
    off = np.asarray(offsets)
    if flat.ndim != 2 or flat.shape[1] != 3:
        raise PackingError(f"vertices must have the shape (V, 3), not {flat.shape}")
    if off.ndim != 1 or len(off) < 1 or not np.issubdtype(off.dtype, np.integer):
        raise PackingError("offsets must be a 1-D integer array of length n + 1")
    if off[0] != 0 or off[-1] != len(flat) or np.any(np.diff(off) < 0):
        raise PackingError("offsets must rise from 0 to the number of vertices")
    bounds = zip(off[:-1].tolist(), off[1:].tolist(), strict=True)
    return [_polyhedron(flat[a:b], f"particle {k}") for k, (a, b) in enumerate(bounds)]


def _box(lo: ArrayLike, hi: ArrayLike) -> tuple[Float, Float]:
    """Validate the box corners."""
    blo = np.asarray(lo, dtype=np.float64).reshape(-1)
    bhi = np.asarray(hi, dtype=np.float64).reshape(-1)
    if blo.shape != (3,) or bhi.shape != (3,):
        raise ConfigError("box_lo and box_hi must be three coordinates each")
    if not (np.isfinite(blo).all() and np.isfinite(bhi).all() and np.all(bhi > blo)):
        raise ConfigError(f"box from {blo.tolist()} to {bhi.tolist()}: need finite lo < hi")
    return blo, bhi


def _cylinder(cylinder: ArrayLike | None, periodic: bool) -> tuple[float, float, float] | None:
    """Validate the axis and radius ``(cx, cy, radius)`` of a walled cylinder (or ``None``)."""
    if cylinder is None:
        return None
    c = np.asarray(cylinder, dtype=np.float64).reshape(-1)
    if c.shape != (3,) or not np.isfinite(c).all() or not c[2] > 0:
        raise ConfigError(
            f"cylinder {c.tolist()}: need the axis and radius (cx, cy, radius), finite, radius > 0"
        )
    if periodic:
        raise ConfigError("a cylinder has walls: it cannot be periodic")
    return float(c[0]), float(c[1]), float(c[2])


def _radial_excess(x: Float, y: Float, cylinder: tuple[float, float, float]) -> Float:
    """Distance of the points ``(x, y)`` beyond the circle of ``cylinder`` (negative inside)."""
    cx, cy, rad = cylinder
    out: Float = np.hypot(x - cx, y - cy) - rad
    return out


def _hull_edges(hull: ConvexHull) -> Float:
    """Directions of the edges of ``hull`` (``(e, 3)``), each once.

    Qhull triangulates the facets; the diagonals inside a flat facet (whose
    two triangles share a plane) are left out. An edge left in by rounding
    only adds a direction to test, which is harmless.
    """
    simplices, neighbours, normals = hull.simplices, hull.neighbors, hull.equations[:, :3]
    rows, opposite = np.nonzero(neighbours > np.arange(len(simplices))[:, None])
    other = neighbours[rows, opposite]
    sharp = np.einsum("ij,ij->i", normals[rows], normals[other]) < 1.0 - 1e-12
    rows, opposite = rows[sharp], opposite[sharp]
    a = simplices[rows, (opposite + 1) % 3]
    b = simplices[rows, (opposite + 2) % 3]
    points = hull.points
    out: Float = points[b] - points[a]
    return out


def _padded_edges(hulls: list[ConvexHull]) -> tuple[Float, NDArray[np.int64]]:
    """``(n, e, 3)`` edge directions of every hull, padded with zero vectors, and their counts."""
    edges = [_hull_edges(h) for h in hulls]
    out = np.zeros((len(hulls), max((len(e) for e in edges), default=1), 3))
    for k, e in enumerate(edges):
        out[k, : len(e)] = e
    return out, np.array([len(e) for e in edges], dtype=np.int64)


class _Particles:
    """Per-particle data of :func:`verify_polyhedra`, padded into rectangular arrays.

    ``corners[i]`` holds the hull vertices of particle ``i`` in absolute
    coordinates (padded by repeating the first), ``normals[i]`` and
    ``offsets[i]`` its facet planes in its own frame (centred on ``centre[i]``;
    padded planes never separate).
    """

    def __init__(self, polyhedra: list[tuple[Float, ConvexHull]]) -> None:
        n = len(polyhedra)
        parts = [v for v, _ in polyhedra]
        hulls = [h for _, h in polyhedra]
        nv = max((len(h.vertices) for h in hulls), default=1)
        nf = max((len(h.equations) for h in hulls), default=1)
        self.n_vertices = np.array([len(h.vertices) for h in hulls], dtype=np.int64)
        self.corners = np.empty((n, nv, 3))
        self.normals = np.zeros((n, nf, 3))
        self.offsets = np.full((n, nf), -np.inf)
        for k, (v, h) in enumerate(zip(parts, hulls, strict=True)):
            cv = v[h.vertices]
            self.corners[k, : len(cv)] = cv
            self.corners[k, len(cv) :] = cv[0]
            self.normals[k, : len(h.equations)] = h.equations[:, :3]
            self.offsets[k, : len(h.equations)] = h.equations[:, 3]
        self.edges, self.n_edges = _padded_edges(hulls)
        self.volume = np.array([h.volume for h in hulls])
        self.centre = np.array([_centre(v) for v in parts]).reshape(n, 3)
        self.diagonal = np.array([_diagonal(v) for v in parts])
        self.radius = np.array(
            [np.linalg.norm(v - c, axis=1).max() for v, c in zip(parts, self.centre, strict=True)]
        )
        self.lower = np.array([v.min(axis=0) for v in parts]).reshape(n, 3)
        self.upper = np.array([v.max(axis=0) for v in parts]).reshape(n, 3)

    def hull(self, k: int) -> Float:
        """Hull vertices of particle ``k``, absolute coordinates."""
        out: Float = self.corners[k, : self.n_vertices[k]]
        return out


def _image_shifts(reach: float, side: Float) -> Float:
    """Periodic image shifts, in units of the box sides, that can bring a pair within ``reach``.

    Two centres wrapped into the box lie less than a side apart along each
    axis, so shifts of at most ``ceil(reach / side)`` sides (at least one)
    find every pair closer than ``reach``: the 27 shifts of ``-1, 0, 1`` when
    no two particles reach across a side. The list is symmetric (shift ``k``
    and ``-k`` at ``len - 1 - k``), its middle entry no shift.
    """
    m = [max(1, math.ceil(reach / s)) for s in side]
    axes = [np.arange(-k, k + 1, dtype=np.float64) for k in m]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _candidates(
    parts: _Particles, lo: Float, hi: Float, periodic: bool
) -> tuple[NDArray[np.int64], NDArray[np.int64], Float]:
    """Pairs ``(i, j, t)`` whose bounding boxes overlap when ``j`` is translated by ``t``.

    ``i < j``, or ``i == j`` with a non-zero ``t`` (a particle and its own
    image, each such contact listed once). Without periodicity ``t = 0``.
    A k-d tree on the centres finds the pairs whose circumscribed spheres
    (about the bounding-box centres) meet; their bounding boxes are then compared.
    """
    n = len(parts.volume)
    reach = parts.radius * (1.0 + 1e-9)
    shifts = np.zeros((1, 3))
    if periodic:
        side = hi - lo
        wrap = np.floor((parts.centre - lo) / side)
        base = parts.centre - wrap * side
        halo = 2.0 * float(reach.max())
        shifts = _image_shifts(halo, side)
        images = (base[None, :, :] + shifts[:, None, :] * side).reshape(-1, 3)
        # only the images within reach of the box can be within reach of a wrapped centre
        index = np.flatnonzero(np.all((images >= lo - halo) & (images <= hi + halo), axis=1))
        images = images[index]
    else:
        wrap = np.zeros((n, 3))
        base = parts.centre
        images = base
        index = np.arange(n, dtype=np.int64)
    tree = cKDTree(images)
    found = tree.query_ball_point(base, reach + reach.max(), return_sorted=False)
    counts = np.fromiter((len(f) for f in found), dtype=np.int64, count=n)
    i = np.repeat(np.arange(n, dtype=np.int64), counts)
    hit = (
        index[np.concatenate([np.asarray(f, dtype=np.int64) for f in found])]
        if counts.sum()
        else np.zeros(0, dtype=np.int64)
    )
    j, image = hit % n, hit // n
    keep = (j > i) | ((j == i) & (image > len(shifts) // 2))
    i, j, image = i[keep], j[keep], image[keep]
    if periodic:
        t = (shifts[image] + wrap[i] - wrap[j]) * (hi - lo)
    else:
        t = np.zeros((len(i), 3))
    near = np.linalg.norm(parts.centre[j] + t - parts.centre[i], axis=1) <= reach[i] + reach[j]
    i, j, t = i[near], j[near], t[near]
    boxes = np.all(
        (parts.lower[i] <= parts.upper[j] + t) & (parts.lower[j] + t <= parts.upper[i]), axis=1
    )
    return i[boxes], j[boxes], t[boxes]


def _face_separations(
    parts: _Particles, i: NDArray[np.int64], j: NDArray[np.int64], t: Float
) -> Float:
    """:func:`_face_separation` of pairs ``(i, j + t)``, over the facets of both.

    Each side is evaluated in the frame of the particle whose planes are used,
    from the absolute vertex coordinates, so that exact contacts stay exact.
    """
    out = np.full(len(i), -np.inf)
    per_pair = parts.normals.shape[1] * parts.corners.shape[1]
    step = max(1, _CHUNK // per_pair)
    for a in range(0, len(i), step):
        s = slice(a, a + step)
        ii, jj, tt = i[s], j[s], t[s]
        for own, other, shift in ((ii, jj, tt), (jj, ii, -tt)):
            pts = (parts.corners[other] + shift[:, None, :]) - parts.centre[own][:, None, :]
            values = np.einsum("pfk,pvk->pfv", parts.normals[own], pts).min(axis=2)
            out[s] = np.maximum(out[s], (values + parts.offsets[own]).max(axis=1))
    return out


def _edge_separations(
    parts: _Particles, i: NDArray[np.int64], j: NDArray[np.int64], t: Float
) -> Float:
    """Largest separation of pairs ``(i, j + t)`` along the cross products of their edges.

    Along a unit direction ``u`` the two hulls' projections are apart by
    ``s(u) = max(min_j - max_i, min_i - max_j)``; ``s >= 0`` proves that they
    share no volume, and ``s < 0`` confines their intersection to a slab of
    width ``-s``. With the facet normals of both
    (:func:`_face_separations`), the cross products of an edge of each are
    the directions of the separating-axis theorem for two convex polyhedra:
    the larger of the two tests is the negative of the penetration depth
    (:func:`separating_gap`), up to rounding. Evaluated in the frame of
    particle ``i`` from the absolute coordinates.

    A pair whose directions cost more than :data:`_EDGE_BUDGET` gets ``-inf``
    (no proof: Qhull measures it). The others are taken largest first, in
    chunks padded to the counts of their largest pair only, so that a few
    polyhedra of many vertices do not pad every pair.
    """
    out = np.full(len(i), -np.inf)
    ne = np.maximum(parts.n_edges[i], parts.n_edges[j])
    nv = np.maximum(parts.n_vertices[i], parts.n_vertices[j])
    cheap = np.flatnonzero(ne * ne * nv <= _EDGE_BUDGET)
    order = cheap[np.argsort(-ne[cheap], kind="stable")]
    # the most vertices of any pair from here on (the edges fall along ``order``)
    vertices = np.maximum.accumulate(nv[order][::-1])[::-1]
    a = 0
    while a < len(order):
        me, mv = int(ne[order[a]]), int(vertices[a])
        step = max(1, _CHUNK // (me * me * mv))
        k = order[a : a + step]
        a += step
        ii, jj, tt = i[k], j[k], t[k]
        axes = np.cross(parts.edges[ii, :me][:, :, None, :], parts.edges[jj, :me][:, None, :, :])
        axes = axes.reshape(len(k), me * me, 3)
        length = np.linalg.norm(axes, axis=2)
        valid = length > 0.0
        axes = axes / np.where(valid, length, 1.0)[:, :, None]
        # the corners are padded by repeating the first: mv of them hold every vertex
        own = parts.corners[ii, :mv] - parts.centre[ii][:, None, :]
        other = (parts.corners[jj, :mv] + tt[:, None, :]) - parts.centre[ii][:, None, :]
        pi = axes @ own.transpose(0, 2, 1)
        pj = axes @ other.transpose(0, 2, 1)
        sep = np.maximum(pj.min(axis=2) - pi.max(axis=2), pi.min(axis=2) - pj.max(axis=2))
        out[k] = np.where(valid, sep, -np.inf).max(axis=1)
    return out


def verify_polyhedra(
    vertices: ArrayLike | Sequence[ArrayLike],
    offsets: ArrayLike | None,
    box_lo: ArrayLike,
    box_hi: ArrayLike,
    periodic: bool = False,
    rel_tol: float = 1e-9,
    cylinder: ArrayLike | None = None,
) -> Report3D:
    """Check that convex polyhedra do not overlap and stay inside a box or a cylinder.

    Every pair whose bounding boxes overlap is measured: pairs that a facet
    plane of one of them separates share no volume; the others get their
    intersection volume from :func:`overlap_volume`'s computation (the same
    frame, the same flat tolerance). In a periodic box the second particle
    of a pair is taken at each of its images within reach of the first
    (centres wrapped into the box; the 27 nearest images when no particle
    is wider than half a side, more in a box thinner than its particles,
    and a particle against its own images), and containment is not checked.

    Parameters
    ----------
    vertices
        Either a list of ``(k_i, 3)`` arrays, one per particle (or an
        ``(n, k, 3)`` array), or a flat ``(V, 3)`` array of all vertices (then
        with ``offsets``), in absolute coordinates. Each particle is the
        convex hull of its vertices.
    offsets
        ``(n + 1,)`` integers: particle ``i`` owns the flat vertices
        ``offsets[i]:offsets[i + 1]``; ``None`` with a list of arrays.
    box_lo, box_hi
        Opposite corners of the box.
    periodic
        Whether the box is periodic in all three directions.
    rel_tol
        A pair violates when its intersection volume exceeds ``rel_tol`` times
        the smaller of the two volumes; a particle violates when a vertex lies
        beyond a wall by more than ``rel_tol`` times the cube root of its volume.
    cylinder
        ``(cx, cy, radius)``: the walls are then those of the cylinder of this
        vertical axis and radius, its floor at ``box_lo[2]`` and its lid at
        ``box_hi[2]`` (``box_lo``, ``box_hi`` being its bounding box). A
        polyhedron lies inside when all its vertices do.

    Returns
    -------
    Report3D
        The outcome; true when the packing is valid.

    Raises
    ------
    ConfigError
        When ``rel_tol`` is negative or not finite, or the box or the cylinder is malformed.
    PackingError
        When the arrays are malformed.
    GeometryError
        When a particle is flat or has fewer than four vertices.

    Examples
    --------
    >>> cube = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> report = verify_polyhedra([cube, cube + (1, 0, 0)], None, (0, 0, 0), (2, 1, 1))
    >>> bool(report), report.n_candidate_pairs, report.worst_overlap_fraction
    (True, 1, 0.0)
    """
    if not (math.isfinite(rel_tol) and rel_tol >= 0):
        raise ConfigError(f"rel_tol = {rel_tol!r}: must be a finite number >= 0")
    lo, hi = _box(box_lo, box_hi)
    cyl = _cylinder(cylinder, periodic)
    domain = "box" if cyl is None else "cylinder"
    raw = _split(vertices, offsets)
    n = len(raw)
    if n == 0:
        return Report3D(True, 0, 0, 0, (), 0.0, None, 0, None, periodic, rel_tol, domain=domain)
    parts = _Particles(raw)
    i, j, t = _candidates(parts, lo, hi, periodic)
    # what _overlap's first test would find, for all pairs at once
    small = np.minimum(parts.diagonal[i], parts.diagonal[j])
    measure = np.flatnonzero(_face_separations(parts, i, j, t) < -2.0 * FLAT_TOL * small)
    # the edge directions settle the touching pairs that no facet plane separates
    edges = _edge_separations(parts, i[measure], j[measure], t[measure])
    measure = measure[edges < -2.0 * FLAT_TOL * small[measure]]
    frac = np.zeros(len(i))
    for k in measure.tolist():
        a, b = int(i[k]), int(j[k])
        p, q = parts.hull(a), parts.hull(b) + t[k]
        pn, qn, scale, size = _frame(p, q)
        frac[k] = _overlap(pn, qn, size) * scale**3 / min(parts.volume[a], parts.volume[b])
    bad = frac > rel_tol
    pairs = tuple(sorted({(int(a), int(b)) for a, b in zip(i[bad], j[bad], strict=True)}))
    worst_pair: tuple[int, int] | None = None
    worst = 0.0
    if len(frac) and frac.max() > 0.0:
        k = int(np.argmax(frac))
        worst, worst_pair = float(frac[k]), (int(i[k]), int(j[k]))

    n_outside, worst_outside = 0, None
    if not periodic:
        if cyl is None:
            beyond = np.maximum(lo - parts.lower, parts.upper - hi).max(axis=1)
        else:
            # all the vertices (the padding repeats one): the hull is inside iff they are
            radial = _radial_excess(parts.corners[:, :, 0], parts.corners[:, :, 1], cyl)
            floor_lid = np.maximum(lo[2] - parts.lower[:, 2], parts.upper[:, 2] - hi[2])
            beyond = np.maximum(radial.max(axis=1), floor_lid)
        rel = np.maximum(beyond, 0.0) / np.cbrt(parts.volume)
        out = rel > rel_tol
        n_outside = int(np.count_nonzero(out))
        if rel.max() > 0.0:
            k = int(np.argmax(rel))
            worst_outside = (k, float(rel[k]))
    return Report3D(
        ok=not pairs and n_outside == 0,
        n_checked=n,
        n_candidate_pairs=len(i),
        n_overlapping_pairs=len(pairs),
        overlapping_pairs=pairs,
        worst_overlap_fraction=worst,
        worst_pair=worst_pair,
        n_outside=n_outside,
        worst_outside=worst_outside,
        periodic=periodic,
        rel_tol=rel_tol,
        domain=domain,
    )


# ---------------------------------------------------------------- spheres


def verify_spheres(
    centres: ArrayLike,
    radii: ArrayLike,
    box_lo: ArrayLike,
    box_hi: ArrayLike,
    periodic: bool = False,
    rel_tol: float = 1e-9,
    cylinder: ArrayLike | None = None,
) -> Report3D:
    """Check that spheres do not overlap and stay inside a box or a cylinder.

    Pairs closer than the sum of their radii (every periodic image, in a
    periodic box, found by a k-d tree over the wrapped centres) share the
    volume of a lens (:func:`lens_volume`); a pair overlaps when that volume
    exceeds ``rel_tol`` times the smaller ball's. A sphere leaves a walled box
    when it reaches beyond a wall by more than ``rel_tol`` times the cube
    root of its volume. With ``cylinder = (cx, cy, radius)`` the walls are
    those of the cylinder of this vertical axis and radius between the floor
    ``box_lo[2]`` and the lid ``box_hi[2]``: a sphere reaches
    ``hypot(centre - axis) + r - radius`` beyond the side wall.

    Examples
    --------
    >>> verify_spheres([[0, 0, 0], [2, 0, 0]], [1, 1], [-1, -1, -1], [3, 1, 1]).ok
    True
    >>> verify_spheres([[0, 0, 0], [1.9, 0, 0]], [1, 1], [-1, -1, -1], [3, 1, 1]).ok
    False
    """
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    r = np.asarray(radii, dtype=np.float64).reshape(-1)
    lo = np.asarray(box_lo, dtype=np.float64).reshape(3)
    hi = np.asarray(box_hi, dtype=np.float64).reshape(3)
    if r.shape[0] != c.shape[0]:
        raise ConfigError(f"{c.shape[0]} centres but {r.shape[0]} radii")
    if not (np.isfinite(c).all() and np.isfinite(r).all() and np.all(r > 0)):
        raise ConfigError("sphere centres and radii must be finite, radii positive")
    cyl = _cylinder(cylinder, periodic)
    n = c.shape[0]
    volume = 4.0 / 3.0 * math.pi * r**3
    rmax = float(r.max()) if n else 0.0
    if periodic:
        period = hi - lo
        wrapped = np.mod(c - lo, period)
        wrapped[wrapped >= period] = 0.0
        tree = cKDTree(wrapped, boxsize=period)
    else:
        period = np.zeros(3)
        wrapped = c
        tree = cKDTree(c)
    pairs = tree.query_pairs(2.0 * rmax) if n > 1 else set()
    candidates = 0
    overlapping: list[tuple[int, int]] = []
    worst = 0.0
    worst_pair: tuple[int, int] | None = None

    def record(i: int, j: int, d: float) -> None:
        nonlocal worst, worst_pair, candidates
        candidates += 1
        frac = lens_volume(float(r[i]), float(r[j]), d) / float(min(volume[i], volume[j]))
        if frac > worst:
            worst, worst_pair = frac, (min(i, j), max(i, j))
        if frac > rel_tol:
            overlapping.append((min(i, j), max(i, j)))

    for i, j in sorted(pairs):
        delta = wrapped[j] - wrapped[i]
        if periodic:
            delta = delta - period * np.round(delta / period)
        d = float(np.linalg.norm(delta))
        if d < r[i] + r[j]:
            record(i, j, d)
    if periodic:  # a sphere wider than the box overlaps its own images
        for i in np.flatnonzero(2.0 * r > period.min()):
            record(int(i), int(i), float(period.min()))
    outside = 0
    worst_out: tuple[int, float] | None = None
    if not periodic and n:
        size = np.cbrt(volume)
        if cyl is None:
            reach = np.maximum(
                (lo - (c - r[:, None])).max(axis=1), ((c + r[:, None]) - hi).max(axis=1)
            )
        else:
            radial = _radial_excess(c[:, 0], c[:, 1], cyl) + r
            reach = np.maximum(radial, np.maximum(lo[2] - (c[:, 2] - r), (c[:, 2] + r) - hi[2]))
        frac_out = reach / size
        out = frac_out > rel_tol
        outside = int(out.sum())
        k = int(np.argmax(frac_out))
        if frac_out[k] > 0:
            worst_out = (k, float(frac_out[k]))
    return Report3D(
        ok=not overlapping and outside == 0,
        n_checked=n,
        n_candidate_pairs=candidates,
        n_overlapping_pairs=len(overlapping),
        overlapping_pairs=tuple(sorted(overlapping)),
        worst_overlap_fraction=worst,
        worst_pair=worst_pair,
        n_outside=outside,
        worst_outside=worst_out,
        periodic=periodic,
        rel_tol=rel_tol,
        kind="spheres",
        domain="box" if cyl is None else "cylinder",
    )
