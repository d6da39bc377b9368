"""The volume of spheres and convex polyhedra inside a vertical cylinder, for the interior fraction.

A solid is cut into horizontal slices: a sphere's slice is a disk, whose
area inside the cylinder's circle is that of two disks' lens
(:func:`disk_disk_area`, closed form); a convex polyhedron's slice is a convex
polygon, whose area inside the circle is exact (:func:`polygons_disk_area`,
triangles and circular sectors about the circle's centre, as
:func:`regopack.geometry.domain.polygon_disk_area`, for many polygons at once).
The slices' areas are integrated over height by Gauss–Legendre quadrature
between breakpoints, the heights where the area is not smooth:

* a sphere's: where its slice circle becomes tangent to the wall circle,
  from inside or outside (``rho(z) = |R - d|`` and ``rho(z) = R + d``, ``d``
  the centre's distance from the axis), and its poles;
* a polyhedron's: its vertices' heights (its slice's corners run along its
  edges linearly between them), where an edge crosses the wall circle (a
  slice corner enters the disk) and where a face's slice line is tangent to
  the circle.

Between two breakpoints the area is analytic in the height, but it may
behave like ``(z - a)^(k/2)`` at the ends (a lens near tangency, a slice
near a pole). Every interval is mapped by ``z = a + (b - a)(3u^2 - 2u^3)``,
which makes these ends smooth in ``u``, and integrated with
:data:`GL_NODES` Gauss–Legendre nodes; an interval whose integral differs
from the sum of its two halves' by more than its share of
``REL_TOL x (the solid's volume)`` is split and integrated again (at most
:data:`MAX_DEPTH` times). The volume of each solid in the cylinder is so
accurate to about ``1e-11`` of the solid's volume (the tests hold it to
``1e-10`` against closed forms and a 10-million-point Monte Carlo estimate).
The arithmetic works about the wall circle's centre: a slice a distance
``R`` from the axis loses about ``1e-16 R / size`` of its area to rounding,
still below ``1e-12`` for a cylinder a thousand particle sizes wide.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull

__all__ = [
    "GL_NODES",
    "MAX_DEPTH",
    "REL_TOL",
    "disk_disk_area",
    "polygons_disk_area",
    "polyhedra_in_cylinder",
    "spheres_in_cylinder",
]

Float = NDArray[np.float64]
Int = NDArray[np.int64]

GL_NODES = 10
"""Gauss–Legendre nodes per interval between breakpoints."""

REL_TOL = 1e-12
"""Target error of a solid's volume in the cylinder, as a fraction of the solid's volume."""

MAX_DEPTH = 20
"""Most times an interval is halved."""

NOISE = 256 * np.finfo(np.float64).eps
"""Rounding of a slice's area, in units of the wall radius times the solid's width.

