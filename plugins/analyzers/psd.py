"""Particle size distribution: the placed particles against the requested ones.

"Requested" are all drawn particles of the packing, placed or not. The
distribution is counted in √2 sieve classes of the equivalent diameter
``d = 2 r`` (:mod:`~regopack.plugins.analyzers.sieve`), by number and by mass.
A particle's mass is taken as its area ``π r²`` in two dimensions and its
volume ``4/3 π r³`` in three (every mineral at the same density); nothing
else weights the mass.

The classes are anchored on the scene's ``size.d_min`` (else the smallest
drawn diameter), not on the length unit: a packing scaled by any factor,
its scene with it, has the same classes and the same errors. A class with at
least ``min_class_count`` drawn particles is *checked*: it holds when the
relative errors of its number and of its mass share, placed against drawn,
are both within ``tolerance`` (3 %).

When the scene's size distribution has a method ``cdf(d)`` (the probability
that a diameter is at most ``d``, as every built-in one has), the classes
and the Kolmogorov–Smirnov distance are also compared with it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.packing.core import Packing
from regopack.packing.sieve import (
    SIEVE_RATIO,
    class_of,
    reference_diameter,
    sieve_edges,
    unplaced_per_class,
)
from regopack.plugins.analyzers.common import Measured
from regopack.registry.interfaces import Analyzer

__all__ = [
    "Psd",
    "PsdConfig",
    "analytic_shares",
    "ks_distance",
    "masses",
    "sampling_error",
    "scene_size_distribution",
    "unplaced_per_class",
]

FloatArray = NDArray[np.float64]
Cdf = Callable[[FloatArray], FloatArray]

MASS_GRID = 4096
"""Log-spaced diameters on which the analytic mass shares are integrated."""


class PsdConfig(BaseModel):
    """Parameters of the size distribution analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    min_class_count: int = Field(
        100,
        ge=1,
        description="Classes with at least this many drawn particles are checked: they count "
        "for the worst class errors and are held to the tolerance.",
    )
    tolerance: float = Field(
        0.03,
        ge=0,
        allow_inf_nan=False,
        description="A checked class holds when its number and mass shares, placed against "
        "drawn, are both within this relative error.",
    )
    d_ref: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description="A class bound (length unit); default: the scene's size.d_min, else the "
        "smallest drawn diameter.",
    )
    analytic: bool = Field(
        True, description="Also compare with the scene's size distribution when it has a CDF."
    )


def ks_distance(diameter: FloatArray, subset: NDArray[np.bool_], weight: FloatArray) -> float:
    """Largest difference between the weighted CDFs of ``subset`` and of all diameters.

    With unit weights this is the two-sample Kolmogorov–Smirnov statistic of
    the subset against the whole sample. NaN when the subset has no weight.
    """
    order = np.argsort(diameter, kind="stable")
    d, w, s = diameter[order], weight[order], subset[order]
    total, total_s = float(w.sum()), float(w[s].sum())
    if not (total > 0 and total_s > 0):
        return math.nan
    last = np.flatnonzero(np.append(d[1:] != d[:-1], True))  # end of each group of ties
    f_all = np.cumsum(w)[last] / total
    f_sub = np.cumsum(np.where(s, w, 0.0))[last] / total_s
    return float(np.max(np.abs(f_sub - f_all)))


def scene_size_distribution(packing: Packing) -> tuple[Any, str | None]:
    """Build the scene's size distribution again; ``(distribution, None)`` or ``(None, why)``."""
    from pydantic import ValidationError

    from regopack.base.errors import RegopackError
    from regopack.registry.manager import default_registry

    size = packing.scene.get("size") if isinstance(packing.scene, dict) else None
    if not isinstance(size, dict) or "kind" not in size:
        return None, "the scene has no size section"
    kind = str(size["kind"])
    try:
        spec = default_registry().get("size", kind)
        params = {k: v for k, v in size.items() if k != "kind"}
        return spec.factory(spec.config_model.model_validate(params)), None
    except (RegopackError, ValidationError, ValueError, TypeError, KeyError, OSError) as err:
        return None, f"size distribution {kind!r} not rebuilt: {' '.join(str(err).split())}"


