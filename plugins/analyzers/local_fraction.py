"""Local packing fraction of every particle from its Laguerre (or Voronoi) cell.

The cells tile the domain: every point belongs to the cell of the particle
centre nearest to it in the power distance ``|x - c_i|^2 - w_i``, with
``w_i = r_i^2`` (``r_i`` the equivalent radius) for Laguerre cells (the power
diagram, or radical tessellation) and ``w_i = 0`` for Voronoi cells. The local
packing fraction of particle ``i`` is its area over the area of its cell,
``phi_i = a_i / A_i``. The cells are clipped exactly to the domain; in a
periodic domain they wrap around its sides.

The power diagram is computed as the dual of the regular triangulation, the
lower convex hull of the lifted points ``(x, y, x^2 + y^2 - w)``: each lower
facet ``z = alpha x + beta y + gamma`` gives the cell vertex
``(alpha / 2, beta / 2)``, the point of equal power distance to its three
centres.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Literal, NamedTuple, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.geometry.domain import Circle, PeriodicRectangle, PlaneDomain
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import Measured, eta_of, interior_margin, interior_mask
from regopack.registry.interfaces import Analyzer

__all__ = [
    "LocalFraction",
    "LocalFractionConfig",
    "Tessellation",
    "domain_cells",
    "histogram_edges",
    "power_cells",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
ObjectArray = NDArray[np.object_]

FAR = 16.0
"""Distance of the bounding sites from the centre of the points, in units of their extent."""

AREA_RTOL = 1e-9
"""Relative tolerance of the check that the cell areas add up to the domain area."""


class LocalFractionConfig(BaseModel):
    """Parameters of the local packing fraction analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    cells: Literal["laguerre", "voronoi"] = Field(
        "laguerre",
        description=(
            "Cells of the particle centres: 'laguerre' (power cells, weighted by 'weights') "
            "or 'voronoi' (no weights)."
        ),
    )
    weights: Literal["inscribed", "equivalent"] = Field(
        "inscribed",
        description=(
            "Radius whose square weighs a Laguerre cell: 'inscribed', of the largest disk "
            "about the particle's centre inside it (every cell is then non-empty), or "
            "'equivalent', the equivalent radius r (area pi r^2); both are r for a disk."
        ),
    )
    bins: int = Field(
        40, ge=2, le=1000, description="Bins of the histogram of the local packing fraction."
    )
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )


# ---------------------------------------------------------------------------
# geometry


def power_cells(
    points: FloatArray, weights: FloatArray | None = None, cover: FloatArray | None = None
) -> ObjectArray:
    """Power cells of the weighted points, as shapely polygons (unclipped).

    Parameters
    ----------
    points
        ``(n, 2)`` sites.
    weights
        ``(n,)`` weights ``w``: the power distance of ``x`` from site ``i`` is
        ``|x - p_i|^2 - w_i``. ``None`` gives the Voronoi cells.
    cover
        Box ``[xmin, xmax, ymin, ymax]`` in which the cells must be exact
        (default: the points' bounding box).

    Returns
    -------
    ndarray of shapely.Polygon
        One cell per site. Cells that reach beyond the points are closed by
        eight sites far outside (at :data:`FAR` times the extent of the points
        and ``cover``), so they are exact within ``cover`` and bounded outside
        it; clip them to a window inside ``cover``. A site whose cell is empty
        (a small weight beside a large one) gets an empty polygon.

    Examples
    --------
    >>> import shapely
    >>> cells = power_cells(np.array([[0.0, 0.0], [2.0, 0.0]]), np.array([1.0, 0.0]))
    >>> float(shapely.get_coordinates(cells[0])[:, 0].max()).__round__(9)
    1.25
    """
    import shapely
    from scipy.spatial import ConvexHull

    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    n = p.shape[0]
    w = np.zeros(n) if weights is None else np.asarray(weights, dtype=np.float64).reshape(n)
    out = np.empty(n, dtype=object)
    if n == 0:
        return out
    lo, hi = p.min(axis=0), p.max(axis=0)
    if cover is not None:
        box = np.asarray(cover, dtype=np.float64)
        lo = np.minimum(lo, box[[0, 2]])
        hi = np.maximum(hi, box[[1, 3]])
    mid = 0.5 * (lo + hi)
    scale = float(max(hi[0] - lo[0], hi[1] - lo[1]))
    if scale <= 0:
        scale = max(math.sqrt(float(np.max(np.abs(w)))), 1.0)
    q = (p - mid) / scale
    ws = (w - w.max()) / (scale * scale)  # a common shift of the weights changes nothing
    t = np.arange(8) * (np.pi / 4)
    far = FAR * np.column_stack([np.cos(t), np.sin(t)])
    sites = np.vstack([q, far])
    weight = np.concatenate([ws, np.full(8, float(ws.min()))])
    lifted = np.column_stack([sites, np.einsum("ij,ij->i", sites, sites) - weight])
    hull = ConvexHull(lifted)
    eq = hull.equations
    lower = eq[:, 2] < -1e-12
    simplices = hull.simplices[lower].astype(np.int64)
    e = eq[lower]
    vertex = -e[:, :2] / (2.0 * e[:, 2:3])
    site = simplices.ravel()
    facet = np.repeat(np.arange(len(simplices), dtype=np.int64), 3)
    real = site < n
    site, facet = site[real], facet[real]
    count = np.bincount(site, minlength=n)
    xy = vertex[facet]
    cx = np.bincount(site, weights=xy[:, 0], minlength=n) / np.maximum(count, 1)
    cy = np.bincount(site, weights=xy[:, 1], minlength=n) / np.maximum(count, 1)
    angle = np.arctan2(xy[:, 1] - cy[site], xy[:, 0] - cx[site])
    order = np.lexsort((angle, site))
    site, xy = site[order], xy[order]
    has = count >= 3
    keep = has[site]
    compact = np.cumsum(has) - 1
    rings = shapely.linearrings(xy[keep] * scale + mid, indices=compact[site[keep]])
    out[has] = shapely.polygons(rings)
    out[~has] = shapely.Polygon()
    return out


