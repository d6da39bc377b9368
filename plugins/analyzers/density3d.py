"""Volume fraction of a 3D packing over the box and over the interior window."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

from pydantic import BaseModel, ConfigDict, Field

from regopack.plugins.analyzers.common import eta_of
from regopack.plugins.analyzers.common3d import (
    as_packing3d,
    interior_margin3d,
    interior_window3d,
    solid_volumes,
)
from regopack.plugins.analyzers.density import void_ratio
from regopack.registry.interfaces import Analyzer


class Density3DConfig(BaseModel):
    """Parameters of the 3D density analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )


class Density3D(Analyzer):
    """Volume fraction of the solids over the box and the interior window, and void ratios.

    Solids that cross the window's faces are clipped exactly by their planes
    (:func:`regopack.packing.solid_fraction.phi_in_box`). A periodic box has no walls: its
    interior is the whole cell.
    """

    name = "density3d"

    def __init__(self, config: Density3DConfig | None = None) -> None:
        self.config = config or Density3DConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Measure the volume fractions."""
        from regopack.packing.solid_fraction import phi_in_box

        p3 = as_packing3d(packing, self)
        margin = interior_margin3d(p3, self.config.margin)
        window = interior_window3d(p3, margin)
        volume = solid_volumes(p3)
        phi_domain = float(volume[p3.placed].sum()) / p3.domain.volume
        if p3.domain.periodic:
            phi_interior = phi_domain  # no walls: the whole cell is interior
        else:
            try:
                phi_interior = phi_in_box(p3, window, volume)
            except NotImplementedError:  # a rounded polyhedron crossing the window's faces
                phi_interior = math.nan
        self._results = {
            "phi_domain": phi_domain,
            "phi_interior": None if math.isnan(phi_interior) else phi_interior,
            "void_ratio_domain": void_ratio(phi_domain),
            "void_ratio_interior": void_ratio(phi_interior),
            "interior_margin": margin,
            "window": list(window.size),
            "n_placed": p3.n_placed,
            "eta": eta_of(p3),  # type: ignore[arg-type]
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars: phi and void ratio of the box and the interior, margin, n_placed, eta."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)