def _cdf_of(dist: Any) -> Cdf | None:
    cdf = getattr(dist, "cdf", None)
    if not callable(cdf):
        return None
    if not float(getattr(dist, "r_max", 0.0)) > float(getattr(dist, "r_min", 0.0)):
        return None  # a single size: no continuous CDF to compare with

    def f(d: FloatArray) -> FloatArray:
        return np.asarray(cdf(np.asarray(d, dtype=np.float64)), dtype=np.float64).reshape(
            np.shape(d)
        )

    return f


def analytic_shares(
    cdf: Cdf, edges: FloatArray, d_lo: float, d_hi: float, power: int = 2
) -> tuple[FloatArray, FloatArray]:
    """Return the number and the mass (area) share of each class under ``cdf``.

    The first class also holds the probability below it and the last class
    the probability above it. Mass shares integrate ``d**power`` (``d²``, the
    area in 2D; ``d³``, the volume in 3D) over the CDF on
    :data:`MASS_GRID` log-spaced diameters from ``d_lo`` to ``d_hi`` (the
    distribution's range) plus the class bounds.
    """
    f = cdf(edges)
    f[0], f[-1] = 0.0, 1.0
    number = np.maximum(np.diff(f), 0.0)
    grid = np.unique(np.concatenate([np.geomspace(d_lo, d_hi, MASS_GRID), edges]))
    grid = grid[(grid >= d_lo) & (grid <= d_hi)]
    fg = cdf(grid)
    mid = 0.5 * (grid[:-1] + grid[1:])
    cell_mass = mid**power * np.maximum(np.diff(fg), 0.0)
    k = class_of(mid, edges)
    mass = np.bincount(k, weights=cell_mass, minlength=len(edges) - 1)
    total = float(mass.sum())
    return number, mass / total if total > 0 else np.full_like(mass, np.nan)


def masses(radius: FloatArray, dimension: int = 2) -> FloatArray:
    """Mass of particles of equivalent radius ``radius``: area ``pi r^2``, or volume in 3D."""
    out: FloatArray = np.pi * radius**2 if dimension == 2 else 4.0 / 3.0 * np.pi * radius**3
    return out


def _weighted_median(d: FloatArray, w: FloatArray) -> float | None:
    if d.size == 0 or not w.sum() > 0:
        return None
    order = np.argsort(d, kind="stable")
    cum = np.cumsum(w[order])
    return float(d[order][np.searchsorted(cum, 0.5 * cum[-1])])


def _worst(rel: FloatArray, ok: NDArray[np.bool_], edges: FloatArray) -> tuple[Any, Any]:
    sel = np.flatnonzero(ok & np.isfinite(rel))
    if len(sel) == 0:
        return None, None
    j = int(sel[np.argmax(np.abs(rel[sel]))])
    return float(rel[j]), [float(edges[j]), float(edges[j + 1])]


def _within(
    number_rel: FloatArray, mass_rel: FloatArray, checked: NDArray[np.bool_], tolerance: float
) -> NDArray[np.bool_]:
    """Return the checked classes whose number and mass errors are both within ``tolerance``."""
    with np.errstate(invalid="ignore"):
        ok: NDArray[np.bool_] = (
            checked & (np.abs(number_rel) <= tolerance) & (np.abs(mass_rel) <= tolerance)
        )
    return ok


def sampling_error(
    k: NDArray[np.int64], weight: FloatArray, n_classes: int, n_placed: int
) -> FloatArray:
    """Return the standard deviation of each class's relative share error by chance alone.

    That is, if the ``n_placed`` placed particles were a uniformly random
    subset of the drawn ones (classes ``k``, weights ``weight``: ones for
    the number, masses for the mass): the share of a class in the subset is
    a ratio estimator, whose variance is taken to first order with the
    finite-population correction. By number this is the hypergeometric
    ``sqrt((1 - p)(N - n) / ((N - 1) n p))`` of a class of share ``p``.
    NaN for an empty class, or without two drawn and one placed particle.
    """
    n = len(k)
    if n < 2 or n_placed < 1:
        return np.full(n_classes, np.nan)
    total = float(weight.sum())
    share = np.bincount(k, weights=weight, minlength=n_classes) / total
    w2 = np.bincount(k, weights=weight**2, minlength=n_classes)
    spread = w2 * (1.0 - 2.0 * share) + share**2 * float((weight**2).sum())
    var_mean = (1.0 - n_placed / n) * np.maximum(spread, 0.0) / (n - 1) / n_placed
    with np.errstate(divide="ignore", invalid="ignore"):
        out: FloatArray = np.where(share > 0, np.sqrt(var_mean) / (total / n) / share, np.nan)
    return out


