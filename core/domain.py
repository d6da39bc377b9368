"""Packing domains (containers with walls)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Rectangle:
    """Axis-aligned rectangular domain with rigid walls.

    Parameters
    ----------
    xmin, xmax, ymin, ymax
        Wall positions (any length unit; micrometres by convention).
    """

    xmin: float
    xmax: float
    ymin: float
    ymax: float

    @classmethod
    def centred(
        cls, width: float, height: float, center: tuple[float, float] = (0.0, 0.0)
    ) -> Rectangle:
        """Build the rectangle of the given size around ``center``."""
        cx, cy = center
        return cls(cx - width / 2, cx + width / 2, cy - height / 2, cy + height / 2)

    @property
    def width(self) -> float:
        """Extent along x."""
        return self.xmax - self.xmin

    @property
    def height(self) -> float:
        """Extent along y."""
        return self.ymax - self.ymin

    @property
    def area(self) -> float:
        """Area of the domain."""
        return self.width * self.height

    @property
    def center(self) -> tuple[float, float]:
        """Centre point of the domain."""
        return (0.5 * (self.xmin + self.xmax), 0.5 * (self.ymin + self.ymax))

    def bounds(self) -> NDArray[np.float64]:
        """Return ``[xmin, xmax, ymin, ymax]`` as a float array."""
        return np.array([self.xmin, self.xmax, self.ymin, self.ymax], dtype=np.float64)

    def shrunk(self, margin: float) -> Rectangle:
        """Return the window inset by ``margin`` from every wall (empty windows are clamped)."""
        cx, cy = self.center
        hw = max(0.0, self.width / 2 - margin)
        hh = max(0.0, self.height / 2 - margin)
        return Rectangle(cx - hw, cx + hw, cy - hh, cy + hh)
