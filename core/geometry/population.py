"""The particle population: every particle's size, mineral and shape, drawn before insertion."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class ShapeBatch:
    """Convex outlines of a batch of particles, in ragged (flat + offsets) form.

    Attributes
    ----------
    vertices
        ``(M, 2)`` counter-clockwise vertices of all particles, relative to each
        particle's reference point (its centre), which lies strictly inside.
    offsets
        ``(n + 1,)`` start of particle ``j``'s vertices is ``offsets[j]``; its end
        is ``offsets[j + 1]``.
    orientation
        ``(n,)`` orientation angle of each particle in radians.
    rounding
        ``(n,)`` radius of the disk that rounds each outline (the particle is
        the outline's Minkowski sum with that disk), or ``None`` for sharp
        polygons. A disk of radius ``r`` is the single vertex ``(0, 0)``
        rounded by ``r``.
    """

    vertices: FloatArray
    offsets: IntArray
    orientation: FloatArray
    rounding: FloatArray | None = None

    def __len__(self) -> int:
        return int(self.offsets.shape[0] - 1)

    def outline(self, j: int) -> FloatArray:
        """Vertices of particle ``j`` relative to its reference point."""
        return self.vertices[self.offsets[j] : self.offsets[j + 1]]

    @property
    def rounding_radius(self) -> FloatArray:
        """Rounding radius of every particle (zeros for sharp polygons)."""
        if self.rounding is None:
            return np.zeros(len(self), dtype=np.float64)
        return np.asarray(self.rounding, dtype=np.float64)


@dataclass(frozen=True)
class Population:
    """All particles of a scene in insertion order, before they are placed.

    Attributes
    ----------
    radius
        ``(n,)`` equivalent radius (area = pi r^2).
    mineral
        ``(n,)`` index into ``mineral_names``.
    mineral_names
        Names of the phases, in scene order.
    shapes
        Outlines and orientations.
    """

    radius: FloatArray
    mineral: IntArray
    mineral_names: tuple[str, ...]
    shapes: ShapeBatch

    def __len__(self) -> int:
        return int(self.radius.shape[0])

    @property
    def circumradius(self) -> FloatArray:
        """Largest distance from each particle's reference point to its outline."""
        v = self.shapes.vertices
        d = np.hypot(v[:, 0], v[:, 1])
        counts = np.diff(self.shapes.offsets)
        out = np.zeros(len(self), dtype=np.float64)
        nonempty = counts > 0
        out[nonempty] = np.maximum.reduceat(d, self.shapes.offsets[:-1][nonempty])
        if self.shapes.rounding is not None:
            out += self.shapes.rounding
        return out


def concat_shapes(parts: list[tuple[IntArray, ShapeBatch]], n: int) -> ShapeBatch:
    """Interleave shape batches generated per phase back into particle order.

    Parameters
    ----------
    parts
        ``(indices, batch)`` pairs: ``batch`` holds the outlines of the particles
        ``indices`` (ascending) of the population.
    n
        Total number of particles.
    """
    counts = np.zeros(n, dtype=np.int64)
    orientation = np.zeros(n, dtype=np.float64)
    rounded = any(batch.rounding is not None for _, batch in parts)
    rounding = np.zeros(n, dtype=np.float64) if rounded else None
    for idx, batch in parts:
        counts[idx] = np.diff(batch.offsets)
        orientation[idx] = batch.orientation
        if rounding is not None:
            rounding[idx] = batch.rounding_radius
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    vertices = np.empty((int(offsets[-1]), 2), dtype=np.float64)
    for idx, batch in parts:
        if len(idx) == 0:
            continue
        src_counts = np.diff(batch.offsets)
        # destination positions of every vertex of this batch
        starts = offsets[idx]
        dest = np.repeat(starts - batch.offsets[:-1], src_counts) + np.arange(batch.offsets[-1])
        vertices[dest] = batch.vertices
    return ShapeBatch(
        vertices=vertices, offsets=offsets, orientation=orientation, rounding=rounding
    )