def _none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


class Psd(Measured):
    """Size distribution of the placed particles against all drawn ones, per √2 class.

    Scalars: counts, medians, KS distances, worst class errors and the
    analytic comparison. After :meth:`compute`, :attr:`classes` holds the
    class table, :attr:`diameter`, :attr:`mass` and :attr:`placed` the
    particles, :attr:`mass_power` the power of the diameter the mass goes
    with (2: areas in 2D, 3: volumes in 3D) and :attr:`cdf` the analytic CDF
    (or ``None``).
    """

    name = "psd"

    def __init__(self, config: PsdConfig | None = None) -> None:
        self.config = config or PsdConfig()
        self.classes: dict[str, Any] = {}
        self.cdf: Cdf | None = None
        self.mass_power = 2

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Count the drawn and placed particles per class; the KS distances."""
        from scipy import stats

        d = 2.0 * packing.radius
        placed = packing.placed
        self.mass_power = packing.domain.dimension
        mass = masses(packing.radius, self.mass_power)
        self.diameter, self.mass, self.placed = d, mass, placed
        n, n_placed = len(d), int(placed.sum())
        notes: list[str] = []
        ref = self.config.d_ref if self.config.d_ref is not None else reference_diameter(packing)
        if ref is not None and n and ref > float(d.min()) * (1 + 1e-9):
            notes.append(f"d_ref = {ref:g} is above the smallest diameter; classes start lower")
        edges = sieve_edges(d, ref) if n else np.array([1.0, SIEVE_RATIO])
        k = class_of(d, edges)
        m = len(edges) - 1
        drawn = np.bincount(k, minlength=m)
        done = np.bincount(k[placed], minlength=m)
        mass_drawn = np.bincount(k, weights=mass, minlength=m)
        mass_done = np.bincount(k[placed], weights=mass[placed], minlength=m)
        with np.errstate(divide="ignore", invalid="ignore"):
            share = {
                "number_share_drawn": drawn / max(n, 1),
                "number_share_placed": done / n_placed if n_placed else np.full(m, np.nan),
                "mass_share_drawn": mass_drawn / mass_drawn.sum(),
                "mass_share_placed": mass_done / mass_done.sum(),
            }
            number_rel = share["number_share_placed"] / share["number_share_drawn"] - 1.0
            mass_rel = share["mass_share_placed"] / share["mass_share_drawn"] - 1.0
            fraction = np.where(drawn > 0, done / drawn, np.nan)
        checked = drawn >= self.config.min_class_count
        within = _within(number_rel, mass_rel, checked, self.config.tolerance)
        analytic_n, analytic_m, res_analytic = self._compare(packing, edges, share, checked, notes)
        self.classes = {
            "class": np.arange(m, dtype=np.int64),
            "d_lo": edges[:-1],
            "d_hi": edges[1:],
            "drawn": drawn.astype(np.int64),
            "placed": done.astype(np.int64),
            "not_placed": (drawn - done).astype(np.int64),
            "placed_fraction": fraction,
            "number_share_drawn": share["number_share_drawn"],
            "number_share_placed": share["number_share_placed"],
            "number_rel_error": number_rel,
            "number_rel_error_sampling": sampling_error(k, np.ones(n), m, n_placed),
            "mass_share_drawn": share["mass_share_drawn"],
            "mass_share_placed": share["mass_share_placed"],
            "mass_rel_error": mass_rel,
            "mass_rel_error_sampling": sampling_error(k, mass, m, n_placed),
            "number_share_analytic": analytic_n,
            "mass_share_analytic": analytic_m,
        }
        with np.errstate(divide="ignore", invalid="ignore"):
            for key, predicted in (("number", analytic_n), ("mass", analytic_m)):
                rel = share[f"{key}_share_placed"] / predicted - 1.0
                self.classes[f"{key}_rel_error_analytic"] = rel
        self.classes["checked"] = checked
        self.classes["within"] = within
        for key in ("number", "mass"):
            for who in ("drawn", "placed", "analytic"):
                self.classes[f"passing_{key}_{who}"] = 100.0 * np.cumsum(
                    self.classes[f"{key}_share_{who}"]
                )

        ks_number = ks_distance(d, placed, np.ones(n)) if n else math.nan
        ks_mass = ks_distance(d, placed, mass) if n else math.nan
        p_number: float | None = None
        if 0 < n_placed < n:
            p_number = float(stats.ks_2samp(d[placed], d[~placed]).pvalue)
        elif n_placed == n and n:
            p_number = 1.0
        worst_n = _worst(number_rel, checked, edges)
        worst_m = _worst(mass_rel, checked, edges)
        outside = np.flatnonzero(checked & ~within)
        self._results = {
            "n_drawn": n,
            "n_placed": n_placed,
            "n_not_placed": n - n_placed,
            "placed_share_mass": _none(float(mass[placed].sum() / mass.sum())) if n else None,
            "d_ref": float(edges[0]) if ref is None else float(ref),
            "n_classes": m,
            "d50_number_drawn": _weighted_median(d, np.ones(n)),
            "d50_number_placed": _weighted_median(d[placed], np.ones(n_placed)),
            "d50_mass_drawn": _weighted_median(d, mass),
            "d50_mass_placed": _weighted_median(d[placed], mass[placed]),
            "ks_number": _none(ks_number),
            "ks_number_pvalue": p_number,
            "ks_mass": _none(ks_mass),
            "min_class_count": self.config.min_class_count,
            "worst_number_rel_error": worst_n[0],
            "worst_number_class": worst_n[1],
            "worst_mass_rel_error": worst_m[0],
            "worst_mass_class": worst_m[1],
            "tolerance": self.config.tolerance,
            "n_classes_checked": int(checked.sum()),
            "n_classes_within": int(within.sum()),
            "classes_outside": [[float(edges[j]), float(edges[j + 1])] for j in outside],
            "all_classes_within": bool(outside.size == 0) if checked.any() else None,
            **res_analytic,
            "notes": notes,
        }
        return self

    def _compare(
        self,
        packing: Packing,
        edges: FloatArray,
        share: Mapping[str, FloatArray],
        checked: NDArray[np.bool_],
        notes: list[str],
    ) -> tuple[FloatArray, FloatArray, dict[str, Any]]:
        """Class shares and KS tests against the scene's size distribution, when it has a CDF."""
        from scipy import stats

        nan = np.full(len(edges) - 1, np.nan)
        res: dict[str, Any] = {
            "analytic": None,
            "ks_drawn_vs_analytic": None,
            "ks_drawn_vs_analytic_pvalue": None,
            "ks_placed_vs_analytic": None,
            "ks_placed_vs_analytic_pvalue": None,
            "worst_analytic_number_rel_error": None,
            "worst_analytic_number_class": None,
            "worst_analytic_mass_rel_error": None,
            "worst_analytic_mass_class": None,
        }
        self.cdf = None
        if not self.config.analytic or self.diameter.size == 0:
            return nan, nan, res
        dist, why = scene_size_distribution(packing)
        cdf = _cdf_of(dist) if dist is not None else None
        if cdf is None:
            notes.append(why or "the size distribution gives no continuous CDF")
            return nan, nan, res
        d, placed = self.diameter, self.placed
        try:
            lo, hi = 2.0 * float(dist.r_min), 2.0 * float(dist.r_max)
            number, mass = analytic_shares(cdf, edges.copy(), lo, hi, self.mass_power)
            ks_d = stats.kstest(d, cdf)
            ks_p = stats.kstest(d[placed], cdf) if placed.any() else None
        except (ValueError, TypeError, ArithmeticError) as err:
            notes.append(f"the size distribution's CDF failed: {' '.join(str(err).split())}")
            return nan, nan, res
        self.cdf = cdf
        res["analytic"] = packing.scene["size"]["kind"]
        res["ks_drawn_vs_analytic"] = float(ks_d.statistic)
        res["ks_drawn_vs_analytic_pvalue"] = float(ks_d.pvalue)
        if ks_p is not None:
            res["ks_placed_vs_analytic"] = float(ks_p.statistic)
            res["ks_placed_vs_analytic_pvalue"] = float(ks_p.pvalue)
        for key, predicted in (("number", number), ("mass", mass)):
            with np.errstate(divide="ignore", invalid="ignore"):
                rel = share[f"{key}_share_placed"] / predicted - 1.0
            worst = _worst(rel, checked, edges)
            res[f"worst_analytic_{key}_rel_error"], res[f"worst_analytic_{key}_class"] = worst
        return number, mass, res

    def tables(self) -> dict[str, dict[str, Any]]:
        """Table ``psd_classes``: one row per sieve class."""
        self._need()
        return {"psd_classes": dict(self.classes)}
