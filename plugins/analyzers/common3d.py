"""Helpers shared by the 3D analyzers: the packing check, the interior window, the cap model."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box
from regopack.packing.core3d import Packing3D
from regopack.plugins.analyzers.common import interior_margin
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def as_packing3d(packing: Any, analyzer: Analyzer) -> Packing3D:
    """Return ``packing`` if it is a 3D packing; refuse anything else in one line."""
    if not isinstance(packing, Packing3D):
        raise ConfigError(
            f"analyzer {analyzer.name!r} analyses 3D packings, not a {type(packing).__name__}"
        )
    return packing


def interior_margin3d(packing: Packing3D, margin: float | None = None) -> float:
    """Exclusion margin from the walls: ``margin`` if given, else the scene's d_max.

    The 2D rule (:func:`regopack.plugins.analyzers.common.interior_margin`),
    which reads only what both packings have: the run's statistics, then the
    scene's size section, then twice the largest drawn radius.
    """
    return interior_margin(cast(Any, packing), margin)


def interior_window3d(packing: Packing3D, margin: float) -> Box:
    """Return the box inset by ``margin`` from every wall (a periodic box: all of it)."""
    return packing.domain.interior(margin)


def interior_mask3d(packing: Packing3D, margin: float) -> BoolArray:
    """Placed particles whose centre lies farther than ``margin`` from every wall."""
    inside = interior_window3d(packing, margin).contains(packing.centre)
    return np.asarray(inside & packing.placed, dtype=np.bool_)


def solid_volumes(packing: Packing3D) -> FloatArray:
    """Volume of every solid, all faces at once (as ``SolidBatch.volume``).

    Each face contributes the cone from the centre over it, ``(A_f . n_f) b_f / 3``,
    with the area vector ``A_f = 1/2 sum_k p_k x p_(k+1)`` of its vertex loop;
    a sphere has ``4/3 pi r^3``. Rounded polyhedra raise ``NotImplementedError``.
    """
    n = packing.n_particles
    rho = packing.solids.rounding_radius
    faces = np.diff(packing.face_offsets)
    if np.any((faces > 0) & (rho > 0)):
        raise NotImplementedError("the volume of a rounded polyhedron")
    out = (4.0 / 3.0) * np.pi * rho**3
    n_faces = packing.normals.shape[0]
    if n_faces == 0:
        return np.asarray(out, dtype=np.float64)
    sizes = np.diff(packing.face_vertex_offsets)
    owner = np.repeat(np.repeat(np.arange(n), faces), sizes)
    v = packing.vertices[packing.offsets[owner] + packing.face_vertices]
    nxt = np.arange(v.shape[0]) + 1
    nxt[packing.face_vertex_offsets[1:] - 1] = packing.face_vertex_offsets[:-1]
    area = 0.5 * np.add.reduceat(np.cross(v, v[nxt]), packing.face_vertex_offsets[:-1])
    cone = np.einsum("ij,ij->i", area, packing.normals) * packing.support / 3.0
    face_owner = np.repeat(np.arange(n), faces)
    out = out + np.bincount(face_owner, weights=cone, minlength=n)
    return np.asarray(out, dtype=np.float64)


def equivalent_cap(volume: FloatArray, area: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Spherical cap with base area ``area`` and volume ``volume``: its height and sphere radius.

    The cap of base radius ``a = sqrt(area / pi)`` and height ``h`` has the
    volume ``pi h (3 a^2 + h^2) / 6``; ``h`` is the one positive root of that
    cubic, found by Newton's method from above (the cubic is convex for
    ``h > 0``, so the iterates fall monotonically onto the root, without
    cancellation however thin the cap). The sphere radius is
    ``(a^2 + h^2) / (2 h)``. Both are 0 where the volume or the area is not positive.

    Examples
    --------
    A hemisphere of radius 1:

    >>> h, r = equivalent_cap(np.array([2 * np.pi / 3]), np.array([np.pi]))
    >>> round(float(h[0]), 12), round(float(r[0]), 12)
    (1.0, 1.0)
    """
    volume = np.asarray(volume, dtype=np.float64)
    area = np.asarray(area, dtype=np.float64)
    ok = (volume > 0) & (area > 0)
    a2 = np.where(ok, area / np.pi, 1.0)
    v6 = np.where(ok, 6.0 * volume / np.pi, 0.0)
    # both starting points lie above the root: f(2V/A) = (2V/A)^3, f(cbrt(6V/pi)) = 3 a^2 h > 0
    h = np.minimum(2.0 * np.where(ok, volume / np.where(ok, area, 1.0), 0.0), np.cbrt(v6))
    for _ in range(100):
        step = (h * h * h + 3.0 * a2 * h - v6) / (3.0 * h * h + 3.0 * a2)
        h = h - step
        if not np.any(step > 1e-15 * h):
            break
    h = np.where(ok, h, 0.0)
    radius = np.where(ok & (h > 0), (a2 + h * h) / (2.0 * np.where(h > 0, h, 1.0)), 0.0)
    return h, radius