def _periodic_sites(
    centre: FloatArray, domain: PeriodicRectangle, pad: float
) -> tuple[FloatArray, IntArray]:
    """Centres plus their periodic images within ``pad`` of the box; the origin of each."""
    lx, ly = domain.period
    c = centre
    shifts_x = [0.0, lx, -lx]
    shifts_y = [0.0, ly, -ly]
    near_x = [None, c[:, 0] < domain.xmin + pad, c[:, 0] >= domain.xmax - pad]
    near_y = [None, c[:, 1] < domain.ymin + pad, c[:, 1] >= domain.ymax - pad]
    pts = [c]
    origin = [np.arange(len(c), dtype=np.int64)]
    for sx, mx in zip(shifts_x, near_x, strict=True):
        for sy, my in zip(shifts_y, near_y, strict=True):
            if mx is None and my is None:
                continue
            sel = np.ones(len(c), dtype=bool)
            if mx is not None:
                sel &= mx
            if my is not None:
                sel &= my
            pts.append(c[sel] + np.array([sx, sy]))
            origin.append(np.flatnonzero(sel).astype(np.int64))
    return np.vstack(pts), np.concatenate(origin)


class Tessellation(NamedTuple):
    """Cells of the particle centres in a domain.

    Attributes
    ----------
    cells
        Power (or Voronoi) cell of every centre, exact inside the domain but
        not clipped to it.
    clipped
        The cells clipped to the domain (in a periodic domain: the cells, which
        wrap around its sides).
    area
        Exact area of every clipped cell; the areas add up to the domain's.
    """

    cells: ObjectArray
    clipped: ObjectArray
    area: FloatArray


