"""Independent check of a packing: no overlaps, nothing outside the walls.

The check uses shapely (GEOS) only, not regopack's own geometry, so it can
serve as an oracle for the insertion algorithms. Coordinates are translated by
the domain centre and divided by the domain's larger side before the shapely
geometries are built, so the check behaves the same at every length scale.

Floating-point overlays can fail on nearly degenerate input (two particles
sharing an edge up to rounding). Every pair or particle that the fast pass
flags is therefore measured again in a frame centred on the particle and
scaled to its size, with a snap-rounding overlay on a grid of
:data:`CONFIRM_GRID` particle sizes, which is robust; only violations confirmed
that way are reported.

In a periodic domain a particle may cross a side; pairs are then compared
through the nearest periodic image of the second particle, and nothing can
leave the domain. In a circular container the area outside the wall is
measured by exact polygon-disk intersection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Circle, ConvexPolygon, PeriodicRectangle, polygon_disk_area
from regopack.packing.core import Packing

__all__ = ["CONFIRM_GRID", "VerifyReport", "assert_valid_packing", "verify"]

CONFIRM_GRID = 1e-12
"""Snap-rounding grid of the confirming overlay, in units of the particle size."""


@dataclass(frozen=True)
class VerifyReport:
    """Outcome of :func:`verify`.

    Attributes
    ----------
    ok
        True when no pair overlaps and no particle leaves the domain.
    n_checked
        Number of placed particles checked.
    n_overlapping_pairs
        Pairs whose intersection area exceeds ``rel_tol`` times the smaller area.
    worst_overlap
        ``(i, j, overlap)`` for the pair with the largest overlap, as a fraction
        of the smaller of the two areas (``i < j`` are particle indices), or
        ``None`` when no pair overlaps.
    n_outside
        Particles whose area outside the domain exceeds ``rel_tol`` times their area.
    worst_outside
        ``(i, outside)`` for the particle with the largest area outside the
        domain, as a fraction of its own area, or ``None``.
    rel_tol
        Tolerance used.
    """

    ok: bool
    n_checked: int
    n_overlapping_pairs: int
    worst_overlap: tuple[int, int, float] | None
    n_outside: int
    worst_outside: tuple[int, float] | None
    rel_tol: float

    def __bool__(self) -> bool:
        """Return whether the packing is valid: ``if regopack.verify(p): ...``."""
        return self.ok

    def __str__(self) -> str:
        status = "OK" if self.ok else "VIOLATED"
        lines = [f"checked {self.n_checked} placed particles (rel_tol {self.rel_tol:g}): {status}"]
        line = f"overlapping pairs: {self.n_overlapping_pairs}"
        if self.worst_overlap is not None:
            i, j, frac = self.worst_overlap
            line += f" (worst: particles {i} and {j}, {frac:.3g} of the smaller area)"
        lines.append(line)
        line = f"particles outside the domain: {self.n_outside}"
        if self.worst_outside is not None:
            i, frac = self.worst_outside
            line += f" (worst: particle {i}, {frac:.3g} of its area)"
        lines.append(line)
        return "\n".join(lines)


def _polygons(
    packing: Packing,
    idx: NDArray[np.int64],
    origin: NDArray[np.float64],
    scale: NDArray[np.float64] | float,
) -> NDArray[np.object_]:
    """Polygons of particles ``idx``, translated by ``-origin`` and divided by ``scale``.

    ``origin`` is ``(2,)`` or ``(len(idx), 2)``; ``scale`` a scalar or ``(len(idx),)``.
    """
    offsets = packing.offsets
    counts = offsets[idx + 1] - offsets[idx]
    starts = np.repeat(offsets[idx], counts)
    within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    local = packing.vertices[starts + within]
    shift = np.broadcast_to(packing.centre[idx] - origin, (len(idx), 2))
    per = np.broadcast_to(np.asarray(scale, dtype=np.float64), (len(idx),))
    coords = (local + np.repeat(shift, counts, axis=0)) / np.repeat(per, counts)[:, None]
    rings = shapely.linearrings(coords, indices=np.repeat(np.arange(len(idx)), counts))
    return np.asarray(shapely.polygons(rings), dtype=object)


def _image_shift(
    packing: Packing, i: NDArray[np.int64], j: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Return the shift that brings particle ``j`` to its periodic image nearest to ``i``.

    Zero in a walled domain.
    """
    dom = packing.domain
    if not isinstance(dom, PeriodicRectangle):
        return np.zeros((len(i), 2))
    delta = packing.centre[j] - packing.centre[i]
    out: NDArray[np.float64] = dom.minimum_image(delta) - delta
    return out


