"""The means and radii a distribution of diameters derives from its moments and range."""

from __future__ import annotations

import math

import numpy as np
import pytest

from regopack.geometry.population import FloatArray
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.plugins.sizes.diameters import DiameterDistribution


class _Powers(DiameterDistribution):
    """Moments ``E[d^k] = 2^k + k`` (not a distribution: each mean reads its own moment)."""

    d_lo = 3.0
    d_hi = 7.0

    def moment(self, k: float) -> float:
        return 2.0**k + k

    def sample(self, n: int, rng: np.random.Generator) -> FloatArray:
        return np.full(n, 2.5)


def test_the_means_come_from_the_moments_and_the_radii_from_the_range() -> None:
    dist = _Powers()
    assert dist.mean_diameter == 3.0
    assert dist.mean_area == math.pi / 4.0 * 6.0
    assert dist.mean_volume == math.pi / 6.0 * 11.0
    assert (dist.r_min, dist.r_max) == (1.5, 3.5)


def test_a_distribution_without_moments_cannot_be_made() -> None:
    class NoMoments(DiameterDistribution):
        def sample(self, n: int, rng: np.random.Generator) -> FloatArray:
            return np.zeros(n)

    with pytest.raises(TypeError, match="moment"):
        NoMoments()  # type: ignore[abstract]


def test_change5_offers_its_moments_and_diameter_range() -> None:
    dist = Change5(Change5Config(d_min=3.0, d_max=30.0))
    assert dist.mean_diameter == dist.moment(1)
    assert dist.mean_area == math.pi / 4.0 * dist.moment(2)
    assert (dist.r_min, dist.r_max) == (1.5, 15.0)
