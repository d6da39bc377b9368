"""The solid fraction of a window: the share of its area (2D) or volume (3D) that particles cover.

Particles that cross the window's edges are clipped exactly: polygons by
shapely (:func:`phi_in_window`), polyhedra by the planes of a box's faces and
spheres analytically (:func:`phi_in_box`). In a coaxial cylinder window
(:func:`phi_in_cylinder`) the solids it cuts are measured by
:mod:`regopack.geometry.cylinder_volume` (slices integrated over height, to
about ``1e-11`` of each cut solid's volume). :func:`fraction_in` takes any.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import ConvexHull

from regopack.geometry.cylinder_volume import polyhedra_in_cylinder, spheres_in_cylinder
from regopack.geometry.domain import Box, Cylinder, Domain, PlaneDomain, Rectangle
from regopack.geometry.population import FloatArray
from regopack.geometry.sphere_volume import sphere_in_box
from regopack.packing.core import Packing

__all__ = ["fraction_in", "phi_in_box", "phi_in_cylinder", "phi_in_window"]

SHAPELY_BATCH = 1 << 16
"""Particles turned into shapely polygons at a time when measuring a covered area."""


def _covered_by_parts(kind: type[PlaneDomain]) -> bool:
    """Whether ``kind.covered_area`` is the sum of ``kind.covered_parts``."""

    def owner(name: str) -> type:
        return next(c for c in kind.__mro__ if name in c.__dict__)

    return owner("covered_area") is PlaneDomain or issubclass(
        owner("covered_parts"), owner("covered_area")
    )


def phi_in_window(
    packing: Packing, window: PlaneDomain | tuple[float, float, float, float]
) -> float:
    """Area fraction of ``window`` covered by placed particles.

    ``window`` is a domain (e.g. ``packing.domain.interior(margin)``) or the
    bounds ``(xmin, xmax, ymin, ymax)`` of a rectangle. Particles are clipped
    exactly to the window. Returns NaN for an empty window.
    """
    if not isinstance(window, PlaneDomain):
        window = Rectangle(*(float(v) for v in window))
    if not window.area > 0:
        return math.nan
    if not _covered_by_parts(type(window)):
        # a domain that redefines its covered area alone gets every polygon at once
        return window.covered_area(packing.to_shapely()) / window.area
    # polygons a batch at a time, so that a large packing never holds them all
    placed = np.flatnonzero(packing.placed)
    groups: list[list[FloatArray]] = []
    for start in range(0, max(len(placed), 1), SHAPELY_BATCH):
        parts = window.covered_parts(packing.to_shapely(placed[start : start + SHAPELY_BATCH]))
        groups = groups or [[] for _ in parts]
        for group, part in zip(groups, parts, strict=True):
            group.append(part)
    return window.add_parts([np.concatenate(group) for group in groups]) / window.area


def _clip(points: FloatArray, normal: FloatArray, offset: float) -> FloatArray:
    """Points whose hull is the part of ``points``' hull with ``normal . x <= offset``.

    The points on that side, and where the segments from them to the points
    on the other side cross the plane (the edges' crossings among them).
    """
    side = points @ normal - offset
    inside = points[side <= 0]
    outside = points[side > 0]
    if outside.shape[0] == 0 or inside.shape[0] == 0:
        return inside
    si = side[side <= 0][:, None]
    so = side[side > 0][None, :]
    t = si / (si - so)  # (n_in, n_out) in [0, 1)
    cross = inside[:, None, :] + t[:, :, None] * (outside[None, :, :] - inside[:, None, :])
    return np.vstack([inside, cross.reshape(-1, 3)])


def phi_in_box(packing: Packing[Box], window: Box, volume: FloatArray | None = None) -> float:
    """Volume fraction of ``window`` covered by the placed solids, clipped exactly.

    A sharp polyhedron that crosses the window's faces is clipped by their
    planes (the hull of its vertices inside and of the crossings of the
    segments between its vertices, which holds its edges); a sphere is
    clipped by :func:`regopack.geometry.sphere_volume.sphere_in_box`; a rounded
    polyhedron that crosses a face raises ``NotImplementedError``.
    NaN for an empty window. ``volume`` gives the solids' volumes when they
    are known already (default: :attr:`regopack.geometry.solids.SolidBatch.volume`).
    """
    if not window.volume > 0:
        return math.nan
    solids = packing.solids
    if volume is None:
        volume = solids.volume
    lo = np.array([window.xmin, window.ymin, window.zmin])
    hi = np.array([window.xmax, window.ymax, window.zmax])
    rho = solids.rounding_radius
    # bounding boxes of all solids at once (rounding is monotone: min(v + c) = min(v) + c)
    starts = packing.offsets[:-1]
    box_lo = np.minimum.reduceat(packing.vertices, starts) + packing.centre - rho[:, None]
    box_hi = np.maximum.reduceat(packing.vertices, starts) + packing.centre + rho[:, None]
    whole = np.all(box_lo >= lo, axis=1) & np.all(box_hi <= hi, axis=1)
    apart = np.any(box_hi <= lo, axis=1) | np.any(box_lo >= hi, axis=1)
    placed = packing.placed
    total = float(np.sum(volume[placed & whole]))
    for j in np.flatnonzero(placed & ~whole & ~apart).tolist():
        pts = packing.world_vertices(int(j))
        if rho[j] > 0:
            if pts.shape[0] != 1:
                raise NotImplementedError("clipping a rounded polyhedron to a window")
            total += sphere_in_box(pts[0], float(rho[j]), lo, hi)
            continue
        for axis in range(3):
            for sign, bound in ((-1.0, -lo[axis]), (1.0, hi[axis])):
                if pts.shape[0] < 4:
                    break
                normal = np.zeros(3)
                normal[axis] = sign
                pts = _clip(pts, normal, bound)
                if pts.shape[0] >= 4:
                    try:
                        pts = pts[ConvexHull(pts).vertices]
                    except Exception:  # a flat remainder: no volume
                        pts = pts[:0]
        if pts.shape[0] >= 4:
            try:
                total += float(ConvexHull(pts).volume)
            except Exception:  # a flat remainder: no volume
                pass
    return total / window.volume


def cylinder_volumes(
    packing: Packing, window: Cylinder, volume: FloatArray | None = None
) -> FloatArray:
    """Volume of each placed solid inside the cylinder ``window`` (0 for those not placed).

    A solid wholly inside counts its ``volume`` (default:
    :attr:`regopack.geometry.solids.SolidBatch.volume`); one the window cuts
    is measured by :func:`~regopack.geometry.cylinder_volume.polyhedra_in_cylinder`
    or :func:`~regopack.geometry.cylinder_volume.spheres_in_cylinder` (to about
    ``1e-11`` of its volume); a rounded polyhedron that the window cuts raises
    ``NotImplementedError``.
    """
    solids = packing.solids
    if volume is None:
        volume = solids.volume
    rho = solids.rounding_radius
    axis = (window.cx, window.cy)
    out = np.zeros(packing.n_particles)
    starts = packing.offsets[:-1]
    v = packing.vertices
    # each solid's reach from the axis and its heights (rounding adds rho to both)
    rel = v + np.repeat(packing.centre, np.diff(packing.offsets), axis=0)
    radial = np.hypot(rel[:, 0] - window.cx, rel[:, 1] - window.cy)
    reach = np.maximum.reduceat(radial, starts) + rho
    z_lo = np.minimum.reduceat(rel[:, 2], starts) - rho
    z_hi = np.maximum.reduceat(rel[:, 2], starts) + rho
    placed = packing.placed
    whole = placed & (reach <= window.radius) & (z_lo >= window.zmin) & (z_hi <= window.zmax)
    out[whole] = volume[whole]
    # below the floor or above the lid (one beyond the side wall gets 0 from the cut)
    apart = (z_hi <= window.zmin) | (z_lo >= window.zmax)
    cut = np.flatnonzero(placed & ~whole & ~apart)
    if cut.size == 0 or not window.radius > 0:
        return out
    ball = np.diff(packing.offsets)[cut] == 1
    if np.any(rho[cut[~ball]] > 0):
        raise NotImplementedError("clipping a rounded polyhedron to a window")
    balls, polys = cut[ball], cut[~ball]
    if balls.size:
        centres = packing.centre[balls] + v[starts[balls]]
        out[balls] = spheres_in_cylinder(
            centres, rho[balls], axis, window.radius, window.zmin, window.zmax
        )
    if polys.size:
        out[polys] = polyhedra_in_cylinder(
            [packing.world_vertices(int(j)) for j in polys],
            axis,
            window.radius,
            window.zmin,
            window.zmax,
        )
    return out


def phi_in_cylinder(packing: Packing, window: Cylinder, volume: FloatArray | None = None) -> float:
    """Volume fraction of the cylinder ``window`` covered by the placed solids.

    ``window`` is a cylinder with a vertical axis, e.g. the interior
    ``packing.domain.interior(margin)`` of a cylinder packing (a coaxial
    cylinder), a horizontal layer of it, or any other. Solids wholly inside
    count whole; the solids it cuts, by their volume inside
    (:func:`cylinder_volumes`: each to about ``1e-11`` of its volume, so the
    fraction to about ``1e-11`` of the cut solids' volume over the window's).
    NaN for an empty window. ``volume`` gives the solids' volumes when they
    are known already.
    """
    if not window.volume > 0:
        return math.nan
    return float(np.sum(cylinder_volumes(packing, window, volume))) / window.volume


def fraction_in(
    packing: Packing,
    window: Domain | tuple[float, ...],
    volume: FloatArray | None = None,
) -> float:
    """Solid fraction of ``window`` in a 2D or a 3D packing (NaN for an empty window).

    ``window`` is a domain of the packing's dimension (a box or a cylinder in 3D), or its bounds
    (``(xmin, xmax, ymin, ymax)``, with ``zmin, zmax`` in 3D). ``volume``
    gives 3D solids' volumes when they are known already.
    """
    dimension = packing.dimension
    if not isinstance(window, Domain):
        bounds = [float(v) for v in window]
        window = Box(*bounds) if dimension == 3 else Rectangle(*bounds)
    if dimension == 3 and isinstance(window, Box):
        return phi_in_box(packing, window, volume)
    if dimension == 3 and isinstance(window, Cylinder):
        return phi_in_cylinder(packing, window, volume)
    if dimension == 2 and isinstance(window, PlaneDomain):
        return phi_in_window(packing, window)
    raise TypeError(f"a {window.dimension}D window for a {dimension}D packing")