def domain_cells(
    domain: PlaneDomain, centre: FloatArray, weights: FloatArray | None = None
) -> Tessellation:
    """Power (or Voronoi) cells of the centres, clipped to the domain, and their exact areas.

    Parameters
    ----------
    domain
        The container. Walled domains clip the cells at their walls; a circle
        exactly, by polygon-disk intersection (the clipped polygons follow its
        drawn outline, the areas the true circle). In a periodic domain the
        cells wrap: periodic images of the centres take part, and a cell near a
        side reaches beyond it.
    centre
        ``(n, 2)`` centres inside the domain.
    weights
        ``(n,)`` power weights (``None``: Voronoi cells).
    """
    import shapely

    c = np.asarray(centre, dtype=np.float64).reshape(-1, 2)
    n = c.shape[0]
    w = None if weights is None else np.asarray(weights, dtype=np.float64).reshape(n)
    if n == 0:
        empty = np.empty(0, dtype=object)
        return Tessellation(empty, empty, np.zeros(0))
    if isinstance(domain, PeriodicRectangle):
        lx, ly = domain.period
        pad = min(4.0 * math.sqrt(domain.area / n), max(lx, ly))
        while True:
            # missing images can only enlarge the cells, so areas adding up to the
            # box's are the test that the images were enough
            pts, origin = _periodic_sites(c, domain, pad)
            cells = power_cells(pts, None if w is None else w[origin], domain.bounds())[:n]
            areas = np.asarray(shapely.area(cells), dtype=np.float64)
            if float(areas.sum()) <= domain.area * (1.0 + AREA_RTOL) or pad >= max(lx, ly):
                return Tessellation(cells, cells, areas)
            pad = min(2.0 * pad, max(lx, ly))
    cells = power_cells(c, w, domain.bounds())
    window = shapely.Polygon(domain.outline())
    shapely.prepare(window)
    inside = shapely.contains_properly(window, cells)
    areas = np.asarray(shapely.area(cells), dtype=np.float64)
    clipped = cells.copy()
    rest = np.flatnonzero(~inside)
    if len(rest):
        clipped[rest] = shapely.intersection(cells[rest], window)
        if isinstance(domain, Circle):
            from regopack.plugins.analyzers.regions import disk_areas

            areas[rest] = disk_areas(cells[rest], domain.center, domain.radius)
        else:
            areas[rest] = shapely.area(clipped[rest])
    return Tessellation(cells, clipped, areas)


# ---------------------------------------------------------------------------
# solid area in the cells


def _rings(geoms: ObjectArray) -> tuple[FloatArray, IntArray]:
    """Exterior ring vertices of the polygons (without the closing one) and their offsets."""
    import shapely

    rings = shapely.get_exterior_ring(shapely.orient_polygons(geoms))  # counter-clockwise
    coords, which = shapely.get_coordinates(rings, return_index=True)
    last = np.r_[which[1:] != which[:-1], True]
    coords, which = coords[~last], which[~last]  # drop every ring's closing vertex
    offsets = np.zeros(len(geoms) + 1, dtype=np.int64)
    np.cumsum(np.bincount(which, minlength=len(geoms)), out=offsets[1:])
    return coords, offsets


def solid_in_cells(
    cells: ObjectArray, particles: ObjectArray, own: IntArray | None = None
) -> tuple[FloatArray, FloatArray]:
    """Area of the particles inside every cell, and of the own particle inside its cell.

    Parameters
    ----------
    cells
        Convex cells (counter-clockwise, as :func:`power_cells` builds them).
    particles
        Convex particle outlines (periodic images included, where they apply).
    own
        Index in ``particles`` of the particle of every cell (default: the same index).

    Returns
    -------
    solid, mine
        Per cell: the area of all particles inside it, and of its own particle.
    """
    import shapely

    from regopack.plugins.analyzers.local_fraction_kernel import overlap_areas

    m = len(cells)
    own = np.arange(m, dtype=np.int64) if own is None else np.asarray(own, dtype=np.int64)
    if m == 0 or len(particles) == 0:
        return np.zeros(m), np.zeros(m)
    tree = shapely.STRtree(particles)
    ci, pj = tree.query(cells)  # bounding boxes that meet; the kernel finds the overlap
    ci, pj = ci.astype(np.int64), pj.astype(np.int64)
    cxy, coff = _rings(cells)
    pxy, poff = _rings(particles)
    area = overlap_areas(
        ci,
        pj,
        np.ascontiguousarray(cxy[:, 0]),
        np.ascontiguousarray(cxy[:, 1]),
        coff,
        np.ascontiguousarray(pxy[:, 0]),
        np.ascontiguousarray(pxy[:, 1]),
        poff,
    )
    solid = np.bincount(ci, weights=area, minlength=m).astype(np.float64)
    hit = pj == own[ci]
    mine = np.bincount(ci[hit], weights=area[hit], minlength=m).astype(np.float64)
    return solid, mine


