"""Homogeneity of a 3D packing: horizontal layers and nested boxes about the centre.

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
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.geometry.domain import Box, PeriodicBox
from regopack.packing.core3d import Packing3D
from regopack.plugins.analyzers.common3d import (
    as_packing3d,
    interior_margin3d,
    interior_window3d,
    solid_volumes,
)
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]


class Homogeneity3DConfig(BaseModel):
    """Parameters of the 3D homogeneity analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    layers: int = Field(6, ge=1, le=1000, description="Horizontal layers of the window along z.")
    shells: int = Field(4, ge=1, le=1000, description="Nested boxes about the window's centre.")
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )


def _region_stats(
    packing: Packing3D, inside: NDArray[np.bool_], volume: float
) -> tuple[int, float, float]:
    """Centres inside, their number density and mean diameter (NaN when none)."""
    n = int(inside.sum())
    d = 2.0 * packing.radius[inside]
    return n, n / volume if volume > 0 else math.nan, float(d.mean()) if n else math.nan


def _images(p3: Packing3D) -> list[Packing3D]:
    """Return the packing, and in a periodic box its 26 images about the cell too."""
    if not p3.domain.periodic:
        return [p3]
    period = np.array(p3.domain.size)
    shifts = [np.array(s, dtype=float) * period for s in itertools.product((-1, 0, 1), repeat=3)]
    return [dataclasses.replace(p3, centre=p3.centre + shift) for shift in shifts]


def _wrapped_centres(p3: Packing3D) -> FloatArray:
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


class Homogeneity3D(Analyzer):
    """Number density, volume fraction and mean diameter over layers and nested boxes."""

    name = "homogeneity3d"

    def __init__(self, config: Homogeneity3DConfig | None = None) -> None:
        self.config = config or Homogeneity3DConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Measure every layer and shell of the interior window."""
        from regopack.packing.solid_fraction import phi_in_box as clip

        p3 = as_packing3d(packing, self)
        cfg = self.config
        margin = interior_margin3d(p3, cfg.margin)
        w = interior_window3d(p3, margin)
        volume = solid_volumes(p3)
        images = _images(p3)

        def phi_in_box(p: Packing3D, window: Box, vol: FloatArray) -> float:
            # in a periodic box a solid that crosses a face fills the window in its images
            return sum(clip(image, window, vol) for image in images)

        centre = _wrapped_centres(p3)
        placed = p3.placed
        with np.errstate(invalid="ignore"):
            layers: dict[str, list[float]] = {k: [] for k in ("z_lo", "z_hi", "n", "density")}
            layers.update({"phi": [], "mean_diameter": []})
            edges = np.linspace(w.zmin, w.zmax, cfg.layers + 1)
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
                for key, value in zip(
                    layers,
                    (lo, hi, n, density, phi_in_box(p3, slab, volume), diameter),
                    strict=True,
                ):
                    layers[key].append(float(value))
            shells: dict[str, list[float]] = {k: [] for k in ("half_lo", "half_hi", "n")}
            shells.update({"density": [], "phi": [], "mean_diameter": []})
            c = np.array(w.center)
            half = 0.5 * np.array(w.size)
            steps = np.linspace(0.0, 1.0, cfg.shells + 1)
            inner_solid, inner_volume = 0.0, 0.0
            reach = np.max(np.abs(centre - c) / np.where(half > 0, half, np.inf), axis=1)
            for lo, hi in itertools.pairwise(steps if w.volume > 0 else []):
                box = Box(
                    *(v for a in range(3) for v in (c[a] - hi * half[a], c[a] + hi * half[a]))
                )
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
                inner_solid, inner_volume = solid, box.volume
        self.layers = {k: np.asarray(v) for k, v in layers.items()}
        self.shells = {k: np.asarray(v) for k, v in shells.items()}

        def clean(values: list[float]) -> list[float | None]:
            return [float(v) if math.isfinite(v) else None for v in values]

        self._results = {
            "interior_margin": margin,
            "window": [float(s) for s in w.size],
            "notes": [] if w.volume > 0 else [f"no interior window: margin {margin:g}"],
            "phi_layers": clean(layers["phi"]),
            "density_layers": clean(layers["density"]),
            "mean_diameter_layers": clean(layers["mean_diameter"]),
            "phi_layers_cv": _cv(layers["phi"]),
            "phi_shells": clean(shells["phi"]),
            "density_shells": clean(shells["density"]),
            "mean_diameter_shells": clean(shells["mean_diameter"]),
            "phi_shells_cv": _cv(shells["phi"]),
        }
        return self

    def results(self) -> dict[str, Any]:
        """Per-region lists (bottom to top, centre outwards) and their coefficients of variation."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)

    def tables(self) -> dict[str, dict[str, Any]]:
        """Tables ``homogeneity_layers`` and ``homogeneity_shells``: one row per region."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return {"homogeneity_layers": dict(self.layers), "homogeneity_shells": dict(self.shells)}
