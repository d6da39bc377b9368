"""The regions of the homogeneity of a 3D packing: horizontal layers and nested boxes.

The interior window is cut into ``layers`` horizontal slabs of equal height
along z (the vertical: packings of the available-surface inserter grow from
the box's centre, a deposit from its floor), and into ``shells``: the
differences of nested boxes about the window's centre, whose half-sides grow
in equal steps to the window's. Each region gets the number density of the
centres in it, the mean volume-equivalent diameter of those particles, and
the volume fraction of the solids clipped exactly to it
(:func:`regopack.packing.solid_fraction.phi_in_box`; a shell's is the difference of its two
boxes'). A homogeneous packing has the same values in every region, up to the
noise of its particle count.

In a cylinder (:func:`layers_and_shells_cylinder`) the window is the coaxial
cylinder inside the walls: a layer is a disc of its cross-section (volume
``pi R^2 dz``), whose φ error comes from :data:`RINGS` rings of equal area
about the axis (rather than columns); a shell is the difference of nested
coaxial cylinders about the window's centre, whose radii and half-heights
grow in equal steps to the window's. The solids are clipped to each by
:func:`regopack.packing.solid_fraction.phi_in_cylinder`.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import Box, Cylinder, PeriodicBox
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import solid_volumes
from regopack.plugins.analyzers.regions import scatter_error

FloatArray = NDArray[np.float64]

LAYER_SPLIT = 3
"""Each layer is cut into this many by this many columns for the error of its φ."""

RINGS = 3
"""A cylinder's layer is cut into this many rings of equal area for the error of its φ."""


def _region_stats(
    packing: Packing[Box] | Packing[Cylinder], inside: NDArray[np.bool_], volume: float
) -> tuple[int, float, float]:
    """Centres inside, their number density and mean diameter (NaN when none)."""
    n = int(inside.sum())
    d = 2.0 * packing.radius[inside]
    return n, n / volume if volume > 0 else math.nan, float(d.mean()) if n else math.nan


def _images(p3: Packing[Box]) -> list[Packing[Box]]:
    """Return the packing, and in a periodic box its 26 images about the cell too."""
    if not p3.domain.periodic:
        return [p3]
    period = np.array(p3.domain.size)
    shifts = [np.array(s, dtype=float) * period for s in itertools.product((-1, 0, 1), repeat=3)]
    return [dataclasses.replace(p3, centre=p3.centre + shift) for shift in shifts]


def _wrapped_centres(p3: Packing[Box]) -> FloatArray:
    """Return the centres, wrapped into the cell in a periodic box."""
    domain = p3.domain
    if not isinstance(domain, PeriodicBox):
        return p3.centre
    return np.asarray(domain.wrap(p3.centre), dtype=np.float64)


def _cv(values: list[float]) -> float | None:
    v = np.asarray([x for x in values if math.isfinite(x)])
    if v.size < 2 or not v.mean() > 0:
        return None
    return float(v.std(ddof=1) / v.mean())