def inscribed_radius(packing: Packing) -> FloatArray:
    """Radius of the largest disk about each particle's centre inside it.

    The smallest distance from the centre to the line of an edge of the
    (convex) outline, plus the rounding radius; a disk's radius.
    """
    v = packing.vertices
    off = packing.offsets
    n = packing.n_particles
    if v.shape[0] == 0:
        return packing.rounding_radius.copy()
    nxt = np.arange(1, v.shape[0] + 1, dtype=np.int64)
    counts = np.diff(off)
    ends = off[1:][counts > 0] - 1
    nxt[ends] = off[:-1][counts > 0]
    edge = v[nxt] - v
    length = np.hypot(edge[:, 0], edge[:, 1])
    cross = v[:, 0] * v[nxt, 1] - v[:, 1] * v[nxt, 0]
    scale = np.repeat(packing.circumradius - packing.rounding_radius, counts)
    real = length > 1e-12 * np.maximum(scale, 1e-300)
    dist = np.where(real, cross / np.where(real, length, 1.0), np.inf)
    out = np.full(n, np.inf)
    has = counts > 0
    out[has] = np.minimum.reduceat(dist, off[:-1][has])
    out = np.where(np.isfinite(out), np.maximum(out, 0.0), 0.0)
    result: FloatArray = out + packing.rounding_radius
    return result


# ---------------------------------------------------------------------------
# the analyzer

OUTSIDE_RTOL = 1e-9
"""A particle counts as reaching beyond its cell when more than this share of it does."""


def _stats(values: FloatArray) -> dict[str, float | None]:
    v = values[np.isfinite(values)]
    if v.size == 0:
        return {"mean": None, "std": None, "median": None, "min": None, "max": None}
    return {
        "mean": float(v.mean()),
        "std": float(v.std(ddof=1)) if v.size > 1 else None,
        "median": float(np.median(v)),
        "min": float(v.min()),
        "max": float(v.max()),
    }


def _ratio(num: float, den: float) -> float | None:
    return num / den if den > 0 else None


def histogram_edges(values: FloatArray, bins: int, step: float = 0.02) -> FloatArray:
    """Return the edges of ``bins`` equal bins over the finite values, rounded out to ``step``.

    Examples
    --------
    >>> histogram_edges(np.array([0.81, 0.93]), 2).tolist()
    [0.8, 0.87, 0.94]
    """
    v = values[np.isfinite(values)]
    if v.size == 0:
        return np.linspace(0.0, 1.0, bins + 1)
    lo = math.floor(float(v.min()) / step) * step
    hi = math.ceil(float(v.max()) / step) * step
    if hi <= lo:
        hi = lo + step
    return np.round(np.linspace(lo, hi, bins + 1), 12)


