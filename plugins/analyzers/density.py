"""Packing density over the domain and over the interior window (SPEC §6)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

from pydantic import BaseModel, ConfigDict, Field

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import eta_of, interior_margin, interior_window
from regopack.registry.interfaces import Analyzer


class DensityConfig(BaseModel):
    """Parameters of the density analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )


def void_ratio(phi: float | None) -> float | None:
    """Void ratio ``e = (1 - phi) / phi``: void area over solid area (``None`` without solid).

    Examples
    --------
    >>> void_ratio(0.5)
    1.0
    """
    if phi is None or not math.isfinite(phi) or phi <= 0:
        return None
    return (1.0 - phi) / phi


class Density(Analyzer):
    """Area fraction of the particles, over the domain and over the interior window.

    Also the void ratio ``e = (1 - phi) / phi`` of both.
    """

    name = "density"

    def __init__(self, config: DensityConfig | None = None) -> None:
        self.config = config or DensityConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Measure the area fractions; particles are clipped exactly to the window."""
        from regopack.packing.solid_fraction import phi_in_window

        margin = interior_margin(packing, self.config.margin)
        window = interior_window(packing, margin)
        area = packing.area()[packing.placed]
        phi_domain = float(area.sum()) / packing.domain.area
        phi_interior = phi_in_window(packing, window)
        self._results = {
            "phi_domain": phi_domain,
            "phi_interior": phi_interior,
            "void_ratio_domain": void_ratio(phi_domain),
            "void_ratio_interior": void_ratio(phi_interior),
            "interior_margin": margin,
            "n_placed": packing.n_placed,
            "eta": eta_of(packing),
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars: phi and void ratio of the domain and the interior, margin, n_placed, eta."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)
