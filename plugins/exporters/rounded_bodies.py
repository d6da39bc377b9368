"""Outlines for DEM codes that model a particle as a rounded polygon.

A rounded polygon is a convex *core* (a polygon, a segment or a point) grown by
a rounding radius ``r``: the set of points within ``r`` of the core. DEM codes
such as LAMMPS' ``body rounded/polygon`` style need a core without repeated or
collinear vertices, and, for the rounded body to stay inside the particle it
stands for, a core that is the particle's outline eroded by ``r``.

>>> square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
>>> clean_outline(square).tolist()
[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]
>>> erode_convex(clean_outline(square), 0.5).tolist()
[[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]]
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CLEAN_TOLERANCE",
    "clean_outline",
    "erode_convex",
    "polygon_moments",
    "rounded_moments",
]

FloatArray = NDArray[np.float64]

CLEAN_TOLERANCE = 1e-6
"""Distances below this fraction of an outline's size count as zero (see :func:`clean_outline`)."""


def _size(v: FloatArray) -> float:
    """Largest extent of the outline (its bounding box's longer side)."""
    if v.shape[0] == 0:
        return 0.0
    return float(np.max(v.max(axis=0) - v.min(axis=0)))


def clean_outline(v: FloatArray, tol: float = CLEAN_TOLERANCE) -> FloatArray:
    """Remove repeated and collinear vertices from a convex counter-clockwise outline.

    A vertex goes when it lies within ``tol × size`` of the next vertex, or of
    the line through its two neighbours (``size`` is the outline's largest
    extent). Removing a vertex of a convex polygon only cuts off a sliver of
    it, so the cleaned outline lies inside the original one. At least one
    vertex is kept; an outline that collapses to a segment keeps its two ends.

    Parameters
    ----------
    v
        ``(n, 2)`` vertices of a convex polygon in counter-clockwise order.
    tol
        Tolerance relative to the outline's size.

    Returns
    -------
    numpy.ndarray
        The remaining vertices, in their order.
    """
    pts = [(float(x), float(y)) for x, y in np.asarray(v, dtype=np.float64).tolist()]
    eps = tol * _size(np.asarray(v, dtype=np.float64))
    changed = True
    while changed and len(pts) > 1:
        changed = False
        n = len(pts)
        for i in range(n):  # repeated vertices
            x0, y0 = pts[i]
            x1, y1 = pts[(i + 1) % n]
            if math.hypot(x1 - x0, y1 - y0) <= eps:
                del pts[i]
                changed = True
                break
        if changed or len(pts) < 3:
            continue
        n = len(pts)
        for i in range(n):  # collinear vertices
            ax, ay = pts[i - 1]
            bx, by = pts[i]
            cx, cy = pts[(i + 1) % n]
            ux, uy = cx - ax, cy - ay
            length = math.hypot(ux, uy)
            if length <= eps or abs(ux * (by - ay) - uy * (bx - ax)) <= eps * length:
                del pts[i]
                changed = True
                break
    return np.array(pts, dtype=np.float64).reshape(-1, 2)


Point = tuple[float, float]


def _clip(pts: list[Point], a: float, b: float, c: float) -> list[Point]:
    """Clip a convex polygon by the half-plane ``a x + b y <= c`` (Sutherland-Hodgman)."""
    out: list[Point] = []
    n = len(pts)
    for j in range(n):
        x1, y1 = pts[j]
        x2, y2 = pts[(j + 1) % n]
        f1 = c - (a * x1 + b * y1)
        f2 = c - (a * x2 + b * y2)
        if f1 >= 0.0:
            out.append((x1, y1))
        if (f1 >= 0.0) != (f2 >= 0.0):
            u = f1 / (f1 - f2)
            out.append((x1 + u * (x2 - x1), y1 + u * (y2 - y1)))
    return out


