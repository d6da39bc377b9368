"""Size distribution of a 3D packing: placed against drawn particles, by number and by mass.

As :mod:`regopack.plugins.analyzers.psd`, with the volume-equivalent diameter
``d = 2 r`` (a particle's volume is ``4/3 pi r^3``) and the mass taken as the
volume (every mineral at the same density), so mass shares weight ``d³``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import NDArray

from regopack.plugins.analyzers.common3d import as_packing3d
from regopack.plugins.analyzers.psd import Psd, PsdConfig
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]


class Psd3DConfig(PsdConfig):
    """Parameters of the 3D size distribution analyzer (those of ``psd``)."""


class Psd3D(Psd):
    """Size distribution of the placed solids against all drawn ones, per √2 class, by volume."""

    name = "psd3d"
    mass_power: ClassVar[int] = 3

    def __init__(self, config: Psd3DConfig | None = None) -> None:
        super().__init__(config or Psd3DConfig())

    @staticmethod
    def masses(radius: FloatArray) -> FloatArray:
        """Mass of particles of volume-equivalent radius ``radius``: their volume."""
        out: FloatArray = 4.0 / 3.0 * np.pi * radius**3
        return out

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Count the drawn and placed solids per class; the KS distances."""
        return super().compute(as_packing3d(packing, self), context)  # type: ignore[arg-type]