The areas are sums of triangles and sectors about the circle's centre: a
slice near a wall far from the axis is the small difference of terms of the
order of ``R x width``. An interval's tolerance is never below that noise
times its length, so that rounding never splits it again and again.
"""

_X, _W = np.polynomial.legendre.leggauss(GL_NODES)
_U = 0.5 * (_X + 1.0)
_S = _U * _U * (3.0 - 2.0 * _U)  # the smoothing map of [0, 1] onto itself
_WS = 0.5 * _W * 6.0 * _U * (1.0 - _U)  # the weights times the map's derivative

FLAT = 1e-13
"""Two triangles of a hull are one flat face when the corners of either lie within this
fraction of the solid's width of the other's plane (a fold below it changes the slices
by less than about this fraction of the solid's volume)."""

_CHUNK = 1 << 21
"""Slice corners evaluated at once (queries times edges) for polyhedra."""


# ---------------------------------------------------------------- slice areas


def _t_minus_sin(t: Float) -> Float:
    """``t - sin(t)`` for ``t`` in ``[0, 2 pi]``, without cancellation near 0."""
    t2 = t * t
    series = t * t2 / 6.0 * (1 - t2 / 20 * (1 - t2 / 42 * (1 - t2 / 72 * (1 - t2 / 110))))
    out: Float = np.where(t < 0.5, series, t - np.sin(t))
    return out


def disk_disk_area(r1: ArrayLike, r2: ArrayLike, gap: ArrayLike) -> Float:
    """Area shared by two disks of radii ``r1`` and ``r2`` (broadcast together).

    ``gap`` is the distance of the centres less ``r2`` (``d - r2``): passing it
    rather than ``d`` keeps the area of a small disk near the edge of a large
    one accurate (``d - r2`` is computed once, where ``d`` is measured). Each
    segment is ``r^2 (2a - sin 2a) / 2`` with the half-angle ``a`` from
    :func:`numpy.arctan2` and ``2a - sin 2a`` by its series when small.

    Examples
    --------
    >>> abs(float(disk_disk_area(1.0, 1.0, 0.0)) - (2 * math.pi / 3 - math.sqrt(3) / 2)) < 1e-15
    True
    >>> float(disk_disk_area(1.0, 3.0, -2.5)) == math.pi
    True
    """
    a, b, e = np.broadcast_arrays(
        np.asarray(r1, dtype=np.float64),
        np.asarray(r2, dtype=np.float64),
        np.asarray(gap, dtype=np.float64),
    )
    d = e + b
    out = np.zeros(a.shape)
    first = e + a <= 0.0  # disk 1 inside disk 2 (d + r1 <= r2)
    second = d + b <= a  # disk 2 inside disk 1
    apart = e >= a  # d >= r1 + r2
    out = np.where(first, math.pi * a * a, out)
    out = np.where(second & ~first, math.pi * b * b, out)
    part = ~(first | second | apart)
    if part.any():
        ap, bp, ep, dp = a[part], b[part], e[part], d[part]
        # distance from disk 1's centre to the chord, towards disk 2: (d^2 + r1^2 - r2^2) / 2d
        x1 = (ep * (dp + bp) + ap * ap) / (2.0 * dp)
        x2 = dp - x1
        h = np.sqrt(np.maximum((ap - x1) * (ap + x1), 0.0))
        s1 = 0.5 * ap * ap * _t_minus_sin(2.0 * np.arctan2(h, x1))
        s2 = 0.5 * bp * bp * _t_minus_sin(2.0 * np.arctan2(h, x2))
        out[part] = s1 + s2
    return out


def polygons_disk_area(corners: ArrayLike, center: Sequence[float], radius: float) -> Float:
    """Areas of convex or simple polygons inside a disk, exactly, many at once.

    ``corners`` is ``(m, k, 2)``: ``m`` polygons of ``k`` corners each in
    order (a shorter polygon repeats a corner: a zero-length edge adds
    nothing). The result is as :func:`regopack.geometry.domain.polygon_disk_area`
    for each (up to rounding): each edge, with the disk's centre, makes a
    triangle, which meets the disk in a triangle (the part of the edge inside)
    and circular sectors (the parts outside), whose signed areas add up.

    Examples
    --------
    >>> square = [[(-2, -2), (2, -2), (2, 2), (-2, 2)], [(0, 0), (2, 0), (2, 2), (0, 2)]]
    >>> np.round(polygons_disk_area(square, (0, 0), 1.0) / math.pi, 12).tolist()
    [1.0, 0.25]
    """
    v = np.asarray(corners, dtype=np.float64) - np.asarray(center, dtype=np.float64)
    a = v
    b = np.roll(v, -1, axis=-2)
    r2 = radius * radius
    d = b - a
    dd = np.einsum("...i,...i->...", d, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.einsum("...i,...i->...", a, d) / dd
        q = (np.einsum("...i,...i->...", a, a) - r2) / dd
        disc = p * p - q
        s = np.sqrt(np.maximum(disc, 0.0))
    enters = (dd > 0) & (disc > 0)
    # the edge a + t d, t in [0, 1]: outside for t < t1, inside on [t1, t2], outside after
    t1 = np.where(enters, np.clip(-p - s, 0.0, 1.0), 1.0)
    t2 = np.where(enters, np.clip(-p + s, 0.0, 1.0), 1.0)
    p1 = a + t1[..., None] * d
    p2 = a + t2[..., None] * d

    def cross(u: Float, w: Float) -> Float:
        out: Float = u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]
        return out

    def sector(u: Float, w: Float) -> Float:
        out: Float = 0.5 * r2 * np.arctan2(cross(u, w), np.einsum("...i,...i->...", u, w))
        return out

    total = sector(a, p1) + 0.5 * cross(p1, p2) + sector(p2, b)
    out: Float = np.abs(total.sum(axis=-1))
    return out


# ---------------------------------------------------------------- quadrature


def _integrate(
    area: Callable[[Float, Int], Float],
    a: Float,
    b: Float,
    owner: Int,
    tol: Float,
    noise: Float,
    n: int,
) -> Float:
    """Integrals of ``area(z, k)`` over the intervals ``k``, ``[a[k], b[k]]``, summed by owner.

    ``area`` gets the heights and the index of the interval (of the input)
    each lies in. ``tol`` is each owner's tolerance, shared among its
    intervals by length; ``noise`` the rounding of each owner's slice areas
    (an interval's least tolerance is that times its length).
    """
    total = np.zeros(n)
    keep = b > a
    span = np.bincount(owner[keep], weights=(b - a)[keep], minlength=n)
    share = np.divide(tol, span, out=np.zeros(n), where=span > 0)
    piece = np.flatnonzero(keep)
    a, b = a[piece], b[piece]
    allowed = np.maximum(share, noise)[owner[piece]] * (b - a)
    for depth in range(MAX_DEPTH + 1):
        if a.size == 0:
            break
        m = 0.5 * (a + b)
        lo = np.concatenate([a, a, m])
        hi = np.concatenate([b, m, b])
        z = lo[:, None] + (hi - lo)[:, None] * _S
        values = area(z.ravel(), np.repeat(np.tile(piece, 3), GL_NODES)).reshape(z.shape)
        integral = (values @ _WS) * (hi - lo)
        whole, left, right = np.split(integral, 3)
        fine = left + right
        done = np.abs(whole - fine) <= allowed
        if depth == MAX_DEPTH:
            done[:] = True
        total += np.bincount(owner[piece[done]], weights=fine[done], minlength=n)
        a, b, m, piece, allowed = a[~done], b[~done], m[~done], piece[~done], allowed[~done]
        a, b = np.concatenate([a, m]), np.concatenate([m, b])
        piece = np.concatenate([piece, piece])
        allowed = np.concatenate([allowed, allowed]) * 0.5
    return total


def _intervals(breaks: list[Float]) -> tuple[Float, Float, Int]:
    """Consecutive pairs of each owner's sorted breakpoints: ``(a, b, owner)``."""
    a, b, owner = [], [], []
    for k, z in enumerate(breaks):
        z = np.unique(z)
        a.append(z[:-1])
        b.append(z[1:])
        owner.append(np.full(max(len(z) - 1, 0), k, dtype=np.int64))
    if not a:
        return np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.int64)
    return np.concatenate(a), np.concatenate(b), np.concatenate(owner)