def _confirm_overlaps(
    packing: Packing, i: NDArray[np.int64], j: NDArray[np.int64], size: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Overlap of pairs ``(i, j)`` relative to the smaller area, measured robustly.

    Both particles are expressed in a frame centred on particle ``i`` and
    scaled by ``size`` (the square root of the smaller area); ``j`` is taken at
    its periodic image nearest to ``i``.
    """
    origin = packing.centre[i]
    gi = _polygons(packing, i, origin, size)
    gj = _polygons(packing, j, origin - _image_shift(packing, i, j), size)
    inter = shapely.area(shapely.intersection(gi, gj, grid_size=CONFIRM_GRID))
    smaller = np.minimum(shapely.area(gi), shapely.area(gj))
    out: NDArray[np.float64] = inter / smaller
    return out


def _confirm_outside(
    packing: Packing, k: NDArray[np.int64], size: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Area of particles ``k`` outside the domain relative to their area, measured robustly."""
    dom: Any = packing.domain
    origin = packing.centre[k]
    geoms = _polygons(packing, k, origin, size)
    if isinstance(dom, Circle):
        outside = np.empty(len(k))
        for n, g in enumerate(geoms):
            ring = np.asarray(shapely.get_exterior_ring(g).coords)[:-1]
            centre = (np.array([dom.cx, dom.cy]) - origin[n]) / size[n]
            area = float(shapely.area(g))
            outside[n] = (area - polygon_disk_area(ring, centre, dom.radius / size[n])) / area
        return outside
    if isinstance(dom, ConvexPolygon):
        # the container near each particle only (see the rectangle below)
        near = 2.0 * np.abs(shapely.bounds(geoms)).max(axis=1) + 1.0
        walls = shapely.intersection(
            np.asarray(
                [shapely.Polygon((dom.array - origin[n]) / size[n]) for n in range(len(k))],
                dtype=object,
            ),
            shapely.box(-near, -near, near, near),
        )
        inside = shapely.area(shapely.intersection(geoms, walls, grid_size=CONFIRM_GRID))
        areas = shapely.area(geoms)
        frac: NDArray[np.float64] = (areas - inside) / areas
        return frac
    # clip the (possibly huge) domain box to the particle's neighbourhood, so the
    # snap-rounding grid stays far above the rounding error of the coordinates
    reach = 2.0 * np.abs(shapely.bounds(geoms)).max(axis=1) + 1.0
    lo_x = np.maximum((dom.xmin - origin[:, 0]) / size, -reach)
    hi_x = np.minimum((dom.xmax - origin[:, 0]) / size, reach)
    lo_y = np.maximum((dom.ymin - origin[:, 1]) / size, -reach)
    hi_y = np.minimum((dom.ymax - origin[:, 1]) / size, reach)
    areas = shapely.area(geoms)
    inside = np.zeros(len(k))
    nonempty = (lo_x < hi_x) & (lo_y < hi_y)
    if nonempty.any():
        boxes = shapely.box(lo_x[nonempty], lo_y[nonempty], hi_x[nonempty], hi_y[nonempty])
        inside[nonempty] = shapely.area(
            shapely.intersection(geoms[nonempty], boxes, grid_size=CONFIRM_GRID)
        )
    out: NDArray[np.float64] = (areas - inside) / areas
    return out


def verify(packing: Packing, rel_tol: float = 1e-9) -> VerifyReport:
    """Check that placed particles do not overlap and stay inside the domain.

    Parameters
    ----------
    packing
        The packing to check.
    rel_tol
        A pair violates when its intersection area exceeds ``rel_tol`` times the
        smaller particle area; a particle violates when its area outside the
        domain exceeds ``rel_tol`` times its area. Touching is allowed.

    Examples
    --------
    >>> from regopack.testing import packing_from_polygons
    >>> sq = [(0, 0), (1, 0), (1, 1), (0, 1)]
    >>> p = packing_from_polygons([sq, [(x + 1, y) for x, y in sq]], domain=(0, 2, 0, 1))
    >>> verify(p).ok
    True

    Raises
    ------
    ConfigError
        When ``rel_tol`` is negative or not finite.
    PackingError
        When the packing breaks the packing format (e.g. a NaN coordinate or
        a particle without vertices after its arrays were changed in place).
    """
    if not (math.isfinite(rel_tol) and rel_tol >= 0):
        raise ConfigError(f"rel_tol = {rel_tol!r}: must be a finite number >= 0")
    packing.validate()  # the arrays may have changed in place since the packing was built
    dom = packing.domain
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    n = len(idx)
    if n == 0:
        return VerifyReport(True, 0, 0, None, 0, None, rel_tol)
    cx, cy = dom.center
    scale = max(dom.width, dom.height)
    if not np.isfinite(scale) or scale <= 0:
        scale = 1.0
    if packing.rounded:
        return _verify_rounded(packing, idx, scale, rel_tol)
    geoms = _polygons(packing, idx, np.array([cx, cy]), scale)
    areas = shapely.area(geoms)

    # overlaps between pairs
    a, b, shifted = _candidate_pairs(packing, idx, geoms, scale)
    worst_overlap: tuple[int, int, float] | None = None
    n_pairs = 0
    if len(a):
        inter = shapely.area(shapely.intersection(geoms[a], shifted))
        smaller = np.minimum(areas[a], areas[b])
        flagged = ~(inter <= rel_tol * smaller)
        if flagged.any():
            a, b = a[flagged], b[flagged]
            size = np.sqrt(smaller[flagged]) * scale
            frac = _confirm_overlaps(packing, idx[a], idx[b], size)
            bad = ~(frac <= rel_tol)
            n_pairs = int(np.count_nonzero(bad))
            if n_pairs:
                k = int(np.argmax(np.where(bad, np.nan_to_num(frac, nan=np.inf), -np.inf)))
                i, j = sorted((int(idx[a[k]]), int(idx[b[k]])))
                worst_overlap = (i, j, float(frac[k]))
    zero = np.zeros(n)
    n_self, worst_self = _self_image_overlaps(packing, idx, geoms, zero, zero, scale, rel_tol)
    if worst_self is not None:
        n_pairs += n_self
        if worst_overlap is None or worst_self[2] > worst_overlap[2]:
            worst_overlap = worst_self

    n_outside, worst_outside = _outside(packing, idx, geoms, areas, scale, rel_tol)
    return VerifyReport(
        ok=n_pairs == 0 and n_outside == 0,
        n_checked=n,
        n_overlapping_pairs=n_pairs,
        worst_overlap=worst_overlap,
        n_outside=n_outside,
        worst_outside=worst_outside,
        rel_tol=rel_tol,
    )


def _candidate_pairs(
    packing: Packing, idx: NDArray[np.int64], geoms: NDArray[np.object_], scale: float
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.object_]]:
    """Pairs ``a < b`` (positions in ``idx``) whose outlines meet, and ``b``'s outline as met.

    In a periodic domain, ``b`` is taken at its periodic image nearest to ``a``.
    """
    dom = packing.domain
    tree = shapely.STRtree(geoms)
    if not isinstance(dom, PeriodicRectangle):
        a, b = tree.query(geoms, predicate="intersects")
        keep = a < b
        return a[keep], b[keep], geoms[b[keep]]
    # every image of every particle that reaches into the domain, found by a box query
    lx, ly = dom.width / scale, dom.height / scale
    pa: list[NDArray[np.int64]] = []
    pb: list[NDArray[np.int64]] = []
    for sx in (-lx, 0.0, lx):
        for sy in (-ly, 0.0, ly):
            moved = shapely.transform(geoms, lambda c, sx=sx, sy=sy: c + (sx, sy))
            q, t = tree.query(moved, predicate="intersects")
            pa.append(t)
            pb.append(q)
    a = np.concatenate(pa)
    b = np.concatenate(pb)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    keep = lo < hi
    pairs = np.unique(np.column_stack([lo[keep], hi[keep]]), axis=0)
    a, b = pairs[:, 0], pairs[:, 1]
    shift = _image_shift(packing, idx[a], idx[b]) / scale
    shifted = np.asarray(
        [shapely.transform(g, lambda c, d=d: c + d) for g, d in zip(geoms[b], shift, strict=True)],
        dtype=object,
    )
    return a, b, shifted


