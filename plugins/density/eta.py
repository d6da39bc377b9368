"""Packing control coefficient eta (SPEC §4 step 6, the paper's Eq. 9).

Each available arc is shrunk at both ends by
``delta = max(0, eta + xi - 1) / 100 * 2 r_new / (r_candidate + r_new)`` radians,
with ``xi ~ U(0, 1)`` drawn per arc; arcs whose remaining length is not
positive are dropped. ``eta = 0`` leaves the arcs unchanged and draws nothing.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import DensityController
from regopack.registry.plugin_types import DensityControllerSpec


class EtaConfig(BaseModel):
    """Parameters of the eta density controller."""

    model_config = ConfigDict(extra="forbid", strict=True)

    eta: float = Field(
        0.0,
        ge=0,
        le=1000,
        allow_inf_nan=False,
        description=(
            "Packing control coefficient eta (0 to 1000, the paper uses 0 to 50); 0 "
            "gives the densest packing."
        ),
    )


class EtaController(DensityController):
    """Shrink arcs by an eta-dependent angle at both ends.

    Examples
    --------
    >>> import numpy as np
    >>> ctl = EtaController(EtaConfig(eta=50))
    >>> arcs = np.array([[0.0, 1.0]])
    >>> out = ctl.shrink(arcs, 1.0, 1.0, np.random.default_rng(0))
    >>> bool(out[0, 0] > 0.0 and out[0, 1] < 1.0)
    True
    """

    def __init__(self, config: EtaConfig) -> None:
        self.eta = config.eta
        self.identity = config.eta == 0.0

    def shrink(
        self, arcs: NDArray[np.float64], r_new: float, r_candidate: float, rng: np.random.Generator
    ) -> NDArray[np.float64]:
        """Shrink every arc at both ends; drop those left with no length."""
        if self.identity or arcs.shape[0] == 0:
            return arcs
        xi = rng.random(arcs.shape[0])
        delta = np.maximum(0.0, self.eta + xi - 1.0) / 100.0 * (2.0 * r_new / (r_candidate + r_new))
        out = np.empty_like(arcs)
        out[:, 0] = arcs[:, 0] + delta
        out[:, 1] = arcs[:, 1] - delta
        return out[out[:, 1] > out[:, 0]]


@hookimpl
def regopack_density_controllers() -> Iterable[DensityControllerSpec]:
    """Register the ``eta`` density controller."""
    return [
        DensityControllerSpec(
            name="eta",
            config_model=EtaConfig,
            factory=EtaController,
            description="Packing control coefficient eta: trims both ends of every available arc.",
        )
    ]