# ---------------------------------------------------------------- spheres


def spheres_in_cylinder(
    centres: ArrayLike,
    radii: ArrayLike,
    axis: Sequence[float],
    radius: float,
    zmin: float,
    zmax: float,
) -> Float:
    """Volume of each ball inside the vertical cylinder of ``axis``, ``radius``, ``zmin``-``zmax``.

    Exact for a ball wholly inside or apart; otherwise the lens areas of its
    horizontal slices integrated between the heights where its slice circle is
    tangent to the wall circle (see the module), to about ``1e-11`` of the
    ball's volume.

    Examples
    --------
    >>> v = spheres_in_cylinder([[0, 0, 0]], [1.0], (0, 0), 5.0, 0.0, 9.0)
    >>> abs(float(v[0]) - 2 * math.pi / 3) < 1e-14
    True
    """
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    r = np.asarray(radii, dtype=np.float64).reshape(-1)
    gap = np.hypot(c[:, 0] - axis[0], c[:, 1] - axis[1]) - radius  # d - R
    d = gap + radius
    zc = c[:, 2]
    lo = np.maximum(zc - r, zmin)
    hi = np.minimum(zc + r, zmax)
    out = np.zeros(len(r))
    whole = (gap + r <= 0) & (zc - r >= zmin) & (zc + r <= zmax)
    out[whole] = 4.0 / 3.0 * math.pi * r[whole] ** 3
    cut = np.flatnonzero(~whole & (gap < r) & (hi > lo))
    if cut.size == 0:
        return out
    breaks = []
    for k in cut.tolist():
        z = [lo[k], hi[k]]
        for rho in (abs(gap[k]), d[k] + radius):  # |R - d| and R + d
            if rho < r[k]:
                h = math.sqrt((r[k] - rho) * (r[k] + rho))
                z += [zc[k] - h, zc[k] + h]
        zz = np.clip(np.array(z), lo[k], hi[k])
        breaks.append(zz)
    a, b, owner = _intervals(breaks)
    rc, zcc, gc = r[cut], zc[cut], gap[cut]

    def area(z: Float, k: Int) -> Float:
        who = owner[k]
        dz = z - zcc[who]
        rk = rc[who]
        rho = np.sqrt(np.maximum((rk - dz) * (rk + dz), 0.0))
        return disk_disk_area(rho, radius, gc[who])

    tol = REL_TOL * 4.0 / 3.0 * math.pi * rc**3
    noise = NOISE * (radius + np.abs(gc)) * 2.0 * rc
    out[cut] = _integrate(area, a, b, owner, tol, noise, len(cut))
    return out


