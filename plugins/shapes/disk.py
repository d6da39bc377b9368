"""The ``disk`` shape: exact circles.

A disk of radius ``r`` is stored as the single vertex ``(0, 0)`` rounded by
``r`` (:attr:`regopack.geometry.population.ShapeBatch.rounding`), so every part of
regopack that meets it uses circle geometry: the envelopes of the
available-arc inserter are circles and rounded polygons, verification
measures distances to the centre, and the area is exactly ``pi r^2``.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from regopack.geometry.population import ShapeBatch
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import ShapeGenerator
from regopack.registry.plugin_types import ShapeSpec

FloatArray = NDArray[np.float64]


class DiskConfig(BaseModel):
    """The disk takes no parameters: its radius is the particle's equivalent radius."""

    model_config = ConfigDict(extra="forbid", strict=True)


class Disk(ShapeGenerator):
    """Exact disks of area ``pi r^2`` about their centre; draws no random numbers.

    Examples
    --------
    >>> import numpy as np
    >>> batch = Disk(DiskConfig()).generate(np.array([1.0, 2.5]), np.random.default_rng(0))
    >>> batch.vertices.tolist(), batch.rounding.tolist()
    ([[0.0, 0.0], [0.0, 0.0]], [1.0, 2.5])
    """

    def __init__(self, config: DiskConfig | None = None) -> None:
        self.config = config or DiskConfig()

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """One disk per radius: the vertex ``(0, 0)`` rounded by the radius."""
        r = np.asarray(radius, dtype=np.float64)
        if r.ndim != 1:
            raise ValueError(f"radius must be one-dimensional, not of shape {r.shape}")
        n = int(r.shape[0])
        return ShapeBatch(
            vertices=np.zeros((n, 2)),
            offsets=np.arange(n + 1, dtype=np.int64),
            orientation=np.zeros(n),
            rounding=r.copy(),
        )


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``disk`` shape."""
    return [
        ShapeSpec(
            name="disk",
            config_model=DiskConfig,
            factory=Disk,
            description="Exact circle of the particle's equivalent radius.",
        )
    ]