class LocalFraction(Measured):
    """Local packing fraction of every particle: the solid share of its cell.

    ``phi_i = s_i / A_i``, with ``A_i`` the area of particle ``i``'s cell and
    ``s_i`` the area of all particles inside it. After :meth:`compute`,
    ``phi_local``, ``cell_area``, ``solid_area`` and ``outside_area`` (the part
    of a particle outside its own cell) hold one value per drawn particle (NaN
    for the particles not placed); ``cells`` the clipped cell of every placed
    particle, in the order of ``idx = np.flatnonzero(placed)``. Scalars:
    statistics of phi_i over the domain and the interior, and the area check.
    """

    name = "local_fraction"

    def __init__(self, config: LocalFractionConfig | None = None) -> None:
        self.config = config or LocalFractionConfig()

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Build and clip the cells; measure the particle area inside each."""
        cfg = self.config
        n = packing.n_particles
        idx = np.flatnonzero(packing.placed).astype(np.int64)
        weights: FloatArray | None = None
        if cfg.cells == "laguerre":
            radius = inscribed_radius(packing) if cfg.weights == "inscribed" else packing.radius
            weights = radius[idx] ** 2
        tess = domain_cells(packing.domain, packing.centre[idx], weights)
        area = packing.area()[idx]
        solid, own = self._solid(packing, idx, tess.cells)
        shapes = packing.to_shapely(idx)
        import shapely

        # the exact particle area, less the part of its outline outside its cell
        outside = np.maximum(np.asarray(shapely.area(shapes)) - own, 0.0)
        outside[~(tess.area > 0)] = area[~(tess.area > 0)]
        solid = np.clip(solid - own + (area - outside), 0.0, tess.area)
        with np.errstate(divide="ignore", invalid="ignore"):
            phi = np.where(tess.area > 0, solid / tess.area, np.nan)
        margin = interior_margin(packing, cfg.margin)
        interior = interior_mask(packing, margin)
        self.idx = idx
        self.cells = tess.clipped
        self.interior = interior
        self.weights = weights
        self.phi_local = self._full(n, idx, phi)
        self.cell_area = self._full(n, idx, tess.area)
        self.solid_area = self._full(n, idx, solid)
        self.particle_area = self._full(n, idx, area)
        self.outside_area = self._full(n, idx, outside)
        inner = interior[idx]
        domain_area = float(packing.domain.area)
        cell_sum = float(tess.area.sum())
        beyond = outside > OUTSIDE_RTOL * area
        res: dict[str, Any] = {
            "cells": cfg.cells,
            "weights": cfg.weights if cfg.cells == "laguerre" else None,
            "eta": eta_of(packing),
            "interior_margin": margin,
            "n_cells": len(idx),
            "n_interior": int(inner.sum()),
            "n_empty_cells": int(np.sum(~(tess.area > 0))),
            "domain_area": domain_area,
            "cell_area_sum": cell_sum,
            "cell_area_rel_error": (cell_sum - domain_area) / domain_area if len(idx) else None,
            "phi_cells": _ratio(float(solid.sum()), cell_sum),
            "phi_cells_interior": _ratio(float(solid[inner].sum()), float(tess.area[inner].sum())),
        }
        for key, value in _stats(phi).items():
            res[f"phi_{key}"] = value
        for key, value in _stats(phi[inner]).items():
            res[f"phi_{key}_interior"] = value
        res["share_beyond_cell"] = float(beyond.mean()) if len(idx) else None
        res["overhang_share"] = _ratio(float(outside.sum()), float(area.sum()))
        self.edges = histogram_edges(phi, cfg.bins)
        self.hist_domain = np.histogram(phi[np.isfinite(phi)], self.edges)[0].astype(np.int64)
        fin = inner & np.isfinite(phi)
        self.hist_interior = np.histogram(phi[fin], self.edges)[0].astype(np.int64)
        self._packing = packing
        self._results = res
        return self

    @staticmethod
    def _full(n: int, idx: IntArray, values: FloatArray) -> FloatArray:
        out = np.full(n, np.nan)
        out[idx] = values
        return out

    @staticmethod
    def _solid(
        packing: Packing, idx: IntArray, cells: ObjectArray
    ) -> tuple[FloatArray, FloatArray]:
        """Particle area inside every cell (periodic images included) and the own share."""
        import shapely

        shapes = packing.to_shapely(idx)
        if isinstance(packing.domain, PeriodicRectangle) and len(idx):
            # images of every particle that can reach a cell beyond the box's sides
            box = packing.domain.bounds()
            lo = shapely.bounds(cells)
            beyond = max(
                float(np.max(box[0] - lo[:, 0])),
                float(np.max(lo[:, 2] - box[1])),
                float(np.max(box[2] - lo[:, 1])),
                float(np.max(lo[:, 3] - box[3])),
                0.0,
            )
            pad = beyond + 2.0 * float(np.max(packing.circumradius[idx]))
            centre, origin = _periodic_sites(packing.centre[idx], packing.domain, pad)
            ghost = np.arange(len(idx), len(origin))
            # shift every ghost's outline by its image's offset from the particle
            offset = centre[ghost] - packing.centre[idx][origin[ghost]]
            source = shapes[origin[ghost]]
            _, part = shapely.get_coordinates(source, return_index=True)
            moved = shapely.transform(source, lambda xy: xy + offset[part])
            shapes = np.concatenate([shapes, moved])
        # the first len(idx) shapes are the cells' own particles
        return solid_in_cells(cells, shapes)

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-particle table ``local_fraction`` and the histogram ``local_fraction_hist``."""
        self._need()
        p, idx = self._packing, self.idx
        return {
            "local_fraction": {
                "particle": idx,
                "mineral": p.mineral[idx],
                "x": p.centre[idx, 0],
                "y": p.centre[idx, 1],
                "radius": p.radius[idx],
                "interior": self.interior[idx],
                "particle_area": self.particle_area[idx],
                "cell_area": self.cell_area[idx],
                "solid_area": self.solid_area[idx],
                "outside_area": self.outside_area[idx],
                "phi_local": self.phi_local[idx],
            },
            "local_fraction_hist": {
                "phi_lo": self.edges[:-1],
                "phi_hi": self.edges[1:],
                "n_domain": self.hist_domain,
                "n_interior": self.hist_interior,
            },
        }
