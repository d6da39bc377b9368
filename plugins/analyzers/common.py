"""Helpers shared by the analyzers of both dimensions: interior window, tolerances, results."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any, NamedTuple, TypeVar

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel

from regopack.base.errors import ConfigError
from regopack.base.units import length_scale
from regopack.geometry.domain import Box, Cylinder
from regopack.packing.core import Packing
from regopack.registry.interfaces import Analyzer

DEFAULT_TOL = 0.05
"""Default contact tolerance at the built-in scale (``d_min = 2``): ``tol = d_min / 40``."""

DEFAULT_TOL_MAX = 0.5
"""Default largest tolerance kept at the built-in scale: ``tol_max = d_min / 4``."""


def contact_tolerances(
    tol: float | None, tol_max: float | None, packing: Any, name: str = "contacts"
) -> tuple[float, float]:
    """``(tol, tol_max)`` of a contact analysis of ``packing``: as given, or the scaled defaults.

    An omitted ``tol`` is ``d_min / 40`` and an omitted ``tol_max`` is
    ``max(d_min / 4, tol)``, ``d_min`` the packing's reference diameter
    (:func:`regopack.base.units.reference_diameter`); computed as ``0.05 * d_min / 2``
    and ``0.5 * d_min / 2``, they are exactly 0.05 and 0.5 at the built-in
    scenes' ``d_min = 2``.

    Raises
    ------
    ConfigError
        When ``tol_max`` is below ``tol``.
    """
    scale = length_scale(packing)
    t = DEFAULT_TOL * scale if tol is None else float(tol)
    t_max = max(DEFAULT_TOL_MAX * scale, t) if tol_max is None else float(tol_max)
    if t_max < t:
        raise ConfigError(f"{name}: tol_max ({t_max:g}) must be at least tol ({t:g})")
    return t, t_max


def interior_margin(packing: Packing, margin: float | None = None) -> float:
    """Exclusion margin from the walls: ``margin`` if given, else the scene's d_max.

    The paper excludes particles within one maximum particle diameter of a wall.
    ``d_max`` is read from the run's statistics, the scene's size section, or,
    failing both, twice the largest drawn radius.
    """
    if margin is not None:
        return float(margin)
    stat = packing.stats.get("interior_margin")
    if stat is not None and np.isfinite(stat):
        return float(stat)
    size: Any = packing.scene.get("size", {}) if isinstance(packing.scene, dict) else {}
    if isinstance(size, dict) and "d_max" in size:
        return float(size["d_max"])
    return 2.0 * float(np.max(packing.radius)) if packing.n_particles else 0.0


def interior_window(packing: Packing, margin: float) -> Any:
    """Return the domain inset by ``margin`` from every wall (a periodic domain: all of it).

    A :class:`~regopack.geometry.domain.PlaneDomain` in 2D, a
    :class:`~regopack.geometry.domain.Box` in 3D.
    """
    return packing.domain.interior(margin)


def interior_mask(packing: Packing, margin: float) -> NDArray[np.bool_]:
    """Placed particles whose centre lies farther than ``margin`` from every wall."""
    inside = interior_window(packing, margin).contains(packing.centre)
    return np.asarray(inside & packing.placed, dtype=np.bool_)


def eta_of(packing: Packing) -> float | None:
    """Return the packing control coefficient of the run, when the scene used one.

    The scene's ``density.eta``, or the η a density target chose (the
    packing's stat ``eta``).
    """
    density = packing.scene.get("density", {}) if isinstance(packing.scene, dict) else {}
    value = density.get("eta") if isinstance(density, dict) else None
    if value is None:
        value = packing.stats.get("eta")
    return float(value) if value is not None else None


class FoundContacts(NamedTuple):
    """What a contact search finds in a packing of one dimension ``d``.

    Attributes
    ----------
    pairs, threshold
        Every pair ``(i, j)`` of particle indices, ``i < j``, in contact at
        ``tol_max``, and the tolerance above which each is in contact.
    columns
        The columns of the table ``contacts`` for the contacts at ``tol``
        (``i``, ``j``, ``area``, ``width``, ``depth`` and those of the
        dimension), without ``normal_*`` and ``point_*``.
    normal, point
        ``(n, d)``: unit normal (from ``i`` to ``j``) and point of each contact at ``tol``.
    pair_normal
        ``(m, d)`` unit normal of every pair, where the search gives it (3D).
    """

    pairs: NDArray[np.int64]
    threshold: NDArray[np.float64]
    columns: dict[str, NDArray[Any]]
    normal: NDArray[np.float64]
    point: NDArray[np.float64]
    pair_normal: NDArray[np.float64] | None = None


class Measured(Analyzer):
    """An analyzer whose :meth:`compute` keeps its scalars in ``_results``."""

    _results: dict[str, Any] | None = None

    def _need(self) -> dict[str, Any]:
        """Return the scalars of the last :meth:`compute`; refuse before it."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return self._results

    def results(self) -> dict[str, Any]:
        """Scalars of the last :meth:`compute` (see the class)."""
        return dict(self._need())