def erode_convex(v: FloatArray, r: float) -> FloatArray:
    """Move every edge of the convex polygon ``v`` inward by ``r``.

    The result is the set of points whose distance to the outside of ``v`` is
    at least ``r``, so the points within ``r`` of it (the rounded body of
    radius ``r`` about it) fill ``v`` but for its corners. It may have fewer
    vertices than ``v`` (short edges vanish), and is empty when ``r`` reaches
    the polygon's inradius.

    Parameters
    ----------
    v
        ``(n, 2)`` vertices of a convex counter-clockwise polygon without
        repeated vertices (see :func:`clean_outline`), ``n >= 3``.
    r
        Erosion distance, ``>= 0``.

    Returns
    -------
    numpy.ndarray
        ``(k, 2)`` vertices, ``k = 0`` when nothing is left.
    """
    v = np.asarray(v, dtype=np.float64)
    pts = [(float(x), float(y)) for x, y in v.tolist()]
    n = len(pts)
    for i in range(n):
        x0, y0 = float(v[i, 0]), float(v[i, 1])
        x1, y1 = float(v[(i + 1) % n, 0]), float(v[(i + 1) % n, 1])
        ex, ey = x1 - x0, y1 - y0
        length = math.hypot(ex, ey)
        if length == 0.0:
            continue
        a, b = ey / length, -ex / length  # outward unit normal of a counter-clockwise edge
        pts = _clip(pts, a, b, a * x0 + b * y0 - r)
        if len(pts) < 3:
            return np.empty((0, 2), dtype=np.float64)
    core = clean_outline(np.array(pts, dtype=np.float64).reshape(-1, 2))
    return core if core.shape[0] >= 3 else np.empty((0, 2), dtype=np.float64)


