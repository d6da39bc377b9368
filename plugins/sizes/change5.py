"""Chang'e-5 size distribution: a truncated shifted power law of diameters.

The number density of diameters is ``n(d) ∝ (d + d0)^(-alpha)`` on
``[d_min, d_max]`` (SPEC §1). Samples come from the closed-form inverse CDF,
written in lengths normalised by ``d_min + d0`` so that every length scale
(1e-6 to 1e6) gives the same relative result.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.plugins.sizes.diameters import DiameterDistribution
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import SizeDistributionSpec

MIN_SPREAD = 1e-9
"""Smallest ``(d_max - d_min) / (d_min + d0)`` (a ratio: the same at every length scale)."""


class Change5Config(BaseModel):
    """Parameters of the Chang'e-5 size distribution."""

    model_config = ConfigDict(extra="forbid", strict=True)

    d_min: float = Field(
        2.0,
        gt=0,
        allow_inf_nan=False,
        description="Smallest diameter (length unit of the scene, µm by default).",
    )
    d_max: float = Field(
        40.0, gt=0, allow_inf_nan=False, description="Largest diameter; must exceed d_min."
    )
    d0: float = Field(
        16.0,
        ge=0,
        allow_inf_nan=False,
        description="Shift d0 of the power law n(d) ∝ (d + d0)^-alpha.",
    )
    alpha: float = Field(
        6.9,
        gt=0,
        le=100,
        allow_inf_nan=False,
        description="Exponent alpha of the power law (0 < alpha ≤ 100).",
    )

    @model_validator(mode="after")
    def _check_range(self) -> Change5Config:
        if not self.d_max > self.d_min:
            raise ValueError(f"d_max ({self.d_max}) must be greater than d_min ({self.d_min})")
        # the distribution is computed in x = (d + d0) / (d_min + d0) on [1, x_max]: a shift
        # d0 so large against d_max - d_min that x_max rounds to 1 leaves nothing to compute
        spread = (self.d_max - self.d_min) / (self.d_min + self.d0)
        if not spread >= MIN_SPREAD:
            raise ValueError(
                f"d0 ({self.d0:g}) is {1 / spread if spread > 0 else math.inf:.3g} times "
                f"d_max - d_min over d_min + d0; at most {1 / MIN_SPREAD:g} times, or the "
                "distribution cannot be computed in 64-bit floats"
            )
        return self


class Change5(DiameterDistribution):
    """Truncated shifted power law of diameters, ``n(d) ∝ (d + d0)^(-alpha)``.

    Parameters
    ----------
    config
        Validated parameters.

    Examples
    --------
    >>> dist = Change5(Change5Config())
    >>> round(dist.mean_diameter, 3), round(dist.mean_area, 2)
    (5.617, 38.6)
    """

    def __init__(self, config: Change5Config) -> None:
        self.config = config
        self._scale = config.d_min + config.d0
        self._xmax = (config.d_max + config.d0) / self._scale  # > 1
        self.d_lo = config.d_min
        self.d_hi = config.d_max

    # -- distribution functions in the normalised variable x = (d + d0) / (d_min + d0)
    def _g(self, x: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """Unnormalised CDF in x: integral of x'^-alpha from 1 to x."""
        a = self.config.alpha
        xa = np.asarray(x, dtype=np.float64)
        if abs(a - 1.0) < 1e-12:
            return np.log(xa)
        return (1.0 - xa ** (1.0 - a)) / (a - 1.0)

    def cdf(self, d: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """Probability that a diameter is at most ``d``."""
        c = self.config
        dd = np.clip(np.asarray(d, dtype=np.float64), c.d_min, c.d_max)
        return self._g((dd + c.d0) / self._scale) / self._g(self._xmax)

    def ppf(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """Diameter at cumulative probability ``u`` (inverse CDF)."""
        c = self.config
        a = c.alpha
        total = float(self._g(self._xmax))
        if abs(a - 1.0) < 1e-12:
            x = np.exp(u * total)
        else:
            x = (1.0 - u * total * (a - 1.0)) ** (1.0 / (1.0 - a))
        d = x * self._scale - c.d0
        return np.clip(d, c.d_min, c.d_max)

    def moment(self, k: float) -> float:
        """``E[d^k]`` by Gauss-Legendre quadrature in log-spaced panels of x."""
        c = self.config
        nodes, weights = np.polynomial.legendre.leggauss(64)
        edges = np.geomspace(1.0, self._xmax, 33)
        total = 0.0
        norm = 0.0
        for lo, hi in itertools.pairwise(edges):
            x = 0.5 * (hi - lo) * nodes + 0.5 * (hi + lo)
            w = 0.5 * (hi - lo) * weights * x ** (-c.alpha)
            d = x * self._scale - c.d0
            total += float(np.sum(w * d**k))
            norm += float(np.sum(w))
        return total / norm

    def sample(self, n: int, rng: np.random.Generator) -> NDArray[np.float64]:
        """Draw ``n`` equivalent radii (half the sampled diameters)."""
        return 0.5 * self.ppf(rng.random(n))


@hookimpl
def regopack_size_distributions() -> Iterable[SizeDistributionSpec]:
    """Register the ``change5`` size distribution."""
    return [
        SizeDistributionSpec(
            name="change5",
            config_model=Change5Config,
            factory=Change5,
            description="Chang'e-5 diameters: truncated power law n(d) ∝ (d + d0)^-alpha.",
        )
    ]
