"""Packing density over the domain and over the interior window (SPEC §6), in 2D and 3D.

The area fraction of a 2D packing, the volume fraction of a 3D one; particles
that cross the window are clipped exactly to it
(:func:`~regopack.packing.solid_fraction.phi_in_window`,
:func:`~regopack.packing.solid_fraction.phi_in_box`; in a cylinder the interior
is the coaxial cylinder inside the walls by the margin,
:func:`~regopack.packing.solid_fraction.phi_in_cylinder`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.geometry.domain import Box, Cylinder
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    Measured,
    eta_of,
    interior_margin,
    interior_window,
    solid_volumes,
)
from regopack.registry.interfaces import Analyzer


class DensityConfig(BaseModel):
    """Parameters of the density analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )


def void_ratio(phi: float | None) -> float | None:
    """Void ratio ``e = (1 - phi) / phi``: void over solid area or volume (``None`` without solid).

    Examples
    --------
    >>> void_ratio(0.5)
    1.0
    """
    if phi is None or not math.isfinite(phi) or phi <= 0:
        return None
    return (1.0 - phi) / phi


def _volume_fraction_in(
    p3: Packing[Box], window: Any, solid: NDArray[np.float64], phi_domain: float
) -> float | None:
    """Volume fraction of the interior window (``None``: empty, or a rounded solid crosses it).

    A periodic box has no walls: its interior is the whole cell.
    """
    from regopack.packing.solid_fraction import phi_in_box, phi_in_cylinder

    if p3.domain.periodic:
        return phi_domain
    try:
        if isinstance(window, Cylinder):
            phi = phi_in_cylinder(p3, window, solid)
        else:
            phi = phi_in_box(p3, window, solid)
    except NotImplementedError:  # a rounded polyhedron crossing the window's faces
        return None
    return None if math.isnan(phi) else phi


class Density(Measured):
    """Area (2D) or volume (3D) fraction of the particles, over the domain and the interior.

    Scalars: ``phi_domain``, ``phi_interior``, the void ratios
    ``e = (1 - phi) / phi`` of both, ``interior_margin``, in 3D the
    ``window``'s sides (a cylinder's: its diameter twice and its height),
    ``n_placed`` and ``eta``.
    """

    name = "density"

    def __init__(self, config: DensityConfig | None = None) -> None:
        self.config = config or DensityConfig()

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Measure the fractions; particles are clipped exactly to the window."""
        from regopack.packing.solid_fraction import phi_in_window

        margin = interior_margin(packing, self.config.margin)
        window = interior_window(packing, margin)
        if packing.dimension == 3:
            solid = solid_volumes(packing)
            phi_domain = float(solid[packing.placed].sum()) / packing.domain.volume
            phi_interior = _volume_fraction_in(packing, window, solid, phi_domain)
        else:
            area = packing.area()[packing.placed]
            phi_domain = float(area.sum()) / packing.domain.area
            phi_interior = phi_in_window(packing, window)
        res: dict[str, Any] = {
            "phi_domain": phi_domain,
            "phi_interior": phi_interior,
            "void_ratio_domain": void_ratio(phi_domain),
            "void_ratio_interior": void_ratio(phi_interior),
            "interior_margin": margin,
        }
        if packing.dimension == 3:
            res["window"] = list(window.size)
        self._results = {**res, "n_placed": packing.n_placed, "eta": eta_of(packing)}
        return self