def layers_and_shells(
    p3: Packing[Box], w: Box, margin: float, n_layers: int, n_shells: int
) -> tuple[dict[str, dict[str, FloatArray]], dict[str, Any]]:
    """Measure every layer and shell of the interior window ``w``.

    Returns the tables ``homogeneity_layers`` and ``homogeneity_shells`` (one
    row per region, bottom to top and centre outwards) and the scalars: the
    per-region lists and their coefficients of variation.
    """
    from regopack.packing.solid_fraction import phi_in_box as clip

    volume = solid_volumes(p3)
    images = _images(p3)

    def phi_in_box(p: Packing[Box], window: Box, vol: FloatArray) -> float:
        # in a periodic box a solid that crosses a face fills the window in its images
        return sum(clip(image, window, vol) for image in images)

    centre = _wrapped_centres(p3)
    placed = p3.placed
    with np.errstate(invalid="ignore"):
        layers: dict[str, list[float]] = {k: [] for k in ("z_lo", "z_hi", "n", "density")}
        layers.update({"phi": [], "mean_diameter": []})
        errors: dict[str, list[float]] = {k: [] for k in ("density", "phi", "mean_diameter")}
        split = np.linspace(0.0, 1.0, LAYER_SPLIT + 1)
        xs = w.xmin + (w.xmax - w.xmin) * split
        ys = w.ymin + (w.ymax - w.ymin) * split
        edges = np.linspace(w.zmin, w.zmax, n_layers + 1)
        # a periodic cell holds its wrapped centres in [lo, hi)
        low = np.greater_equal if p3.domain.periodic else np.greater
        inside_xy = (
            placed
            & low(centre[:, 0], w.xmin)
            & (centre[:, 0] < w.xmax)
            & low(centre[:, 1], w.ymin)
            & (centre[:, 1] < w.ymax)
        )
        # a margin that leaves no window leaves no regions
        for lo, hi in itertools.pairwise(edges if w.volume > 0 else []):
            slab = Box(w.xmin, w.xmax, w.ymin, w.ymax, float(lo), float(hi))
            sel = inside_xy & (centre[:, 2] >= lo) & (centre[:, 2] < hi)
            n, density, diameter = _region_stats(p3, sel, slab.volume)
            columns = [
                Box(float(xs[a]), float(xs[a + 1]), float(ys[b]), float(ys[b + 1]), lo, hi)
                for a in range(LAYER_SPLIT)
                for b in range(LAYER_SPLIT)
            ]
            parts = np.array([[phi_in_box(p3, col, volume) * col.volume for col in columns]])
            cells = np.array([[col.volume for col in columns]])
            for key, value in zip(
                layers,
                (lo, hi, n, density, parts.sum() / slab.volume, diameter),
                strict=True,
            ):
                layers[key].append(float(value))
            d = 2.0 * p3.radius[sel]
            errors["density"].append(math.sqrt(max(n, 1)) / slab.volume)
            errors["phi"].append(float(scatter_error(parts, cells)[0]))
            errors["mean_diameter"].append(
                float(d.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
            )
        shells: dict[str, list[float]] = {k: [] for k in ("half_lo", "half_hi", "n")}
        shells.update({"density": [], "phi": [], "mean_diameter": []})
        c = np.array(w.center)
        half = 0.5 * np.array(w.size)
        steps = np.linspace(0.0, 1.0, n_shells + 1)
        inner_solid, inner_volume = 0.0, 0.0
        shell_errors: dict[str, list[float]] = {"density": [], "mean_diameter": []}
        reach = np.max(np.abs(centre - c) / np.where(half > 0, half, np.inf), axis=1)
        for lo, hi in itertools.pairwise(steps if w.volume > 0 else []):
            box = Box(*(v for a in range(3) for v in (c[a] - hi * half[a], c[a] + hi * half[a])))
            solid = phi_in_box(p3, box, volume) * box.volume
            sel = placed & (reach >= lo) & (reach < hi)
            shell_volume = box.volume - inner_volume
            n, density, diameter = _region_stats(p3, sel, shell_volume)
            phi = (solid - inner_solid) / shell_volume if shell_volume > 0 else math.nan
            for key, value in zip(
                shells,
                (lo * half.min(), hi * half.min(), n, density, phi, diameter),
                strict=True,
            ):
                shells[key].append(float(value))
            d = 2.0 * p3.radius[sel]
            shell_errors["density"].append(
                math.sqrt(max(n, 1)) / shell_volume if shell_volume > 0 else math.nan
            )
            shell_errors["mean_diameter"].append(
                float(d.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
            )
            inner_solid, inner_volume = solid, box.volume

    whole = inside_xy & low(centre[:, 2], w.zmin) & (centre[:, 2] < w.zmax)
    n_whole, density_whole, d_whole = (
        _region_stats(p3, whole, w.volume) if w.volume > 0 else (0, math.nan, math.nan)
    )
    phi_whole = phi_in_box(p3, w, volume) if w.volume > 0 else math.nan
    overall = (n_whole, density_whole, phi_whole, d_whole)
    return _assembled(w, margin, overall, (layers, errors), (shells, shell_errors))


def layers_and_shells_cylinder(
    p3: Packing[Cylinder], w: Cylinder, margin: float, n_layers: int, n_shells: int
) -> tuple[dict[str, dict[str, FloatArray]], dict[str, Any]]:
    """Measure every layer and shell of the coaxial interior window ``w`` of a cylinder.

    The tables and scalars of :func:`layers_and_shells`: layers are discs of
    the window's cross-section, shells differences of nested coaxial
    cylinders (``half_lo``, ``half_hi`` are their smaller half-extents,
    ``min(radius, height / 2)`` scaled, as a box's smallest half-side).
    """
    from regopack.packing.solid_fraction import cylinder_volumes

    volume = solid_volumes(p3)

    def solid_in(window: Cylinder) -> float:
        if not window.volume > 0:
            return 0.0
        return float(np.sum(cylinder_volumes(p3, window, volume)))

    centre = p3.centre
    placed = p3.placed
    axis_r = np.hypot(centre[:, 0] - w.cx, centre[:, 1] - w.cy)
    layers: dict[str, list[float]] = {k: [] for k in ("z_lo", "z_hi", "n", "density")}
    layers.update({"phi": [], "mean_diameter": []})
    errors: dict[str, list[float]] = {k: [] for k in ("density", "phi", "mean_diameter")}
    with np.errstate(invalid="ignore"):
        inside_xy = placed & (axis_r < w.radius)
        edges = np.linspace(w.zmin, w.zmax, n_layers + 1)
        rings = w.radius * np.sqrt(np.arange(1, RINGS + 1) / RINGS)  # equal areas
        for lo, hi in itertools.pairwise(edges if w.volume > 0 else []):
            disc = Cylinder(w.cx, w.cy, w.radius, float(lo), float(hi))
            sel = inside_xy & (centre[:, 2] >= lo) & (centre[:, 2] < hi)
            n, density, diameter = _region_stats(p3, sel, disc.volume)
            within = np.array(
                [solid_in(Cylinder(w.cx, w.cy, float(r), float(lo), float(hi))) for r in rings]
            )
            parts = np.diff(within, prepend=0.0)[None, :]
            cells = np.full((1, RINGS), disc.volume / RINGS)
            for key, value in zip(
                layers,
                (lo, hi, n, density, within[-1] / disc.volume, diameter),
                strict=True,
            ):
                layers[key].append(float(value))
            d = 2.0 * p3.radius[sel]
            errors["density"].append(math.sqrt(max(n, 1)) / disc.volume)
            errors["phi"].append(float(scatter_error(parts, cells)[0]))
            errors["mean_diameter"].append(
                float(d.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
            )
        shells: dict[str, list[float]] = {k: [] for k in ("half_lo", "half_hi", "n")}
        shells.update({"density": [], "phi": [], "mean_diameter": []})
        cz = w.center[2]
        half_h = 0.5 * w.height
        smallest = min(w.radius, half_h)
        inner_solid, inner_volume = 0.0, 0.0
        shell_errors: dict[str, list[float]] = {"density": [], "mean_diameter": []}
        reach = np.maximum(
            axis_r / w.radius if w.radius > 0 else np.inf,
            np.abs(centre[:, 2] - cz) / half_h if half_h > 0 else np.inf,
        )
        for lo, hi in itertools.pairwise(
            np.linspace(0.0, 1.0, n_shells + 1) if w.volume > 0 else []
        ):
            nested = Cylinder(w.cx, w.cy, hi * w.radius, cz - hi * half_h, cz + hi * half_h)
            solid = solid_in(nested)
            sel = placed & (reach >= lo) & (reach < hi)
            shell_volume = nested.volume - inner_volume
            n, density, diameter = _region_stats(p3, sel, shell_volume)
            phi = (solid - inner_solid) / shell_volume if shell_volume > 0 else math.nan
            for key, value in zip(
                shells, (lo * smallest, hi * smallest, n, density, phi, diameter), strict=True
            ):
                shells[key].append(float(value))
            d = 2.0 * p3.radius[sel]
            shell_errors["density"].append(
                math.sqrt(max(n, 1)) / shell_volume if shell_volume > 0 else math.nan
            )
            shell_errors["mean_diameter"].append(
                float(d.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
            )
            inner_solid, inner_volume = solid, nested.volume

    whole = inside_xy & (centre[:, 2] > w.zmin) & (centre[:, 2] < w.zmax)
    n_whole, density_whole, d_whole = (
        _region_stats(p3, whole, w.volume) if w.volume > 0 else (0, math.nan, math.nan)
    )
    phi_whole = solid_in(w) / w.volume if w.volume > 0 else math.nan
    overall = (n_whole, density_whole, phi_whole, d_whole)
    return _assembled(w, margin, overall, (layers, errors), (shells, shell_errors))


def _clean(values: list[float]) -> list[float | None]:
    """Return the values as JSON numbers, ``None`` for a non-finite one."""
    return [float(v) if math.isfinite(v) else None for v in values]


def _assembled(
    w: Box | Cylinder,
    margin: float,
    overall: tuple[int, float, float, float],
    layers: tuple[dict[str, list[float]], dict[str, list[float]]],
    shells: tuple[dict[str, list[float]], dict[str, list[float]]],
) -> tuple[dict[str, dict[str, FloatArray]], dict[str, Any]]:
    """Return the tables and scalars of a window's layers and shells from columns and errors.

    ``overall`` is the whole window's particle count, number density, φ and
    mean diameter; ``layers`` and ``shells`` each their columns and their
    sampling errors. The tables carry the columns also under the names of
    the 2D tables.
    """
    n_whole, density_whole, phi_whole, d_whole = overall
    layer_columns, errors = layers
    shell_columns, shell_errors = shells
    results = {
        "interior_margin": margin,
        "n_interior": n_whole,
        "number_density": float(density_whole) if math.isfinite(density_whole) else None,
        "phi": float(phi_whole) if math.isfinite(phi_whole) else None,
        "mean_d": float(d_whole) if math.isfinite(d_whole) else None,
        "window": [float(s) for s in w.size],
        "notes": [] if w.volume > 0 else [f"no interior window: margin {margin:g}"],
        "phi_layers": _clean(layer_columns["phi"]),
        "density_layers": _clean(layer_columns["density"]),
        "mean_diameter_layers": _clean(layer_columns["mean_diameter"]),
        "phi_layers_cv": _cv(layer_columns["phi"]),
        "phi_shells": _clean(shell_columns["phi"]),
        "density_shells": _clean(shell_columns["density"]),
        "mean_diameter_shells": _clean(shell_columns["mean_diameter"]),
        "phi_shells_cv": _cv(shell_columns["phi"]),
    }
    layer_table = {k: np.asarray(v) for k, v in layer_columns.items()}
    # the columns under the names of the 2D tables, with their sampling errors
    layer_table.update(
        {
            "number_density": layer_table["density"],
            "number_density_err": np.asarray(errors["density"]),
            "phi_err": np.asarray(errors["phi"]),
            "mean_d": layer_table["mean_diameter"],
            "mean_d_err": np.asarray(errors["mean_diameter"]),
        }
    )
    shell_table = {k: np.asarray(v) for k, v in shell_columns.items()}
    shell_table.update(
        {
            "number_density": shell_table["density"],
            "number_density_err": np.asarray(shell_errors["density"]),
            "mean_d": shell_table["mean_diameter"],
            "mean_d_err": np.asarray(shell_errors["mean_diameter"]),
        }
    )
    return {"homogeneity_layers": layer_table, "homogeneity_shells": shell_table}, results