def _outside(
    packing: Packing,
    idx: NDArray[np.int64],
    geoms: NDArray[np.object_],
    areas: NDArray[np.float64],
    scale: float,
    rel_tol: float,
) -> tuple[int, tuple[int, float] | None]:
    """Count the particles outside the walls; return the count and the worst one."""
    dom = packing.domain
    if isinstance(dom, PeriodicRectangle):
        return 0, None
    # decided on coordinates: a particle far away has no area left in the frame of
    # ``geoms`` (its outline rounds to a point there), so neither the fast pass nor
    # that frame's areas may vouch for it; the confirming overlay is in its own frame
    crossing = np.flatnonzero(~_vertices_inside(packing, idx))
    worst_outside: tuple[int, float] | None = None
    n_outside = 0
    if len(crossing):
        far = np.flatnonzero(~(areas[crossing] > 0))
        if isinstance(dom, Circle | ConvexPolygon) or len(far):
            outside_fast = None
        else:
            cx, cy = dom.center
            outside_fast = _crossing_box(dom, geoms[crossing], areas[crossing], cx, cy, scale)
        if outside_fast is not None:
            flagged = ~(outside_fast <= rel_tol * areas[crossing])  # NaN counts as flagged
            crossing = crossing[flagged]
        if len(crossing):
            size = np.sqrt(packing.area()[idx[crossing]])
            frac = _confirm_outside(packing, idx[crossing], size)
            bad = ~(frac <= rel_tol)
            n_outside = int(np.count_nonzero(bad))
            if n_outside:
                k = int(np.argmax(np.where(bad, np.nan_to_num(frac, nan=np.inf), -np.inf)))
                worst_outside = (int(idx[crossing[k]]), float(frac[k]))
    return n_outside, worst_outside