# ---------------------------------------------------------------- polyhedra


def _edges_and_planes(points: Float) -> tuple[Float, Float, Float, float]:
    """Return the hull's edges (their two ends), its facet planes and its volume.

    Qhull triangulates the faces; the diagonals inside a flat face (between
    two triangles of one plane: the neighbour's corners lie in the triangle's
    plane within :data:`FLAT` of the solid's width) are left out. Two faces
    that meet at a tiny angle keep their edge: without it the slices would
    lose their corner there, about the angle times the solid's volume.
    """
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    local = points - centre
    hull = ConvexHull(local)
    s, nb, eq = hull.simplices, hull.neighbors, hull.equations
    flat_tol = FLAT * float(np.ptp(points, axis=0).max())
    ends = []
    for m in range(3):
        edge = s[:, [(m + 1) % 3, (m + 2) % 3]]
        # the neighbour across this edge: its corners' distances from this triangle's plane
        far = np.einsum("ikj,ij->ik", local[s[nb[:, m]]], eq[:, :3]) + eq[:, 3:4]
        flat = np.abs(far).max(axis=1) <= flat_tol
        ends.append(edge[~flat])
    pairs = np.unique(np.sort(np.concatenate(ends), axis=1), axis=0)
    eq = hull.equations.copy()
    eq[:, 3] -= eq[:, :3] @ centre  # back to absolute coordinates
    return points[pairs[:, 0]], points[pairs[:, 1]], eq, float(hull.volume)


def _breakpoints(
    p: Float, q: Float, eq: Float, axis: Sequence[float], radius: float, lo: float, hi: float
) -> Float:
    """Heights where a polyhedron's slice area in the circle may not be smooth (see the module)."""
    z = [np.array([lo, hi]), p[:, 2], q[:, 2]]
    dz = q[:, 2] - p[:, 2]
    moving = dz != 0
    if moving.any():
        # a slice corner p + s g (s = z - p_z) on the circle: |w + s g|^2 = R^2
        g = (q[moving, :2] - p[moving, :2]) / dz[moving, None]
        w = p[moving, :2] - np.asarray(axis, dtype=np.float64)
        gg = np.einsum("ij,ij->i", g, g)
        wg = np.einsum("ij,ij->i", w, g)
        ww = np.einsum("ij,ij->i", w, w)
        span = dz[moving]
        with np.errstate(divide="ignore", invalid="ignore"):
            disc = wg * wg - gg * (ww - radius * radius)
            root = np.sqrt(np.maximum(disc, 0.0))
            for sign in (-1.0, 1.0):
                s = (-wg + sign * root) / gg  # on the edge when s / dz is in [0, 1]
                ok = (gg > 0) & (disc >= 0) & (s * span >= 0) & (np.abs(s) <= np.abs(span))
                z.append(p[moving, 2][ok] + s[ok])
    n_xy = np.hypot(eq[:, 0], eq[:, 1])
    tilted = (eq[:, 2] != 0) & (n_xy > 0)
    if tilted.any():
        # the face's slice line n_x x + n_y y = -off - n_z z at a distance R from the axis
        e = eq[tilted]
        at_axis = e[:, 0] * axis[0] + e[:, 1] * axis[1] + e[:, 3]
        unit = e[:, :2] / n_xy[tilted, None]
        slack = 1e-9 * (radius + float(np.ptp(p, axis=0).max()))
        for sign in (-1.0, 1.0):
            zt = (sign * radius * n_xy[tilted] - at_axis) / e[:, 2]
            # the tangent point, the foot of the axis on the line; kept when on the face
            foot = np.column_stack([np.asarray(axis)[None, :] - sign * radius * unit, zt])
            on = (foot @ eq[:, :3].T + eq[:, 3] <= slack).all(axis=1)
            z.append(zt[on])
    out: Float = np.concatenate(z)
    out = np.clip(out[np.isfinite(out)], lo, hi)
    return out


