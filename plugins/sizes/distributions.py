"""General size distributions of particle diameters.

Five distributions of the diameter ``d`` (the equivalent radius is ``d / 2``):

``lognormal``
    ``ln d`` is normal with median ``exp(mu)`` and standard deviation ``sigma``;
    optionally truncated to ``[d_min, d_max]``.
``rosin-rammler``
    Rosin–Rammler (Weibull) by number, ``F(d) = 1 - exp(-(d / d63)^n)``;
    optionally truncated to ``[d_min, d_max]``.
``uniform``
    Uniform diameters on ``[d_min, d_max]``.
``monodisperse``
    One diameter ``d``.
``tabulated``
    A sieve curve read from a CSV file (sieve size, cumulative percent passing),
    by number or by mass, interpolated linearly in ``ln d``.

Every distribution samples by the inverse CDF from one call ``rng.random(n)``;
each uniform number ``v`` is moved to the middle of its 2^-53 cell
(``u = v + 2^-54``), so the quantile is never taken at exactly 0 or 1 and an
unbounded distribution still returns finite, positive sizes. Quantiles below
the median are computed from the CDF and those above from the survival
function, so both tails keep full relative precision. Lengths enter only as
ratios, so results scale exactly with the length unit (1e-6 to 1e6 and beyond).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from scipy import special

from regopack.base.errors import ConfigError
from regopack.plugins.sizes.diameters import DiameterDistribution
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import SizeDistributionSpec

__all__ = [
    "MIN_TRUNCATED_MASS",
    "LogNormal",
    "LogNormalConfig",
    "Monodisperse",
    "MonodisperseConfig",
    "RosinRammler",
    "RosinRammlerConfig",
    "Tabulated",
    "TabulatedConfig",
    "Uniform",
    "UniformConfig",
    "read_sieve_table",
]

FloatArray = NDArray[np.float64]

HALF_CELL = 2.0**-54
"""Offset that moves ``rng.random()`` values to the middle of their 2^-53 cell."""

MIN_TRUNCATED_MASS = 1e-12
"""Smallest probability of the parent distribution that ``[d_min, d_max]`` may hold."""


def _fractions(n: int, rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    """Draw ``n`` cumulative probabilities ``a`` in (0, 1) and their complements ``b = 1 - a``.

    Both are computed without rounding on their own half of the unit interval,
    ``a`` for ``a <= 1/2`` and ``b`` for ``b <= 1/2``.
    """
    v = rng.random(n)
    return v + HALF_CELL, (1.0 - v) - HALF_CELL


def _as_array(x: ArrayLike) -> FloatArray:
    return np.asarray(x, dtype=np.float64)


def _check_truncation(d_min: float | None, d_max: float | None) -> None:
    if d_min is not None and d_max is not None and not d_max > d_min:
        raise ValueError(f"d_max ({d_max:g}) must be greater than d_min ({d_min:g})")


def _check_mass(mass: float, d_min: float | None, d_max: float | None) -> None:
    if not mass >= MIN_TRUNCATED_MASS:
        lo = "0" if d_min is None else f"{d_min:g}"
        hi = "inf" if d_max is None else f"{d_max:g}"
        raise ValueError(
            f"the truncation interval [d_min, d_max] = [{lo}, {hi}] holds a probability of "
            f"{mass:.3g} of the untruncated distribution (at least {MIN_TRUNCATED_MASS:g} "
            "is needed); check the units of d_min and d_max"
        )


def _log_normal_mass(alpha: float, beta: float) -> float:
    """``ln(Phi(beta) - Phi(alpha))`` for the standard normal, accurate in both tails."""
    if beta <= 0.0:
        lb = float(special.log_ndtr(beta))
        la = float(special.log_ndtr(alpha))
        return lb + math.log1p(-math.exp(la - lb)) if la < lb else -math.inf
    if alpha >= 0.0:
        la = float(special.log_ndtr(-alpha))
        lb = float(special.log_ndtr(-beta))
        return la + math.log1p(-math.exp(lb - la)) if lb < la else -math.inf
    return math.log1p(-(float(special.ndtr(alpha)) + float(special.ndtr(-beta))))


def _gamma_mass(c: float, t_lo: float, t_hi: float) -> float:
    """Probability of ``[t_lo, t_hi]`` under Gamma(c, 1), accurate in both tails."""
    p_lo = float(special.gammainc(c, t_lo))
    if p_lo >= 0.5:
        return float(special.gammaincc(c, t_lo)) - float(special.gammaincc(c, t_hi))
    p_hi = float(special.gammainc(c, t_hi))
    if p_hi <= 0.5:
        return p_hi - p_lo
    return 1.0 - p_lo - float(special.gammaincc(c, t_hi))


# ---------------------------------------------------------------------------
# configuration models

_D_MIN_DESCRIPTION = (
    "Optional lower truncation diameter (> 0): samples come from the distribution "
    "restricted to d >= d_min and renormalised. Omit for no lower bound."
)
_D_MAX_DESCRIPTION = (
    "Optional upper truncation diameter (> d_min): samples come from the distribution "
    "restricted to d <= d_max and renormalised. Omit for no upper bound (then r_max is "
    "the largest quantile the sampler can reach)."
)
_DMin = Annotated[float | None, Field(gt=0, allow_inf_nan=False, description=_D_MIN_DESCRIPTION)]
"""Optional lower truncation diameter of a distribution (``None``: no lower bound)."""
_DMax = Annotated[float | None, Field(gt=0, allow_inf_nan=False, description=_D_MAX_DESCRIPTION)]
"""Optional upper truncation diameter of a distribution (``None``: no upper bound)."""


class LogNormalConfig(BaseModel):
    """Parameters of the (optionally truncated) lognormal distribution of diameters."""

    model_config = ConfigDict(extra="forbid", strict=True)

    median: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Median diameter exp(mu) of the untruncated distribution (> 0). "
            "Give exactly one of median and mean."
        ),
    )
    mean: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Number-mean diameter exp(mu + sigma^2 / 2) of the untruncated distribution (> 0). "
            "Give exactly one of median and mean."
        ),
    )
    sigma: float = Field(
        gt=0,
        le=5,
        allow_inf_nan=False,
        description="Standard deviation of ln d (0 < sigma <= 5); required.",
    )
    d_min: _DMin = None
    d_max: _DMax = None

    @model_validator(mode="after")
    def _check(self) -> LogNormalConfig:
        if (self.median is None) == (self.mean is None):
            got = "both" if self.median is not None else "neither"
            raise ValueError(f"give exactly one of median and mean (got {got})")
        _check_truncation(self.d_min, self.d_max)
        _check_mass(math.exp(LogNormal.log_mass_of(self)), self.d_min, self.d_max)
        return self

    @property
    def median_diameter(self) -> float:
        """Median exp(mu) of the untruncated distribution, from ``median`` or ``mean``."""
        if self.median is not None:
            return self.median
        assert self.mean is not None
        return self.mean * math.exp(-0.5 * self.sigma**2)


class RosinRammlerConfig(BaseModel):
    """Parameters of the (optionally truncated) Rosin–Rammler distribution of diameters."""

    model_config = ConfigDict(extra="forbid", strict=True)

    d63: float = Field(
        gt=0,
        allow_inf_nan=False,
        description=(
            "Characteristic diameter (scale, > 0): 63.2 % (1 - 1/e) of the untruncated "
            "distribution is finer; required."
        ),
    )
    n: float = Field(
        ge=0.1,
        le=100,
        allow_inf_nan=False,
        description="Shape (uniformity) exponent n (0.1 <= n <= 100); required.",
    )
    d_min: _DMin = None
    d_max: _DMax = None

    @model_validator(mode="after")
    def _check(self) -> RosinRammlerConfig:
        _check_truncation(self.d_min, self.d_max)
        _check_mass(RosinRammler.mass_of(self), self.d_min, self.d_max)
        return self


class UniformConfig(BaseModel):
    """Parameters of the uniform distribution of diameters."""

    model_config = ConfigDict(extra="forbid", strict=True)

    d_min: float = Field(
        gt=0, allow_inf_nan=False, description="Smallest diameter (> 0); required."
    )
    d_max: float = Field(
        gt=0, allow_inf_nan=False, description="Largest diameter (> d_min); required."
    )

    @model_validator(mode="after")
    def _check(self) -> UniformConfig:
        _check_truncation(self.d_min, self.d_max)
        return self


class MonodisperseConfig(BaseModel):
    """Parameters of the single-size distribution."""

    model_config = ConfigDict(extra="forbid", strict=True)

    d: float = Field(
        gt=0, allow_inf_nan=False, description="The diameter of every particle (> 0); required."
    )


class TabulatedConfig(BaseModel):
    """Parameters of a sieve curve read from a CSV file."""

    model_config = ConfigDict(extra="forbid", strict=True)

    path: Path = Field(
        strict=False,  # a TOML string
        description=(
            "CSV file with two columns, sieve size and cumulative percent passing, finest "
            "sieve first. A relative path is taken from the current working directory and "
            "stored as an absolute path; '~' is expanded. Required."
        ),
    )
    basis: Literal["number", "mass"] = Field(
        description=(
            'What the percent passing counts: "number" (of particles) or "mass" '
            "(converted to numbers by weighting with d^-mass_exponent); required."
        ),
    )
    mass_exponent: float = Field(
        3.0,
        ge=0,
        le=10,
        allow_inf_nan=False,
        description=(
            'Exponent k of particle mass ∝ d^k used to convert basis = "mass" to numbers '
            '(0 <= k <= 10; 3 for grains of one density); ignored for basis = "number".'
        ),
    )

    @field_validator("path", mode="after")
    @classmethod
    def _read(cls, value: Path) -> Path:
        path = value.expanduser().resolve()
        read_sieve_table(path)
        return path


# ---------------------------------------------------------------------------
# distributions


class _Diameters(DiameterDistribution):
    """A distribution of diameters sampled by its inverse CDF."""

    def _quantile(self, a: FloatArray, b: FloatArray) -> FloatArray:
        """Diameters at cumulative probability ``a``, given also ``b = 1 - a`` exactly."""
        raise NotImplementedError

    def cdf(self, d: ArrayLike) -> FloatArray:
        """Probability that a diameter is at most ``d``."""
        raise NotImplementedError

    def ppf(self, u: ArrayLike) -> FloatArray:
        """Diameter at cumulative probability ``u`` (inverse CDF)."""
        a = _as_array(u)
        return self._quantile(a, 1.0 - a)

    def sample_diameters(self, n: int, rng: np.random.Generator) -> FloatArray:
        """Draw ``n`` diameters (one ``rng.random(n)`` call)."""
        a, b = _fractions(n, rng)
        return self._quantile(a, b)

    def sample(self, n: int, rng: np.random.Generator) -> FloatArray:
        """Draw ``n`` equivalent radii (half the sampled diameters)."""
        return 0.5 * self.sample_diameters(n, rng)


class _Truncated(_Diameters):
    """A parent distribution restricted to ``[lo, hi]`` (``0`` and ``inf`` when not truncated).

    Subclasses set ``lo``, ``hi``, the parent's ``p_lo = P(lo)``, ``q_hi = 1 - P(hi)``
    and the mass ``P(hi) - P(lo)``, and provide the parent's CDF, survival function
    and their inverses.
    """

    lo: float
    hi: float
    p_lo: float
    q_hi: float
    mass: float

    def _parent(self, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Parent CDF and survival function at ``d``."""
        raise NotImplementedError

    def _parent_ppf(self, p: FloatArray) -> FloatArray:
        raise NotImplementedError

    def _parent_isf(self, q: FloatArray) -> FloatArray:
        raise NotImplementedError

    def _bounds(self) -> None:
        lo, hi = self.lo, self.hi
        a = np.array([HALF_CELL])
        self.d_lo = lo if lo > 0 else float(self._quantile(a, 1.0 - a)[0])
        self.d_hi = hi if math.isfinite(hi) else float(self._quantile(1.0 - a, a)[0])

    def _quantile(self, a: FloatArray, b: FloatArray) -> FloatArray:
        p = self.p_lo + a * self.mass
        q = self.q_hi + b * self.mass
        low = p <= 0.5
        d = np.empty_like(p)
        d[low] = self._parent_ppf(p[low])
        d[~low] = self._parent_isf(q[~low])
        return np.clip(d, self.lo, self.hi)

    def cdf(self, d: ArrayLike) -> FloatArray:
        """Probability that a diameter is at most ``d`` (of the truncated distribution)."""
        dd = _as_array(d)
        p, q = self._parent(dd)
        f = np.where(p <= 0.5, (p - self.p_lo) / self.mass, 1.0 - (q - self.q_hi) / self.mass)
        return np.clip(f, 0.0, 1.0)


