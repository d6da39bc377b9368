"""What a distribution of diameters offers once its moments and range are known.

:class:`DiameterDistribution` gives a size distribution written in diameters
``d`` (radii are ``d / 2``) its expected diameter, area and volume from the
raw moments ``E[d^k]``, and its smallest and largest radii from the range of
diameters it samples. The Chang'e-5 and the general distributions build on it.
"""

from __future__ import annotations

import math
from abc import abstractmethod

from regopack.registry.interfaces import SizeDistribution

__all__ = ["DiameterDistribution"]


class DiameterDistribution(SizeDistribution):
    """A distribution of diameters ``d`` sampled within ``[d_lo, d_hi]``; radii are ``d / 2``.

    A subclass sets ``d_lo`` and ``d_hi`` and gives :meth:`moment`.
    """

    d_lo: float
    """Smallest diameter the sampler can return."""
    d_hi: float
    """Largest diameter the sampler can return."""

    @abstractmethod
    def moment(self, k: float) -> float:
        """Raw moment ``E[d^k]`` of the diameter."""

    @property
    def mean_diameter(self) -> float:
        """Expected diameter ``E[d]``."""
        return self.moment(1)

    @property
    def mean_area(self) -> float:
        """Expected particle area ``E[pi d^2 / 4]``."""
        return math.pi / 4.0 * self.moment(2)

    @property
    def mean_volume(self) -> float:
        """Expected particle volume ``E[pi d^3 / 6]`` (3D scenes)."""
        return math.pi / 6.0 * self.moment(3)

    @property
    def r_min(self) -> float:
        """Smallest radius the sampler can return."""
        return 0.5 * self.d_lo

    @property
    def r_max(self) -> float:
        """Largest radius the sampler can return."""
        return 0.5 * self.d_hi