def periodic_images(packing: Packing, pad: float) -> tuple[Packing, NDArray[np.int64]]:
    """Return the packing with ghost copies of the placed particles within ``pad`` of a side.

    Each ghost is its particle translated by one period along x, y or both,
    towards the inside of the domain; ghosts follow the particles (indices
    ``>= n``). Returns the extended packing and ``origin``, the original index
    of every particle and ghost. The domain must be periodic.
    """
    dom: Any = packing.domain
    lx, ly = dom.width, dom.height
    idx = np.flatnonzero(packing.placed)
    c = packing.centre[idx]
    near_lo_x = c[:, 0] < dom.xmin + pad
    near_hi_x = c[:, 0] > dom.xmax - pad
    near_lo_y = c[:, 1] < dom.ymin + pad
    near_hi_y = c[:, 1] > dom.ymax - pad
    ghosts: list[NDArray[np.int64]] = []
    shifts: list[NDArray[np.float64]] = []
    for sx, mx in ((0.0, None), (lx, near_lo_x), (-lx, near_hi_x)):
        for sy, my in ((0.0, None), (ly, near_lo_y), (-ly, near_hi_y)):
            if mx is None and my is None:
                continue
            sel = np.ones(len(idx), dtype=bool)
            if mx is not None:
                sel &= mx
            if my is not None:
                sel &= my
            ghosts.append(idx[sel])
            shifts.append(np.tile([sx, sy], (int(sel.sum()), 1)))
    g = np.concatenate(ghosts).astype(np.int64)
    shift = np.concatenate(shifts).reshape(-1, 2)
    n = packing.n_particles
    origin = np.concatenate([np.arange(n, dtype=np.int64), g])
    counts = np.diff(packing.offsets)
    ext_counts = np.concatenate([counts, counts[g]])
    offsets = np.zeros(len(origin) + 1, dtype=np.int64)
    np.cumsum(ext_counts, out=offsets[1:])
    starts = np.repeat(packing.offsets[origin], ext_counts)
    within = np.arange(int(offsets[-1])) - np.repeat(offsets[:-1], ext_counts)
    # ghosts are numbered after the placed particles, so the extended packing keeps
    # the format's order of placement 0 .. n_placed - 1
    index = np.concatenate([packing.insertion_index, np.arange(len(g)) + packing.n_placed])
    ext = replace(
        packing,
        radius=packing.radius[origin],
        mineral=packing.mineral[origin],
        vertices=packing.vertices[starts + within],
        offsets=offsets,
        orientation=packing.orientation[origin],
        centre=np.concatenate([packing.centre, packing.centre[g] + shift]),
        insertion_index=index.astype(np.int64),
        rounding=None if packing.rounding is None else packing.rounding[origin],
    )
    return ext, origin


ROUNDED_CONTACT_ERROR = 0.01
"""Largest radial error of a rounded outline's polygon in the contact analysis, per unit tol."""


def rounded_as_polygons(packing: Packing, error: float) -> Packing:
    """Return the packing with every rounded outline replaced by a circumscribed polygon.

    The polygon of a particle rounded by ``rho`` is its core grown by
    ``rho / cos(pi / k)`` with ``k`` segments per full turn, chosen so that the
    polygon lies outside the rounded outline by at most ``error`` (and touches
    it at the middle of every edge). Sharp particles are unchanged.
    """
    import shapely

    if not packing.rounded:
        return packing
    rho = packing.rounding_radius
    n = packing.n_particles
    outlines: list[NDArray[np.float64]] = []
    for j in range(n):
        local = packing.vertices[packing.offsets[j] : packing.offsets[j + 1]]
        if rho[j] <= 0.0:
            outlines.append(local)
            continue
        k = max(16, 4 * math.ceil(math.pi * math.sqrt(rho[j] / (2.0 * error)) / 4.0))
        grown = shapely.buffer(
            shapely.convex_hull(shapely.multipoints(local)),
            rho[j] / math.cos(math.pi / k),
            quad_segs=k // 4,
        )
        ring = np.asarray(shapely.get_exterior_ring(shapely.orient_polygons(grown)).coords)[:-1]
        outlines.append(ring)
    counts = np.array([len(o) for o in outlines], dtype=np.int64)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return replace(
        packing,
        vertices=np.concatenate(outlines) if n else np.zeros((0, 2)),
        offsets=offsets,
        rounding=None,
    )


_Config = TypeVar("_Config", bound=BaseModel)


def scaled_defaults(config: _Config, packing: Any, defaults: Mapping[str, Any]) -> _Config:
    """Return ``config`` with its omitted lengths set to ``defaults`` scaled to ``packing``.

    ``defaults`` maps a field of ``config`` to its default at the built-in
    scale (``d_min = 2``): a length or a tuple of lengths. A field left
    ``None`` becomes that value times :func:`~regopack.base.units.length_scale`
    (``d_min / 2``), which is exactly the value at ``d_min = 2``; a field the
    user set is kept as given.
    """
    scale = length_scale(packing)
    update: dict[str, Any] = {}
    for key, value in defaults.items():
        if getattr(config, key) is not None:
            continue
        if isinstance(value, tuple):
            update[key] = tuple(float(v) * scale for v in value)
        else:
            update[key] = float(value) * scale
    return config.model_copy(update=update)


def solid_volumes(packing: Packing[Box] | Packing[Cylinder]) -> NDArray[np.float64]:
    """Volume of every solid (:attr:`regopack.geometry.solids.SolidBatch.volume`)."""
    return packing.solids.volume