class LogNormal(_Truncated):
    """Lognormal diameters, optionally truncated to ``[d_min, d_max]``.

    ``ln d`` is normal with mean ``mu`` and standard deviation ``sigma``;
    ``E[d^k] = exp(k mu + k^2 sigma^2 / 2)`` without truncation.

    Parameters
    ----------
    config
        Validated parameters.

    Examples
    --------
    >>> dist = LogNormal(LogNormalConfig(median=10.0, sigma=0.5))
    >>> round(dist.mean_diameter, 4), round(dist.mean_area, 3)
    (11.3315, 129.49)
    >>> cut = LogNormal(LogNormalConfig(median=10.0, sigma=0.5, d_min=5.0, d_max=20.0))
    >>> cut.r_min, cut.r_max
    (2.5, 10.0)
    """

    def __init__(self, config: LogNormalConfig) -> None:
        self.config = config
        self.median = config.median_diameter
        self.sigma = config.sigma
        self.lo = 0.0 if config.d_min is None else config.d_min
        self.hi = math.inf if config.d_max is None else config.d_max
        self._alpha, self._beta = self._z_bounds(config)
        self.p_lo = float(special.ndtr(self._alpha))
        self.q_hi = float(special.ndtr(-self._beta))
        self._log_mass = _log_normal_mass(self._alpha, self._beta)
        self.mass = math.exp(self._log_mass)
        self._bounds()

    @staticmethod
    def _z_bounds(config: LogNormalConfig) -> tuple[float, float]:
        median, s = config.median_diameter, config.sigma
        alpha = -math.inf if config.d_min is None else math.log(config.d_min / median) / s
        beta = math.inf if config.d_max is None else math.log(config.d_max / median) / s
        return alpha, beta

    @classmethod
    def log_mass_of(cls, config: LogNormalConfig) -> float:
        """Log of the untruncated probability of ``[d_min, d_max]``."""
        return _log_normal_mass(*cls._z_bounds(config))

    def _parent(self, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        with np.errstate(divide="ignore"):
            z = np.log(d / self.median) / self.sigma
        return _as_array(special.ndtr(z)), _as_array(special.ndtr(-z))

    def _parent_ppf(self, p: FloatArray) -> FloatArray:
        return self.median * np.exp(self.sigma * _as_array(special.ndtri(p)))

    def _parent_isf(self, q: FloatArray) -> FloatArray:
        return self.median * np.exp(-self.sigma * _as_array(special.ndtri(q)))

    def moment(self, k: float) -> float:
        """``E[d^k]``: ``median^k exp(k^2 s^2 / 2)`` times the ratio of shifted normal masses."""
        ks = k * self.sigma
        shifted = _log_normal_mass(self._alpha - ks, self._beta - ks)
        return float(self.median**k * math.exp(0.5 * ks * ks + shifted - self._log_mass))


class RosinRammler(_Truncated):
    """Rosin–Rammler (Weibull) diameters by number, optionally truncated.

    ``F(d) = 1 - exp(-(d / d63)^n)``; ``E[d^k] = d63^k Gamma(1 + k / n)``
    without truncation.

    Parameters
    ----------
    config
        Validated parameters.

    Examples
    --------
    >>> dist = RosinRammler(RosinRammlerConfig(d63=10.0, n=2.0))
    >>> round(dist.mean_diameter, 4), round(dist.mean_area, 4)
    (8.8623, 78.5398)
    >>> round(float(dist.cdf(10.0)), 6)
    0.632121
    """

    def __init__(self, config: RosinRammlerConfig) -> None:
        self.config = config
        self.scale = config.d63
        self.shape = config.n
        self.lo = 0.0 if config.d_min is None else config.d_min
        self.hi = math.inf if config.d_max is None else config.d_max
        self._t_lo, self._t_hi = self._t_bounds(config)
        self.p_lo = -math.expm1(-self._t_lo)
        self.q_hi = math.exp(-self._t_hi)
        self.mass = self.mass_of(config)
        self._bounds()

    @staticmethod
    def _t_bounds(config: RosinRammlerConfig) -> tuple[float, float]:
        t_lo = 0.0 if config.d_min is None else (config.d_min / config.d63) ** config.n
        t_hi = math.inf if config.d_max is None else (config.d_max / config.d63) ** config.n
        return t_lo, t_hi

    @classmethod
    def mass_of(cls, config: RosinRammlerConfig) -> float:
        """Untruncated probability of ``[d_min, d_max]``: ``exp(-t_lo) - exp(-t_hi)``."""
        t_lo, t_hi = cls._t_bounds(config)
        return math.exp(-t_lo) * -math.expm1(-(t_hi - t_lo))

    def _parent(self, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        t = (d / self.scale) ** self.shape
        return -np.expm1(-t), np.exp(-t)

    def _parent_ppf(self, p: FloatArray) -> FloatArray:
        return _as_array(self.scale * (-np.log1p(-p)) ** (1.0 / self.shape))

    def _parent_isf(self, q: FloatArray) -> FloatArray:
        return _as_array(self.scale * (-np.log(q)) ** (1.0 / self.shape))

    def moment(self, k: float) -> float:
        """``E[d^k]``: ``d63^k Gamma(1 + k/n)`` times the Gamma(1 + k/n) mass of the window."""
        c = 1.0 + k / self.shape
        part = _gamma_mass(c, self._t_lo, self._t_hi)
        return float(self.scale**k * special.gamma(c) * part / self.mass)


class Uniform(_Diameters):
    """Diameters uniform on ``[d_min, d_max]``.

    ``E[d] = (a + b) / 2`` and ``E[d^2] = (a^2 + a b + b^2) / 3``.

    Parameters
    ----------
    config
        Validated parameters.

    Examples
    --------
    >>> dist = Uniform(UniformConfig(d_min=2.0, d_max=4.0))
    >>> dist.mean_diameter, round(dist.mean_area, 4)
    (3.0, 7.3304)
    """

    def __init__(self, config: UniformConfig) -> None:
        self.config = config
        self.d_lo = config.d_min
        self.d_hi = config.d_max

    def _quantile(self, a: FloatArray, b: FloatArray) -> FloatArray:
        lo, hi = self.d_lo, self.d_hi
        d = np.where(a <= 0.5, lo + a * (hi - lo), hi - b * (hi - lo))
        return np.clip(d, lo, hi)

    def cdf(self, d: ArrayLike) -> FloatArray:
        """Probability that a diameter is at most ``d``."""
        return np.clip((_as_array(d) - self.d_lo) / (self.d_hi - self.d_lo), 0.0, 1.0)

    def moment(self, k: float) -> float:
        """``E[d^k] = (b^(k+1) - a^(k+1)) / ((k + 1)(b - a))``, summed without cancellation."""
        a, b = self.d_lo, self.d_hi
        if k == 1:
            return 0.5 * (a + b)
        if k == 2:
            return (a * a + a * b + b * b) / 3.0
        r = a / b
        if k == -1:
            return -math.log(r) / (b - a)
        return float(b**k * -math.expm1((k + 1) * math.log(r)) / ((k + 1) * (1.0 - r)))


class Monodisperse(_Diameters):
    """Every particle has the diameter ``d``; sampling draws no random numbers.

    Parameters
    ----------
    config
        Validated parameters.

    Examples
    --------
    >>> dist = Monodisperse(MonodisperseConfig(d=2.0))
    >>> dist.sample(3, np.random.default_rng(0)).tolist(), dist.mean_area == math.pi
    ([1.0, 1.0, 1.0], True)
    """

    def __init__(self, config: MonodisperseConfig) -> None:
        self.config = config
        self.d_lo = self.d_hi = config.d

    def _quantile(self, a: FloatArray, b: FloatArray) -> FloatArray:
        return np.full_like(a, self.config.d)

    def sample_diameters(self, n: int, rng: np.random.Generator) -> FloatArray:
        """Return ``n`` copies of ``d``; ``rng`` is not used."""
        return np.full(n, self.config.d, dtype=np.float64)

    def cdf(self, d: ArrayLike) -> FloatArray:
        """Step function: 0 below ``d``, 1 from ``d`` on."""
        return np.where(_as_array(d) >= self.config.d, 1.0, 0.0)

    def moment(self, k: float) -> float:
        """``E[d^k] = d^k``."""
        return float(self.config.d**k)


# ---------------------------------------------------------------------------
# tabulated sieve curves

_SEPARATORS = re.compile(r"\s*[,;]\s*|\s+")


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def read_sieve_table(path: str | Path) -> tuple[FloatArray, FloatArray]:
    """Read a sieve curve: sizes and cumulative percent passing.

    The file is UTF-8 text, one sieve per line: the sieve size and the
    cumulative percent passing, separated by a comma, a semicolon, tabs or
    spaces. Blank lines and text after ``#`` are ignored; a first line with
    no number in it is a header and is skipped.

    Parameters
    ----------
    path
        The CSV file.

    Returns
    -------
    sizes, percent
        Sizes strictly increasing and > 0; percents in [0, 100], never
        decreasing, and rising overall.

    Raises
    ------
    ValueError
        One line naming the file, the line and the problem.
    """
    name = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise ValueError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise ValueError(f"{name}: is a directory, not a CSV file") from None
    except UnicodeDecodeError:
        raise ValueError(f"{name}: not a UTF-8 text file") from None
    except OSError as err:
        raise ValueError(f"{name}: cannot read the file: {err.strerror}") from None

    sizes: list[float] = []
    percents: list[float] = []
    lines: list[int] = []
    first = True
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = _SEPARATORS.split(line)
        while fields and not fields[-1]:
            fields.pop()
        values = [_number(f) for f in fields]
        if first and all(v is None for v in values):
            first = False  # a header line
            continue
        first = False
        where = f"{name}, line {lineno}"
        if len(fields) != 2:
            raise ValueError(
                f"{where}: expected 2 columns (sieve size, cumulative percent passing), "
                f"found {len(fields)}"
            )
        for text_value, value in zip(fields, values, strict=True):
            if value is None:
                raise ValueError(f"{where}: {text_value!r} is not a number")
            if not math.isfinite(value):
                raise ValueError(f"{where}: {text_value!r} is not a finite number")
        size, percent = values[0], values[1]
        assert size is not None and percent is not None
        if not size > 0:
            raise ValueError(f"{where}: sieve size {size:g} must be > 0")
        if not 0.0 <= percent <= 100.0:
            raise ValueError(f"{where}: percent passing {percent:g} is outside 0–100")
        if sizes and not size > sizes[-1]:
            raise ValueError(
                f"{where}: sieve size {size:g} is not greater than {sizes[-1]:g} on line "
                f"{lines[-1]}; sizes must increase (finest sieve first)"
            )
        if percents and percent < percents[-1]:
            raise ValueError(
                f"{where}: percent passing {percent:g} is less than {percents[-1]:g} on line "
                f"{lines[-1]}; the cumulative percent must not decrease"
            )
        sizes.append(size)
        percents.append(percent)
        lines.append(lineno)
    if len(sizes) < 2:
        raise ValueError(
            f"{name}: needs at least 2 rows (sieve size, cumulative percent passing), "
            f"found {len(sizes)}"
        )
    if not percents[-1] > percents[0]:
        raise ValueError(
            f"{name}: the percent passing does not rise (it is {percents[0]:g} on every line)"
        )
    return np.array(sizes), np.array(percents)


def _int_exp(a: FloatArray, width: FloatArray) -> FloatArray:
    """``integral of exp(a t) dt over [0, width]``, elementwise, exact at ``a = 0``."""
    x = a * width
    small = np.abs(x) < 1e-8
    safe = np.where(small, 1.0, a)
    with np.errstate(over="ignore"):
        full = np.expm1(x) / safe
    return np.where(small, width * (1.0 + 0.5 * x), full)


class Tabulated(_Diameters):
    """Number distribution of diameters from a sieve curve.

    The cumulative fraction ``F`` is linear in ``ln d`` between sieve sizes and
    rescaled to run from 0 at the finest to 1 at the coarsest sieve. With
    ``basis = "number"`` that is the number CDF: the density of ``ln d`` is
    constant in each segment. With ``basis = "mass"`` the number density of
    ``x = ln d`` is ``dF/dx · exp(-k x)`` (``k = mass_exponent``), integrated
    exactly in each segment.

    Parameters
    ----------
    config
        Validated parameters.
    """

    def __init__(self, config: TabulatedConfig) -> None:
        self.config = config
        try:
            sizes, percent = read_sieve_table(config.path)
        except ValueError as err:
            raise ConfigError(str(err)) from None
        self.sizes = sizes
        self.percent = percent
        self.k = config.mass_exponent if config.basis == "mass" else 0.0
        self._d0 = float(sizes[0])
        self._y = np.log(sizes / sizes[0])
        self._width = np.diff(self._y)
        rise = np.diff(percent)
        k = np.full_like(self._width, self.k)
        self._norm = _int_exp(-k, self._width)  # integral of exp(-k t) over each segment
        with np.errstate(divide="ignore"):
            log_w = np.log(rise) - np.log(self._width) - self.k * self._y[:-1]
            log_w += np.log(self._norm)
        w = np.exp(log_w - np.max(log_w))
        self.weights = w / w.sum()
        """Number probability of each segment between neighbouring sieves."""
        self._cum = np.concatenate(([0.0], np.cumsum(self.weights)))
        self._cum[-1] = 1.0
        used = np.flatnonzero(self.weights > 0)
        self.d_lo = float(sizes[used[0]])
        self.d_hi = float(sizes[used[-1] + 1])

    def _quantile(self, a: FloatArray, b: FloatArray) -> FloatArray:
        m = len(self.weights)
        i = np.clip(np.searchsorted(self._cum, a, side="right") - 1, 0, m - 1)
        w = self.weights[i]
        t = np.clip(np.where(w > 0, (a - self._cum[i]) / np.where(w > 0, w, 1.0), 0.0), 0, 1)
        width = self._width[i]
        if self.k > 0:
            y = self._y[i] - np.log1p(-t * -np.expm1(-self.k * width)) / self.k
        else:
            y = self._y[i] + t * width
        return _as_array(np.clip(self._d0 * np.exp(y), self.d_lo, self.d_hi))

    def cdf(self, d: ArrayLike) -> FloatArray:
        """Return the number fraction of diameters at most ``d``."""
        with np.errstate(divide="ignore"):
            y = np.log(_as_array(d) / self._d0)
        m = len(self.weights)
        i = np.clip(np.searchsorted(self._y, y, side="right") - 1, 0, m - 1)
        s = np.clip(y - self._y[i], 0.0, self._width[i])
        if self.k > 0:
            h = np.expm1(-self.k * s) / np.expm1(-self.k * self._width[i])
        else:
            h = s / self._width[i]
        f = self._cum[i] + self.weights[i] * h
        return _as_array(np.clip(np.where(y < 0, 0.0, f), 0.0, 1.0))

    def moment(self, k: float) -> float:
        """``E[d^k]``, exact for the interpolated curve (closed form per segment)."""
        shifted = _int_exp(np.full_like(self._width, k - self.k), self._width)
        with np.errstate(over="ignore"):
            per = np.exp(k * self._y[:-1]) * shifted / self._norm
        return float(self._d0**k * np.sum(self.weights * per))


# ---------------------------------------------------------------------------
# registration


@hookimpl
def regopack_size_distributions() -> Iterable[SizeDistributionSpec]:
    """Register ``lognormal``, ``rosin-rammler``, ``uniform``, ``monodisperse``, ``tabulated``."""
    return [
        SizeDistributionSpec(
            name="lognormal",
            config_model=LogNormalConfig,
            factory=LogNormal,
            description="Lognormal diameters (median or mean, sigma of ln d), optionally "
            "truncated.",
        ),
        SizeDistributionSpec(
            name="rosin-rammler",
            config_model=RosinRammlerConfig,
            factory=RosinRammler,
            description="Rosin–Rammler (Weibull) diameters by number, F = 1 - exp(-(d/d63)^n), "
            "optionally truncated.",
        ),
        SizeDistributionSpec(
            name="uniform",
            config_model=UniformConfig,
            factory=Uniform,
            description="Diameters uniform on [d_min, d_max].",
        ),
        SizeDistributionSpec(
            name="monodisperse",
            config_model=MonodisperseConfig,
            factory=Monodisperse,
            description="Every particle has the same diameter d.",
        ),
        SizeDistributionSpec(
            name="tabulated",
            config_model=TabulatedConfig,
            factory=Tabulated,
            description="Sieve curve from a CSV file (cumulative percent passing, by number "
            "or mass), interpolated linearly in ln d.",
        ),
    ]