def _vertices_inside(packing: Packing, idx: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Whether every vertex of each particle lies inside (or on) a convex container's wall.

    A convex particle lies inside a convex container exactly when its vertices do.
    The coordinates are compared as they are, at any distance from the domain.
    """
    dom = packing.domain
    counts = packing.offsets[idx + 1] - packing.offsets[idx]
    starts = np.repeat(packing.offsets[idx], counts)
    within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    pts = packing.vertices[starts + within] + np.repeat(packing.centre[idx], counts, axis=0)
    if isinstance(dom, Circle):
        ok = np.hypot(pts[:, 0] - dom.cx, pts[:, 1] - dom.cy) <= dom.radius
    elif isinstance(dom, ConvexPolygon):
        normal, offset = dom.halfplanes()
        ok = np.all(pts @ normal.T <= offset, axis=1)
    else:
        b = dom.bounds()
        ok = (pts[:, 0] >= b[0]) & (pts[:, 0] <= b[1]) & (pts[:, 1] >= b[2]) & (pts[:, 1] <= b[3])
    owner = np.repeat(np.arange(len(idx)), counts)
    bad = np.bincount(owner[~ok], minlength=len(idx))
    out: NDArray[np.bool_] = bad == 0
    return out


def _crossing_box(
    dom: Any,
    geoms: NDArray[np.object_],
    areas: NDArray[np.float64],
    cx: float,
    cy: float,
    scale: float,
) -> NDArray[np.float64]:
    """Area outside a rectangle's walls of particles that cross them (fast pass)."""
    lo_x, hi_x = (dom.xmin - cx) / scale, (dom.xmax - cx) / scale
    lo_y, hi_y = (dom.ymin - cy) / scale, (dom.ymax - cy) / scale
    box = shapely.box(lo_x, lo_y, hi_x, hi_y)
    inside = shapely.area(shapely.intersection(geoms, box))
    out: NDArray[np.float64] = areas - inside
    return out


def _cores(packing: Packing, idx: NDArray[np.int64], scale: float) -> NDArray[np.object_]:
    """Core outlines (points, segments or polygons) in the frame of :func:`verify`."""
    dom = packing.domain
    counts = packing.offsets[idx + 1] - packing.offsets[idx]
    starts = np.repeat(packing.offsets[idx], counts)
    within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    shift = packing.centre[idx] - np.asarray(dom.center)
    coords = (packing.vertices[starts + within] + np.repeat(shift, counts, axis=0)) / scale
    points = shapely.multipoints(coords, indices=np.repeat(np.arange(len(idx)), counts))
    return np.asarray(shapely.convex_hull(points), dtype=object)


def _self_image_overlaps(
    packing: Packing,
    idx: NDArray[np.int64],
    shapes: NDArray[np.object_],
    rho: NDArray[np.float64],
    req: NDArray[np.float64],
    scale: float,
    rel_tol: float,
) -> tuple[int, tuple[int, int, float] | None]:
    """Particles of a periodic packing that overlap their own periodic image.

    Only a particle wider or higher than a period can; ``shapes`` are the
    outlines (sharp) or cores (rounded, by ``rho``) in the frame of
    :func:`verify`. Returns how many overlap by more than ``rel_tol`` and
    the worst of those as ``(i, i, fraction)``.
    """
    dom: Any = packing.domain
    if not dom.periodic or len(idx) == 0:
        return 0, None
    lx, ly = dom.width / scale, dom.height / scale
    b = shapely.bounds(shapes)
    wide = np.flatnonzero((b[:, 2] - b[:, 0] + 2 * rho >= lx) | (b[:, 3] - b[:, 1] + 2 * rho >= ly))
    count = 0
    worst: tuple[int, int, float] | None = None
    for k in wide.tolist():
        g = shapes[k]
        frac = 0.0
        for sx, sy in ((lx, 0.0), (0.0, ly), (lx, ly), (lx, -ly)):
            moved = shapely.transform(g, lambda c, sx=sx, sy=sy: c + (sx, sy))
            if rho[k] > 0:
                depth = 2.0 * rho[k] - shapely.distance(g, moved)
                f = float(segment_fraction(np.array([depth]), np.array([req[k]]))[0])
            else:
                f = float(shapely.area(shapely.intersection(g, moved)) / shapely.area(g))
            frac = max(frac, f)
        if not frac <= rel_tol:
            count += 1
            if worst is None or frac > worst[2]:
                worst = (int(idx[k]), int(idx[k]), frac)
    return count, worst


def segment_fraction(depth: NDArray[np.float64], r: NDArray[np.float64]) -> NDArray[np.float64]:
    """Area of the circular segment of depth ``depth`` of a disk of radius ``r``, over its area.

    Depths at or below 0 give 0, depths of ``2 r`` or more give 1; small depths
    use the series ``(4/3) sqrt(2 r) d^1.5``, which keeps the precision that
    the closed form loses.

    Examples
    --------
    >>> float(segment_fraction(np.array([1.0]), np.array([1.0]))[0])
    0.5
    """
    d = np.clip(np.asarray(depth, dtype=np.float64), 0.0, 2.0 * r)
    x = d / r
    small = x < 1e-4
    closed = np.arccos(np.clip(1.0 - x, -1.0, 1.0)) - (1.0 - x) * np.sqrt(
        np.maximum(x * (2.0 - x), 0.0)
    )
    series = (4.0 / 3.0) * np.sqrt(2.0) * x**1.5
    out: NDArray[np.float64] = np.where(small, series, closed) / np.pi
    return out


def _verify_rounded(
    packing: Packing, idx: NDArray[np.int64], scale: float, rel_tol: float
) -> VerifyReport:
    """:func:`verify` for packings with rounded particles (disks, rounded polygons).

    A particle is its core grown by its rounding radius, so two particles
    overlap by the depth ``rho_i + rho_j - distance(core_i, core_j)`` (GEOS
    distance; cores that meet count as overlapping entirely) and a particle
    crosses a wall by how far its core, grown by its radius, reaches beyond
    it. A depth is turned into an area fraction by :func:`segment_fraction`
    (the circular segment that a disk of the smaller equivalent radius loses
    at that depth), so ``rel_tol`` means what it means for polygons. Pairs of
    two sharp polygons are measured by their intersection area, as without
    rounding.
    """
    dom = packing.domain
    rho = packing.rounding_radius[idx] / scale
    req = packing.radius[idx] / scale
    cores = _cores(packing, idx, scale)
    # the search shapes contain the true ones (drawn outside the circle)
    search = cores.copy()
    grow = rho > 0
    search[grow] = shapely.buffer(cores[grow], rho[grow] * (1.0 + 1e-3), quad_segs=32)
    a, b, _ = _candidate_pairs(packing, idx, search, scale)
    shift = _image_shift(packing, idx[a], idx[b]) / scale
    cores_b = np.asarray(
        [shapely.transform(g, lambda c, d=d: c + d) for g, d in zip(cores[b], shift, strict=True)],
        dtype=object,
    )
    frac = np.zeros(len(a))
    both_sharp = ~grow[a] & ~grow[b]
    if both_sharp.any():
        inter = shapely.area(shapely.intersection(cores[a][both_sharp], cores_b[both_sharp]))
        smaller = np.minimum(shapely.area(cores[a][both_sharp]), shapely.area(cores_b[both_sharp]))
        frac[both_sharp] = inter / smaller
    rest = ~both_sharp
    if rest.any():
        gap = shapely.distance(cores[a][rest], cores_b[rest])
        depth = rho[a][rest] + rho[b][rest] - gap
        frac[rest] = segment_fraction(depth, np.minimum(req[a][rest], req[b][rest]))
    bad = ~(frac <= rel_tol)
    n_pairs = int(np.count_nonzero(bad))
    worst_overlap: tuple[int, int, float] | None = None
    if n_pairs:
        k = int(np.argmax(np.where(bad, np.nan_to_num(frac, nan=np.inf), -np.inf)))
        i, j = sorted((int(idx[a[k]]), int(idx[b[k]])))
        worst_overlap = (i, j, float(frac[k]))
    n_self, worst_self = _self_image_overlaps(packing, idx, cores, rho, req, scale, rel_tol)
    if worst_self is not None:
        n_pairs += n_self
        if worst_overlap is None or worst_self[2] > worst_overlap[2]:
            worst_overlap = worst_self
    # walls: how far the grown core reaches beyond them
    out = np.zeros(len(idx))
    if not dom.periodic:
        counts = packing.offsets[idx + 1] - packing.offsets[idx]
        owner = np.repeat(np.arange(len(idx)), counts)
        starts = np.repeat(packing.offsets[idx], counts)
        within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
        pts = packing.vertices[starts + within] + packing.centre[idx][owner]
        r = packing.rounding_radius[idx][owner]
        if isinstance(dom, Circle):
            beyond = np.hypot(pts[:, 0] - dom.cx, pts[:, 1] - dom.cy) + r - dom.radius
        else:
            if isinstance(dom, ConvexPolygon):
                normal, offset = dom.halfplanes()
            else:
                normal = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]])
                offset = np.array([-dom.xmin, dom.xmax, -dom.ymin, dom.ymax])
            beyond = (pts @ normal.T - offset).max(axis=1) + r
        np.maximum.at(out, owner, beyond / scale)
        out = segment_fraction(out, req)
    flagged = ~(out <= rel_tol)
    n_outside = int(np.count_nonzero(flagged))
    worst_outside: tuple[int, float] | None = None
    if n_outside:
        k = int(np.argmax(np.where(flagged, np.nan_to_num(out, nan=np.inf), -np.inf)))
        worst_outside = (int(idx[k]), float(out[k]))
    return VerifyReport(
        ok=n_pairs == 0 and n_outside == 0,
        n_checked=len(idx),
        n_overlapping_pairs=n_pairs,
        worst_overlap=worst_overlap,
        n_outside=n_outside,
        worst_outside=worst_outside,
        rel_tol=rel_tol,
    )


def assert_valid_packing(packing: Packing, rel_tol: float = 1e-9) -> VerifyReport:
    """Raise :class:`AssertionError` with the report unless :func:`verify` passes.

    Returns
    -------
    VerifyReport
        The report, when the packing is valid.
    """
    report = verify(packing, rel_tol=rel_tol)
    if not report.ok:
        raise AssertionError(f"invalid packing:\n{report}")
    return report
