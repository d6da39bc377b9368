"""Rings and tiles of the interior window, and the particle area inside each, exactly.

A *ring* is the part of the window at a distance in ``[r_in, r_out)`` from a
centre; a *tile* is a cell of a grid laid over the window's bounding box, cut
to the window. Particle outlines are cut to the window with shapely (polygon
windows) or with the exact polygon–disk intersection (circular windows); in a
periodic domain the images one period away of the particles crossing a side
are added first, so every part of a particle is counted once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import Circle, PeriodicRectangle, PlaneDomain
from regopack.packing.core import Packing

__all__ = [
    "MIN_TILE_FILL",
    "Tiles",
    "WindowPieces",
    "disk_areas",
    "ring_edges",
    "ring_mean_radius",
    "ring_piece_areas",
    "ring_sector_areas",
    "ring_window_areas",
    "scatter_error",
    "tile_cell_areas",
    "tile_grid",
    "tile_piece_areas",
    "window_area_in_disk",
    "window_pieces",
    "window_reach",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
Centre = tuple[float, float]

MIN_TILE_FILL = 0.5
"""Tiles with less than this share of their cell inside the window are left out."""


@dataclass(frozen=True)
class WindowPieces:
    """Placed particles cut to a window.

    Attributes
    ----------
    geoms
        Shapely polygons: the parts of the particles inside the window (for a
        circular window, the whole outlines, still to be cut to ``disk``).
    owner
        Index in the packing of the particle each piece belongs to.
    disk
        ``(cx, cy, radius)`` of a circular window, else ``None``.
    """

    geoms: NDArray[np.object_]
    owner: IntArray
    disk: tuple[float, float, float] | None = None


def _periodic_images(
    geoms: NDArray[np.object_], owner: IntArray, domain: PeriodicRectangle
) -> tuple[NDArray[np.object_], IntArray]:
    """Add the copies one period away of the outlines that reach across a side."""
    import shapely

    b = shapely.bounds(geoms)
    lx, ly = domain.period
    out_g, out_o = [geoms], [owner]
    for sx in (-lx, 0.0, lx):
        for sy in (-ly, 0.0, ly):
            if sx == 0.0 and sy == 0.0:
                continue
            sel = (
                (b[:, 0] + sx < domain.xmax)
                & (b[:, 2] + sx > domain.xmin)
                & (b[:, 1] + sy < domain.ymax)
                & (b[:, 3] + sy > domain.ymin)
            )
            if sel.any():
                shift = np.array([sx, sy])
                out_g.append(shapely.transform(geoms[sel], lambda c, s=shift: c + s))
                out_o.append(owner[sel])
    return np.concatenate(out_g), np.concatenate(out_o).astype(np.int64)


def window_pieces(packing: Packing, window: PlaneDomain) -> WindowPieces:
    """Cut the placed particles to ``window`` (rounded outlines drawn as by ``to_shapely``)."""
    import shapely

    owner = np.flatnonzero(packing.placed).astype(np.int64)
    geoms = packing.to_shapely(owner)
    if isinstance(packing.domain, PeriodicRectangle) and len(geoms):
        geoms, owner = _periodic_images(geoms, owner, packing.domain)
    if isinstance(window, Circle):
        return WindowPieces(geoms, owner, (window.cx, window.cy, window.radius))
    if not window.area > 0 or len(geoms) == 0:
        return WindowPieces(np.empty(0, dtype=object), np.zeros(0, dtype=np.int64))
    poly = shapely.Polygon(window.outline())
    shapely.prepare(poly)
    inside = shapely.contains_properly(poly, geoms)
    cut = geoms.copy()
    if (~inside).any():
        cut[~inside] = shapely.intersection(geoms[~inside], poly)
    keep = shapely.area(cut) > 0
    return WindowPieces(cut[keep], owner[keep])


def _sector_or_triangle(
    p: FloatArray, q: FloatArray, r2: float, straight: NDArray[np.bool_]
) -> FloatArray:
    """Signed area, inside the disk, of the triangles (0, p, q): straight or a circular sector."""
    cross = p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
    dot = np.einsum("ij,ij->i", p, q)
    out: FloatArray = np.where(straight, 0.5 * cross, 0.5 * r2 * np.arctan2(cross, dot))
    return out


def disk_areas(geoms: NDArray[np.object_], centre: Centre, radius: float) -> FloatArray:
    """Area of each shapely polygon inside the disk of ``radius`` about ``centre``, exactly.

    Every edge ``(a, b)`` closes a triangle with the centre; the part of the
    edge inside the circle adds a straight triangle, the parts outside add
    circular sectors (a tangent edge is all sector).
    """
    import shapely

    out = np.zeros(len(geoms), dtype=np.float64)
    if len(geoms) == 0 or radius <= 0:
        return out
    parts, part_of = shapely.get_parts(geoms, return_index=True)
    polys = shapely.get_type_id(parts) == 3
    parts, part_of = parts[polys], part_of[polys]
    coords, ring = shapely.get_coordinates(shapely.get_exterior_ring(parts), return_index=True)
    same = ring[1:] == ring[:-1]
    c = np.asarray(centre, dtype=np.float64)
    a, b = coords[:-1][same] - c, coords[1:][same] - c
    owner = part_of[ring[:-1][same]]
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    edge = dd > 0  # a repeated vertex closes no triangle (and has no direction)
    a, b, d, dd, owner = a[edge], b[edge], d[edge], dd[edge], owner[edge]
    r2 = radius * radius
    mid = -np.einsum("ij,ij->i", a, d) / dd
    disc = mid * mid - (np.einsum("ij,ij->i", a, a) - r2) / dd
    root = np.sqrt(np.maximum(disc, 0.0))
    s0 = np.clip(mid - root, 0.0, 1.0)
    s1 = np.clip(mid + root, 0.0, 1.0)
    crossing = (disc > 0) & (s1 > s0)
    s0 = np.where(crossing, s0, 1.0)
    s1 = np.where(crossing, s1, 1.0)
    p0, p1 = a + s0[:, None] * d, a + s1[:, None] * d
    none = np.zeros(len(a), dtype=bool)
    area = (
        _sector_or_triangle(a, p0, r2, none)
        + _sector_or_triangle(p0, p1, r2, crossing)
        + _sector_or_triangle(p1, b, r2, none)
    )
    np.add.at(out, owner, area)
    return np.abs(out)


def _distance_range(geoms: NDArray[np.object_], centre: Centre) -> tuple[FloatArray, FloatArray]:
    """Smallest and largest distance from ``centre`` to each shape."""
    import shapely

    if len(geoms) == 0:
        return np.zeros(0), np.zeros(0)
    near = np.asarray(shapely.distance(shapely.points(*centre), geoms), dtype=np.float64)
    coords, index = shapely.get_coordinates(geoms, return_index=True)
    far = np.zeros(len(geoms), dtype=np.float64)
    np.maximum.at(far, index, np.hypot(coords[:, 0] - centre[0], coords[:, 1] - centre[1]))
    return near, far


def window_reach(window: PlaneDomain, centre: Centre) -> tuple[float, float]:
    """Distances from ``centre`` to the nearest and to the farthest point of the window's edge."""
    if isinstance(window, Circle):
        d = math.hypot(window.cx - centre[0], window.cy - centre[1])
        return max(0.0, window.radius - d), window.radius + d
    v = window.outline()
    w = np.roll(v, -1, axis=0)
    p = np.asarray(centre, dtype=np.float64)
    e = w - v
    t = np.clip(np.einsum("ij,ij->i", p - v, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
    foot = v + t[:, None] * e
    near = float(np.min(np.hypot(*(foot - p).T)))
    far = float(np.max(np.hypot(*(v - p).T)))
    return near, far


def window_area_in_disk(window: PlaneDomain, centre: Centre, radius: float) -> float:
    """Area of the window inside the disk of ``radius`` about ``centre``."""
    if radius <= 0 or not window.area > 0:
        return 0.0
    import shapely

    if isinstance(window, Circle) and (window.cx, window.cy) == tuple(centre):
        return math.pi * min(radius, window.radius) ** 2
    poly = np.array([shapely.Polygon(window.outline())], dtype=object)
    return float(disk_areas(poly, centre, radius)[0])


def ring_window_areas(window: PlaneDomain, centre: Centre, edges: FloatArray) -> FloatArray:
    """Area of the window in each ring ``[edges[k], edges[k + 1])``."""
    cum = np.array([window_area_in_disk(window, centre, float(r)) for r in edges])
    return np.maximum(np.diff(cum), 0.0)


def ring_mean_radius(
    window: PlaneDomain, centre: Centre, lo: float, hi: float, steps: int = 64
) -> float:
    """Mean distance from ``centre`` of the window's points in the ring ``[lo, hi)``.

    ``∫ r dA = [r A(r)] - ∫ A(r) dr`` with ``A(r)`` the window's area within
    ``r``, integrated by Simpson's rule over ``steps`` intervals (exact for a
    full annulus).
    """
    r = np.linspace(lo, hi, steps + 1)
    area = np.array([window_area_in_disk(window, centre, float(x)) for x in r])
    ring = float(area[-1] - area[0])
    if ring <= 0:
        return 0.5 * (lo + hi)
    h = (hi - lo) / steps
    simpson = h / 3.0 * (area[0] + area[-1] + 4.0 * area[1:-1:2].sum() + 2.0 * area[2:-1:2].sum())
    return float((hi * area[-1] - lo * area[0] - simpson) / ring)


def ring_edges(window: PlaneDomain, centre: Centre, width: float) -> FloatArray:
    """Ring radii from 0 to the farthest window point in steps of ``width``.

    The outermost rings, while their area in the window is less than half
    that of the ring inside them, are merged into it.
    """
    if not window.area > 0 or width <= 0:
        return np.zeros(1)
    _, far = window_reach(window, centre)
    if far <= 0:
        return np.zeros(1)
    k = max(1, math.ceil(far / width - 1e-9))
    edges = np.minimum(width * np.arange(k + 1, dtype=np.float64), far)
    edges[-1] = far
    areas = list(ring_window_areas(window, centre, edges))
    while len(areas) > 1 and areas[-1] < 0.5 * areas[-2]:
        edges = np.delete(edges, -2)
        areas[-2] += areas.pop()
    return edges


def ring_piece_areas(pieces: WindowPieces, centre: Centre, edges: FloatArray) -> FloatArray:
    """``(pieces, rings)`` area of each piece in each ring ``[edges[k], edges[k + 1])``."""
    import shapely

    m, k = len(pieces.geoms), len(edges) - 1
    cum = np.zeros((m, k + 1), dtype=np.float64)
    if m == 0 or k < 1:
        return np.zeros((m, max(k, 0)))
    full = np.asarray(shapely.area(pieces.geoms), dtype=np.float64)
    near, far = _distance_range(pieces.geoms, centre)
    for j, r in enumerate(edges[1:], start=1):
        rr = float(r)
        if pieces.disk is not None:
            rr = min(rr, pieces.disk[2])
        cum[far <= rr, j] = full[far <= rr]
        cut = (far > rr) & (near < rr)
        cum[cut, j] = disk_areas(pieces.geoms[cut], centre, rr)
    return np.maximum(np.diff(cum, axis=1), 0.0)


@dataclass(frozen=True)
class Tiles:
    """Cells of a grid over a window, cut to it.

    Attributes
    ----------
    bounds
        ``(T, 4)`` cell rectangles ``[x_min, x_max, y_min, y_max]``.
    ix, iy
        Column and row of each cell.
    area
        Area of each cell inside the window.
    """

    bounds: FloatArray
    ix: IntArray
    iy: IntArray
    area: FloatArray


def _areas_inside(window: PlaneDomain, cells: FloatArray) -> FloatArray:
    """Area inside the window of each rectangle ``[x_min, x_max, y_min, y_max]`` of ``cells``."""
    import shapely

    boxes = shapely.box(cells[:, 0], cells[:, 2], cells[:, 1], cells[:, 3])
    if isinstance(window, Circle):
        return disk_areas(np.asarray(boxes, dtype=object), (window.cx, window.cy), window.radius)
    poly = shapely.Polygon(window.outline())
    return np.asarray(shapely.area(shapely.intersection(boxes, poly)), dtype=np.float64)


def tile_grid(window: PlaneDomain, nx: int, ny: int) -> Tiles:
    """Grid of ``nx`` by ``ny`` cells over the window's bounding box.

    Cells with less than :data:`MIN_TILE_FILL` of their area inside the
    window are left out (all of them for an empty window).
    """
    x0, x1, y0, y1 = (float(b) for b in window.bounds())
    if not window.area > 0:
        nx = ny = 0
    xs = np.linspace(x0, x1, nx + 1)
    ys = np.linspace(y0, y1, ny + 1)
    rows: list[tuple[float, float, float, float, int, int, float]] = []
    for iy in range(ny):
        for ix in range(nx):
            cell = (xs[ix], xs[ix + 1], ys[iy], ys[iy + 1])
            inside = float(_areas_inside(window, np.array([cell]))[0])
            full = (cell[1] - cell[0]) * (cell[3] - cell[2])
            if full > 0 and inside >= MIN_TILE_FILL * full:
                rows.append((*cell, ix, iy, inside))
    arr = np.array([r[:4] for r in rows], dtype=np.float64).reshape(-1, 4)
    return Tiles(
        bounds=arr,
        ix=np.array([r[4] for r in rows], dtype=np.int64),
        iy=np.array([r[5] for r in rows], dtype=np.int64),
        area=np.array([r[6] for r in rows], dtype=np.float64),
    )


def tile_piece_areas(pieces: WindowPieces, tiles: Tiles) -> FloatArray:
    """``(pieces, tiles)`` area of each piece in each tile."""
    import shapely

    m = len(pieces.geoms)
    out = np.zeros((m, len(tiles.area)), dtype=np.float64)
    if m == 0:
        return out
    b = shapely.bounds(pieces.geoms)
    full = np.asarray(shapely.area(pieces.geoms), dtype=np.float64)
    straddle = np.zeros(m, dtype=bool)
    if pieces.disk is not None:
        cx, cy, radius = pieces.disk
        _, far = _distance_range(pieces.geoms, (cx, cy))
        straddle = far > radius
    for t, (x0, x1, y0, y1) in enumerate(tiles.bounds):
        touch = (b[:, 2] > x0) & (b[:, 0] < x1) & (b[:, 3] > y0) & (b[:, 1] < y1)
        within = touch & (b[:, 0] >= x0) & (b[:, 2] <= x1) & (b[:, 1] >= y0) & (b[:, 3] <= y1)
        easy = within & ~straddle
        out[easy, t] = full[easy]
        rest = np.flatnonzero(touch & ~easy)
        if len(rest) == 0:
            continue
        cut = shapely.clip_by_rect(pieces.geoms[rest], x0, y0, x1, y1)
        area = np.asarray(shapely.area(cut), dtype=np.float64)
        if pieces.disk is not None:
            cx, cy, radius = pieces.disk
            far_out = straddle[rest]
            area[far_out] = disk_areas(cut[far_out], (cx, cy), radius)
        out[rest, t] = area
    return out


def _wedges(centre: Centre, sectors: int, reach: float) -> NDArray[np.object_]:
    """``sectors`` equal wedges about ``centre`` (from angle 0, counter-clockwise) to ``reach``."""
    import shapely

    arc = 16  # chords per wedge: the wedges stay far outside the reach they cover
    cx, cy = centre
    out = []
    for s in range(sectors):
        t = 2.0 * np.pi * (s + np.linspace(0.0, 1.0, arc + 1)) / sectors
        ring = np.column_stack([cx + reach * np.cos(t), cy + reach * np.sin(t)])
        out.append(shapely.Polygon(np.vstack([[cx, cy], ring])))
    return np.asarray(out, dtype=object)


def _sector_of(geoms: NDArray[np.object_], centre: Centre, sectors: int) -> IntArray:
    """Wedge of each shape by the angle of its centroid (right for a shape inside one wedge)."""
    import shapely

    c = shapely.get_coordinates(shapely.centroid(geoms))
    angle = np.mod(np.arctan2(c[:, 1] - centre[1], c[:, 0] - centre[0]), 2.0 * np.pi)
    out: IntArray = np.minimum((angle / (2.0 * np.pi) * sectors).astype(np.int64), sectors - 1)
    return out


def _sector_pieces(
    pieces: WindowPieces, centre: Centre, wedges: NDArray[np.object_], reach: float
) -> tuple[WindowPieces, IntArray]:
    """Cut the pieces along the wedges' sides; return the parts and the wedge of each.

    A piece that crosses no side of a wedge (and is one polygon) lies in one
    wedge whole; only the others are cut.
    """
    import shapely

    geoms = pieces.geoms
    cx, cy = centre
    sectors = len(wedges)
    t = 2.0 * np.pi * np.arange(sectors) / sectors
    sides = shapely.multilinestrings(
        [[(cx, cy), (cx + reach * np.cos(a), cy + reach * np.sin(a))] for a in t]
    )
    cut = shapely.intersects(geoms, sides) | (shapely.get_type_id(geoms) != 3)
    parts = [geoms[~cut]]
    owners = [pieces.owner[~cut]]
    which = [_sector_of(geoms[~cut], centre, sectors)]
    for k, wedge in enumerate(wedges):
        inside = shapely.intersection(geoms[cut], wedge)
        keep = shapely.area(inside) > 0
        parts.append(inside[keep])
        owners.append(pieces.owner[cut][keep])
        which.append(np.full(int(keep.sum()), k, dtype=np.int64))
    out = WindowPieces(np.concatenate(parts), np.concatenate(owners), pieces.disk)
    return out, np.concatenate(which)


def ring_sector_areas(
    pieces: WindowPieces, window: PlaneDomain, centre: Centre, edges: FloatArray, sectors: int
) -> tuple[FloatArray, FloatArray]:
    """Particle area and window area in each cell of the rings cut into ``sectors`` wedges.

    The wedges are equal, about ``centre``; every outline is cut exactly to
    each cell (polygon clipping at the wedges' sides, the exact polygon–disk
    intersection at the ring radii), so the cells of a ring add up to it.

    Returns
    -------
    solid, area
        ``(rings, sectors)`` particle area and window area of each cell.
    """
    import shapely

    k = len(edges) - 1
    if k < 1 or not window.area > 0:
        return np.zeros((max(k, 0), sectors)), np.zeros((max(k, 0), sectors))
    reach = 2.0 * window_reach(window, centre)[1]
    wedges = _wedges(centre, sectors, reach)
    solid = np.zeros((sectors, k))
    if len(pieces.geoms):
        parts, sector = _sector_pieces(pieces, centre, wedges, reach)
        np.add.at(solid, sector, ring_piece_areas(parts, centre, edges))
    if isinstance(window, Circle):  # cut to the window's disk with the rings
        disk = (window.cx, window.cy, window.radius)
        own = WindowPieces(wedges, np.arange(sectors, dtype=np.int64), disk)
    else:
        inside = shapely.intersection(wedges, shapely.Polygon(window.outline()))
        own = WindowPieces(inside, np.arange(sectors, dtype=np.int64))
    return solid.T, ring_piece_areas(own, centre, edges).T


def tile_cell_areas(
    pieces: WindowPieces, window: PlaneDomain, tiles: Tiles, split: int
) -> tuple[FloatArray, FloatArray]:
    """Particle area and window area in each of ``split`` × ``split`` equal cells of every tile.

    Returns
    -------
    solid, area
        ``(tiles, split²)`` particle area and window area of each cell, cut
        exactly to it (the cells of a tile add up to the tile).
    """
    t = np.linspace(0.0, 1.0, split + 1)
    cells = []
    for x0, x1, y0, y1 in tiles.bounds:
        xs, ys = x0 + (x1 - x0) * t, y0 + (y1 - y0) * t
        cells += [(xs[i], xs[i + 1], ys[j], ys[j + 1]) for j in range(split) for i in range(split)]
    bounds = np.asarray(cells, dtype=np.float64).reshape(-1, 4)
    n = len(bounds)
    area = _areas_inside(window, bounds) if n else np.zeros(0)
    grid = Tiles(bounds, np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), area)
    solid = tile_piece_areas(pieces, grid).sum(axis=0)
    shape = (len(tiles.area), split * split)
    return solid.reshape(shape), area.reshape(shape)


def scatter_error(solid: FloatArray, area: FloatArray) -> FloatArray:
    """Estimate the standard error of each region's area fraction from the scatter of its cells.

    A region's fraction ``phi = sum(solid) / sum(area)`` is the mean of its
    cells' fractions ``phi_c`` weighted by their shares ``w_c`` of its area;
    its variance is estimated as ``m / (m - 1) * sum((w_c (phi_c - phi))^2)``
    over the ``m`` cells inside the window (NaN with fewer than 2).

    Parameters
    ----------
    solid, area
        ``(regions, cells)`` particle area and window area of each cell.

    Examples
    --------
    Two cells of equal area at 0.8 and 0.9: the mean's standard error is 0.05.

    >>> scatter_error(np.array([[0.8, 0.9]]), np.ones((1, 2))).round(12).tolist()
    [0.05]
    """
    solid = np.asarray(solid, dtype=np.float64)
    area = np.asarray(area, dtype=np.float64)
    inside = area > 0
    m = inside.sum(axis=1)
    total = area.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = solid.sum(axis=1) / total
        share = np.where(inside, area / total[:, None], 0.0)
        cell_phi = np.where(inside, solid / np.where(inside, area, 1.0), 0.0)
        spread = np.sum((share * (cell_phi - phi[:, None])) ** 2, axis=1)
        err = np.sqrt(m / (m - 1.0) * spread)
    return np.asarray(np.where(m >= 2, err, np.nan), dtype=np.float64)