def _corners_in_order(p: Float, q: Float, z: float) -> Int:
    """Edges that cross the height ``z`` strictly, in order around the slice polygon."""
    zp, zq = p[:, 2], q[:, 2]
    cross = np.flatnonzero((np.minimum(zp, zq) < z) & (np.maximum(zp, zq) > z))
    t = (z - zp[cross]) / (zq[cross] - zp[cross])
    pts = p[cross, :2] + t[:, None] * (q[cross, :2] - p[cross, :2])
    rel = pts - pts.mean(axis=0)
    out: Int = cross[np.argsort(np.arctan2(rel[:, 1], rel[:, 0]))]
    return out


def polyhedra_in_cylinder(
    vertices: Sequence[ArrayLike],
    axis: Sequence[float],
    radius: float,
    zmin: float,
    zmax: float,
) -> Float:
    """Volume of each convex polyhedron inside the vertical cylinder of ``axis``, ``radius``.

    Each polyhedron is the hull of its ``(k, 3)`` vertices (absolute
    coordinates). Exact for one wholly inside the cylinder (all its vertices
    are) or wholly outside its floor, lid or bounding square; otherwise the
    areas of its horizontal slices (convex polygons) in the circle, integrated
    between breakpoints (see the module), to about ``1e-11`` of its volume.
    Between two breakpoints the slice's corners run along a fixed list of
    edges, in a fixed order, found once at the middle.

    Examples
    --------
    >>> cube = np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    >>> v = polyhedra_in_cylinder([cube], (1.0, 0.0), 10.0, -5.0, 0.0)
    >>> abs(float(v[0]) - 4.0) < 1e-12
    True
    """
    n = len(vertices)
    out = np.zeros(n)
    ax = np.asarray(axis, dtype=np.float64)
    cut: list[int] = []
    tol: list[float] = []
    noise: list[float] = []
    ends: list[tuple[Float, Float]] = []
    intervals: list[tuple[float, float, int]] = []  # (a, b, owner)
    orders: list[Int] = []  # each interval's edges (global indices), in order
    first_edge = 0
    for k, pts in enumerate(vertices):
        v = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
        lo, hi = max(float(v[:, 2].min()), zmin), min(float(v[:, 2].max()), zmax)
        if not hi > lo:
            continue
        near = np.clip(ax, v[:, :2].min(axis=0), v[:, :2].max(axis=0))  # of the bounding square
        if math.hypot(*(near - ax)) >= radius:
            continue
        radial = np.hypot(v[:, 0] - ax[0], v[:, 1] - ax[1])
        p, q, eq, volume = _edges_and_planes(v)
        if radial.max() <= radius and v[:, 2].min() >= zmin and v[:, 2].max() <= zmax:
            out[k] = volume
            continue
        width = float(np.ptp(v[:, :2], axis=0).max())
        tol.append(REL_TOL * volume)
        noise.append(NOISE * (radius + float(radial.max()) + width) * width)
        zs = np.unique(_breakpoints(p, q, eq, axis, radius, lo, hi))
        for z0, z1 in itertools.pairwise(zs.tolist()):
            intervals.append((z0, z1, len(cut)))
            orders.append(_corners_in_order(p, q, 0.5 * (z0 + z1)) + first_edge)
        cut.append(k)
        ends.append((p, q))
        first_edge += len(p)
    if not cut:
        return out
    p_all = np.concatenate([e[0] for e in ends])
    q_all = np.concatenate([e[1] for e in ends])
    kmax = max(max((len(o) for o in orders), default=1), 1)
    table = np.zeros((len(orders), kmax), dtype=np.int64)
    corners = np.zeros(len(orders), dtype=np.int64)
    for i, o in enumerate(orders):
        corners[i] = len(o)
        if len(o):
            table[i, : len(o)] = o
            table[i, len(o) :] = o[0]  # a repeated corner: an edge of zero length
    iv = np.array(intervals, dtype=np.float64).reshape(-1, 3)

    def area(z: Float, k: Int) -> Float:
        res = np.empty(len(z))
        step = max(1, _CHUNK // kmax)
        for start in range(0, len(z), step):
            sl = slice(start, start + step)
            idx = table[k[sl]]
            pa, qa = p_all[idx], q_all[idx]
            t = (z[sl, None] - pa[..., 2]) / (qa[..., 2] - pa[..., 2])
            pts = pa[..., :2] + t[..., None] * (qa[..., :2] - pa[..., :2])
            res[sl] = polygons_disk_area(pts, (float(ax[0]), float(ax[1])), radius)
        res[corners[k] < 3] = 0.0
        return res

    owner = iv[:, 2].astype(np.int64)
    out[cut] = _integrate(area, iv[:, 0], iv[:, 1], owner, np.array(tol), np.array(noise), len(cut))
    return out