def _polygon_raw_moments(v: FloatArray) -> FloatArray:
    """Return ``(A, ∫x, ∫y, ∫x², ∫y², ∫xy)`` of counter-clockwise polygons about the origin.

    ``v`` is ``(k, 2)`` for one polygon or ``(m, k, 2)`` for ``m`` polygons of
    ``k`` vertices each, whose moments are summed.
    """
    v = v.reshape(-1, v.shape[-2], 2)
    if v.shape[1] < 3:
        return np.zeros(6)
    x0, y0 = v[..., 0], v[..., 1]
    x1, y1 = np.roll(x0, -1, axis=1), np.roll(y0, -1, axis=1)
    cross = x0 * y1 - x1 * y0
    return np.array(
        [
            cross.sum() / 2.0,
            ((x0 + x1) * cross).sum() / 6.0,
            ((y0 + y1) * cross).sum() / 6.0,
            ((x0 * x0 + x0 * x1 + x1 * x1) * cross).sum() / 12.0,
            ((y0 * y0 + y0 * y1 + y1 * y1) * cross).sum() / 12.0,
            ((x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross).sum() / 24.0,
        ]
    )


def _sector_raw_moments(
    px: FloatArray, py: FloatArray, r: float, a: FloatArray, b: FloatArray
) -> FloatArray:
    """Sum the raw moments of sectors of radius ``r`` at ``p`` from angle ``a`` to ``b``."""
    da = b - a
    area = 0.5 * r * r * da
    # first moments of each sector about its apex
    mx = r**3 / 3.0 * (np.sin(b) - np.sin(a))
    my = r**3 / 3.0 * (np.cos(a) - np.cos(b))
    r4 = r**4
    s2 = np.sin(2 * b) - np.sin(2 * a)
    jxx = r4 / 8.0 * (da + 0.5 * s2)
    jyy = r4 / 8.0 * (da - 0.5 * s2)
    jxy = r4 / 16.0 * (np.cos(2 * a) - np.cos(2 * b))
    return np.array(
        [
            area.sum(),
            (mx + px * area).sum(),
            (my + py * area).sum(),
            (jxx + 2 * px * mx + px * px * area).sum(),
            (jyy + 2 * py * my + py * py * area).sum(),
            (jxy + px * my + py * mx + px * py * area).sum(),
        ]
    )


def polygon_moments(v: FloatArray) -> tuple[float, FloatArray, float, float, float]:
    """Area, centroid and second moments of a counter-clockwise polygon.

    Returns
    -------
    tuple
        ``(area, centroid, ixx, iyy, ixy)`` with ``ixx = ∫ y² dA``,
        ``iyy = ∫ x² dA`` and ``ixy = ∫ x y dA``, about the centroid.

    Examples
    --------
    >>> sq = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    >>> a, c, ixx, iyy, ixy = polygon_moments(sq + 3.0)
    >>> float(a), c.tolist(), round(ixx, 12), round(iyy, 12), round(ixy, 12)
    (4.0, [3.0, 3.0], 1.333333333333, 1.333333333333, 0.0)
    """
    x0, y0 = v[:, 0], v[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    cross = x0 * y1 - x1 * y0
    area = float(cross.sum()) / 2.0
    cx = float(((x0 + x1) * cross).sum()) / (6.0 * area)
    cy = float(((y0 + y1) * cross).sum()) / (6.0 * area)
    x0, x1, y0, y1 = x0 - cx, x1 - cx, y0 - cy, y1 - cy
    cross = x0 * y1 - x1 * y0
    ixx = float(((y0 * y0 + y0 * y1 + y1 * y1) * cross).sum()) / 12.0
    iyy = float(((x0 * x0 + x0 * x1 + x1 * x1) * cross).sum()) / 12.0
    ixy = float(((x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross).sum()) / 24.0
    return area, np.array([cx, cy]), ixx, iyy, ixy


def rounded_moments(core: FloatArray, r: float) -> tuple[float, FloatArray, float, float, float]:
    """Area, centroid and second moments of a core grown by the radius ``r``.

    The body is split, exactly, into the core polygon, one rectangle of width
    ``r`` outside each edge and one circular sector at each vertex, between
    the normals of its two edges. A one-vertex core gives a disk and a
    two-vertex core a stadium.

    Parameters
    ----------
    core
        ``(n, 2)`` vertices of a convex counter-clockwise polygon (``n >= 3``),
        a segment (``n = 2``) or a point (``n = 1``), without repeated vertices.
    r
        Rounding radius, ``>= 0`` (``> 0`` when ``n < 3``).

    Returns
    -------
    tuple
        ``(area, centroid, ixx, iyy, ixy)`` with ``ixx = ∫ y² dA``,
        ``iyy = ∫ x² dA`` and ``ixy = ∫ x y dA`` about the centroid, as
        :func:`polygon_moments` returns them.

    Examples
    --------
    >>> area, c, ixx, iyy, ixy = rounded_moments(np.array([[1.0, 2.0]]), 2.0)
    >>> round(area / math.pi, 12), c.tolist(), round(ixx / math.pi, 12), round(ixy, 12)
    (4.0, [1.0, 2.0], 4.0, 0.0)
    """
    core = np.asarray(core, dtype=np.float64).reshape(-1, 2)
    n = core.shape[0]
    total = _polygon_raw_moments(core)
    if r > 0.0 and n == 1:  # a disk, exactly
        px, py = float(core[0, 0]), float(core[0, 1])
        a, j = math.pi * r * r, 0.25 * math.pi * r**4
        total = total + np.array([a, px * a, py * a, j + px * px * a, j + py * py * a, px * py * a])
    elif r > 0.0:
        nxt = np.roll(core, -1, axis=0)
        e = nxt - core
        length = np.hypot(e[:, 0], e[:, 1])
        normal = np.stack([e[:, 1], -e[:, 0]], axis=1) / length[:, None] * r  # outward
        strips = np.stack([core, core + normal, nxt + normal, nxt], axis=1)  # counter-clockwise
        total = total + _polygon_raw_moments(strips)
        out_after = np.arctan2(-e[:, 0], e[:, 1])  # outward normal angle of each edge
        out_before = np.roll(out_after, 1)  # and of the edge before each vertex
        turn = np.mod(out_after - out_before, 2 * math.pi)
        total = total + _sector_raw_moments(
            core[:, 0], core[:, 1], r, out_before, out_before + turn
        )
    area, sx, sy, jxx, jyy, jxy = (float(t) for t in total)
    cx, cy = sx / area, sy / area
    return (
        area,
        np.array([cx, cy]),
        jyy - area * cy * cy,
        jxx - area * cx * cx,
        jxy - area * cx * cy,
    )
