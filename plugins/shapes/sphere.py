"""The ``sphere`` shape: exact spheres, the 3D counterpart of ``disk``.

A sphere of radius ``r`` is stored as the single vertex ``(0, 0, 0)`` rounded
by ``r`` (:attr:`regopack.geometry.solids.SolidBatch.rounding`), with no faces, so
its volume is exactly ``4/3 pi r^3`` and every part of regopack that meets it
can use sphere geometry.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from regopack.geometry.solids import SolidBatch
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import SolidGenerator
from regopack.registry.plugin_types import ShapeSpec

FloatArray = NDArray[np.float64]


class SphereConfig(BaseModel):
    """The sphere takes no parameters: its radius is the particle's equivalent radius."""

    model_config = ConfigDict(extra="forbid", strict=True)


class Sphere(SolidGenerator):
    """Exact spheres of volume ``4/3 pi r^3`` about their centre; draws no random numbers.

    Examples
    --------
    >>> import numpy as np
    >>> batch = Sphere().generate(np.array([1.0, 2.5]), np.random.default_rng(0))
    >>> batch.vertices.tolist(), batch.rounding.tolist()
    ([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [1.0, 2.5])
    """

    def __init__(self, config: SphereConfig | None = None) -> None:
        self.config = config or SphereConfig()

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> SolidBatch:
        """One sphere per radius: the vertex ``(0, 0, 0)`` rounded by the radius."""
        return SolidBatch.of_spheres(radius)


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``sphere`` shape."""
    return [
        ShapeSpec(
            name="sphere",
            config_model=SphereConfig,
            factory=Sphere,
            description="Exact sphere of the particle's equivalent radius (3D).",
            dimension=3,
        )
    ]
