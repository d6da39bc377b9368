"""Radial distribution function of particle centres (SPEC §6).

``g(r)`` over the interior window ``W`` with an edge correction, so that
``g -> 1`` for an uncorrelated pattern at every ``r`` the window admits:

- a rectangle ``a x b``: the translation correction, every pair at separation
  ``(dx, dy)`` weighted by ``|W| / ((a - |dx|)(b - |dy|))`` (``r < min(a, b)``);
- a circle or convex polygon: the isotropic covariogram correction, every pair
  at distance ``r`` weighted by ``|W| / gamma(r)``, with ``gamma(r)`` the mean
  area of ``W ∩ (W + r u)`` over directions ``u`` (exact for the circle;
  :data:`COVARIOGRAM_DIRECTIONS` directions for a polygon);
- a periodic rectangle: no edges; pairs are counted through the nearest
  periodic image (``r < min(a, b) / 2``).

Per mineral pair ``(A, B)`` the normalisation uses ``N_A N_B``
(``N_A (N_A - 1)`` when ``A = B``); a pair's bins are merged until each holds
enough pairs (:func:`regopack.plugins.analyzers.rdf_peak.count_bins`), and its
curve is tabled over its merged bins, each with its own edges ``r_lo``,
``r_hi`` (table ``rdf_<field>_pairs``). The top of the near-field curve is
fitted, and reported as the first peak, with its standard error, only when it
is a distinct peak; otherwise as a plateau
(:func:`regopack.plugins.analyzers.rdf_peak.first_peak`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from regopack.base.limits import BIN_BYTES, LimitError, check_memory, histogram_bins
from regopack.geometry.domain import Circle, ConvexPolygon, PeriodicRectangle, PlaneDomain
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    eta_of,
    interior_margin,
    interior_mask,
    interior_window,
    periodic_images,
    scaled_defaults,
)
from regopack.plugins.analyzers.rdf_peak import (
    BinnedCurve,
    first_peak,
    merged_width,
    pair_curves,
    peak_results,
    rdf_tables,
)
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]

COVARIOGRAM_DIRECTIONS = 90
"""Directions over which a polygon window's covariogram is averaged."""


RDF_DEFAULTS: dict[str, Any] = {
    "near": (0.0, 10.0),
    "near_bin": 0.1,
    "far": (100.0, 340.0),
    "far_bin": 2.0,
}
"""Default ranges and bin widths of r at the built-in scale (``d_min = 2``); for
another packing each is times :func:`~regopack.base.units.length_scale` (``d_min / 2``)."""


class RdfConfig(BaseModel):
    """Parameters of the radial distribution function."""

    model_config = ConfigDict(extra="forbid", strict=True)

    near: tuple[float, float] | None = Field(
        None,
        strict=False,
        description=(
            "Near-field range of r (length unit); default: [0, 5 d_min] ([0, 10] at the "
            "built-in scenes' d_min = 2)."
        ),
    )
    near_bin: float | None = Field(
        None,
        gt=0,
        description="Bin width in the near field; default: d_min / 20 (0.1 at d_min = 2).",
    )
    far: tuple[float, float] | None = Field(
        None,
        strict=False,
        description=(
            "Far-field range of r (length unit); default: [50, 170] d_min "
            "([100, 340] at d_min = 2)."
        ),
    )
    far_bin: float | None = Field(
        None,
        gt=0,
        description="Bin width in the far field; default: d_min (2.0 at d_min = 2).",
    )
    per_mineral: bool = Field(True, description="Also compute g(r) for every pair of minerals.")
    min_pairs_per_bin: float = Field(
        100.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Bins of a mineral-pair curve are merged until an uncorrelated pattern would put "
            "this many pairs into each at the middle of the range (0: no merging)."
        ),
    )
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )

    @field_validator("near_bin", "far_bin")
    @classmethod
    def _bounded_bins(cls, width: float | None, info: ValidationInfo) -> float | None:
        """Refuse a bin width that gives more than ``MAX_HISTOGRAM_BINS`` bins over its range."""
        name = str(info.field_name).removesuffix("_bin")
        span = info.data.get(name)
        if width is not None and span is not None and 0 <= span[0] < span[1]:
            try:
                lo, hi = span
                histogram_bins(lo, hi, width, field=f"{name}_bin", range_name=name)
            except LimitError as err:
                raise ValueError(err.text) from None
        return width

    @model_validator(mode="after")
    def _check(self) -> RdfConfig:
        for name in ("near", "far"):
            given = getattr(self, name)
            if given is None:
                continue
            lo, hi = given
            if not 0 <= lo < hi:
                raise ValueError(
                    f"{name} must be a range [lo, hi] with 0 <= lo < hi, got [{lo}, {hi}]"
                )
        return self


def _bins(span: float, width: float, cut: bool) -> int:
    """Return the number of whole bins of ``width`` in ``span`` (at least 1).

    A range the user gave (or a scaled default) whose span is a whole number of
    bins up to rounding (``10 s / (0.1 s)`` is 99.99999999999999 for some ``s``)
    keeps that number; a range cut at the window keeps only the bins inside it.
    """
    ratio = span / width
    if not cut:
        ratio *= 1.0 + 4.0 * np.finfo(np.float64).eps
    return max(1, int(np.floor(ratio)))


def rdf_histogram(
    x: FloatArray,
    y: FloatArray,
    kind: NDArray[np.int64],
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    a: float,
    b: float,
    window: PlaneDomain | None = None,
    n_real: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Edge-corrected ``g(r)`` of the points in ``window``, total and per kind pair.

    ``window`` defaults to the ``a x b`` rectangle (translation correction).
    For a periodic window the points from index ``n_real`` on are ghost
    images of the first ``n_real`` (see :func:`periodic_images`).

    Returns
    -------
    total, per_kind
        ``(bins,)`` and ``(n_kinds, n_kinds, bins)`` (symmetric) curves; NaN where
        a kind pair has no pairs to normalise by.

    Raises
    ------
    ValueError
        When the arguments would make the compiled kernel index out of bounds:
        a kind outside ``[0, n_kinds)``, arrays of different lengths, a
        coordinate that is not finite, no bins, a bin width that is not
        positive, or ``n_real`` beyond the points.
    """
    kind = _checked_kinds(x, y, kind, n_kinds, r_lo, width, bins, n_real)
    from regopack.plugins.analyzers.rdf_kernel import weighted_pair_histogram

    edges = r_lo + width * np.arange(bins + 1)
    if isinstance(window, PeriodicRectangle):
        assert n_real is not None
        hist = weighted_pair_histogram(
            x, y, kind, n_kinds, r_lo, width, bins, a, b, False, n_real
        ) / (a * b)
        area = a * b
        x, kind = x[:n_real], kind[:n_real]
    elif isinstance(window, Circle | ConvexPolygon):
        counts_r = weighted_pair_histogram(x, y, kind, n_kinds, r_lo, width, bins, a, b, False)
        gamma = covariogram(window, 0.5 * (edges[:-1] + edges[1:]))
        with np.errstate(divide="ignore", invalid="ignore"):
            hist = np.where(gamma > 0, counts_r / gamma, np.nan)
        area = window.area
    else:
        hist = weighted_pair_histogram(x, y, kind, n_kinds, r_lo, width, bins, a, b)
        area = a * b
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    counts = np.bincount(kind, minlength=n_kinds).astype(np.float64)
    area2 = area**2
    n = float(len(x))
    total = hist.sum(axis=(0, 1)) * area2 / (max(n * (n - 1.0) / 2.0, 1e-300) * shell)
    per = np.full_like(hist, np.nan)
    for p in range(n_kinds):
        for q in range(p, n_kinds):
            norm = counts[p] * (counts[p] - 1.0) / 2.0 if p == q else counts[p] * counts[q]
            if norm > 0:
                per[p, q] = hist[p, q] * area2 / (norm * shell)
                per[q, p] = per[p, q]
    return total, per


def _checked_kinds(
    x: FloatArray,
    y: FloatArray,
    kind: NDArray[np.int64],
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    n_real: int | None,
) -> NDArray[np.int64]:
    """Return ``kind`` as int64 after checking what the compiled kernel indexes without checks.

    The kernel writes ``out[kind[p], kind[q], k]`` with numba's unchecked
    indexing: a kind out of range, or a bin ``k`` from a NaN distance, would
    write outside the histogram.
    """
    kind = np.asarray(kind)
    if kind.dtype.kind not in "iu":
        raise ValueError(f"kind must be an integer array, not {kind.dtype}")
    kind = kind.astype(np.int64, copy=False)
    n = x.shape[0]
    if x.ndim != 1 or y.shape != x.shape or kind.shape != x.shape:
        raise ValueError(
            f"x, y and kind must be 1-D arrays of one length, not {x.shape}, {y.shape} and "
            f"{kind.shape}"
        )
    if n_kinds < 1:
        raise ValueError(f"n_kinds must be >= 1, not {n_kinds}")
    if n and (int(kind.min()) < 0 or int(kind.max()) >= n_kinds):
        raise ValueError(
            f"every kind must lie in [0, {n_kinds}); got kinds from {int(kind.min())} "
            f"to {int(kind.max())}"
        )
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise ValueError("the coordinates x and y must be finite")
    if not (bins >= 1 and math.isfinite(width) and width > 0 and math.isfinite(r_lo) and r_lo >= 0):
        raise ValueError(
            f"bins ({bins}) must be >= 1, width ({width}) > 0 and r_lo ({r_lo}) >= 0, finite"
        )
    if n_real is not None and not 0 <= n_real <= n:
        raise ValueError(f"n_real must lie in [0, {n}], not {n_real}")
    return kind


def covariogram(window: PlaneDomain, r: FloatArray) -> FloatArray:
    """Isotropised set covariogram: mean area of ``W ∩ (W + r u)`` over directions ``u``.

    Exact for a circle; for a polygon the mean over
    :data:`COVARIOGRAM_DIRECTIONS` directions in ``[0, pi)`` (the area is even in ``u``).
    """
    r = np.asarray(r, dtype=np.float64)
    if isinstance(window, Circle):
        big = window.radius
        q = np.clip(r / (2.0 * big), 0.0, 1.0)
        return np.asarray(
            2.0 * big * big * (np.arccos(q) - q * np.sqrt(1.0 - q * q)), dtype=np.float64
        )
    import shapely

    poly = shapely.Polygon(window.outline())
    t = (np.arange(COVARIOGRAM_DIRECTIONS) + 0.5) * np.pi / COVARIOGRAM_DIRECTIONS
    out = np.empty(r.shape[0])
    for k, rk in enumerate(r):
        moved = [shapely.affinity.translate(poly, rk * np.cos(a), rk * np.sin(a)) for a in t]
        out[k] = float(np.mean(shapely.area(shapely.intersection(poly, moved))))
    return out


class Rdf(Analyzer):
    """Radial distribution function, total and per mineral pair, near and far field.

    After :meth:`compute`, by field (``"near"``, ``"far"``): :attr:`curves`
    holds ``r`` (bin centres) and ``total``; :attr:`curves_fine` those and
    every pair ``"A-B"`` at the same bins; :attr:`pair_curves` every pair over
    its merged bins (a :class:`~regopack.plugins.analyzers.rdf_peak.BinnedCurve`);
    :attr:`edges` the bin edges and :attr:`expected` the pairs an uncorrelated
    pattern puts into each bin. :attr:`pair_kinds` gives the indices of the
    minerals of each pair and :attr:`peak` the top of the near field.
    """

    name = "rdf"

    def __init__(self, config: RdfConfig | None = None) -> None:
        self._asked = config or RdfConfig()
        self.config = self._asked
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Histogram the centre pairs inside the interior window."""
        # after compute, the config holds the ranges and bin widths used
        self.config = cfg = scaled_defaults(self._asked, packing, RDF_DEFAULTS)
        assert cfg.near is not None and cfg.far is not None
        assert cfg.near_bin is not None and cfg.far_bin is not None
        margin = interior_margin(packing, cfg.margin)
        w = interior_window(packing, margin)
        a, b = w.width, w.height
        sel = interior_mask(packing, margin)
        pts = packing.centre[sel]
        kinds = packing.mineral[sel].astype(np.int64)
        n_real: int | None = None
        limit = min(a, b)
        if isinstance(w, PeriodicRectangle):
            limit = 0.5 * min(a, b)
            reach = min(limit, max(cfg.near[1], cfg.far[1]))
            ext, origin = periodic_images(packing, reach)
            ghosts = np.arange(packing.n_particles, len(origin))
            n_real = len(pts)
            pts = np.concatenate([pts, ext.centre[ghosts]])
            kinds = np.concatenate([kinds, packing.mineral[origin[ghosts]]]).astype(np.int64)
        self.curves: dict[str, dict[str, FloatArray]] = {}
        self.curves_fine: dict[str, dict[str, FloatArray]] = {}
        self.pair_curves: dict[str, dict[str, BinnedCurve]] = {}
        self.pair_kinds: dict[str, tuple[int, int]] = {}
        self.expected: dict[str, FloatArray] = {}
        self.edges: dict[str, FloatArray] = {}
        pair_bins: dict[str, dict[str, float]] = {}
        n_pts = len(pts) if n_real is None else n_real
        kind_counts = np.bincount(kinds[:n_pts], minlength=len(packing.mineral_names))
        area = w.area if isinstance(w, Circle | ConvexPolygon) else a * b
        notes = []
        for field_name, (lo, hi), width in (
            ("near", cfg.near, cfg.near_bin),
            ("far", cfg.far, cfg.far_bin),
        ):
            cut_from = hi
            if hi >= limit:
                notes.append(f"{field_name} field cut at {limit:g}: the window is {a:g} x {b:g}")
                hi = np.nextafter(limit, 0.0)
            if lo >= hi:
                continue
            # the range as set (or by default), before the window cuts it: the same bound
            # as the settings' own check, which cannot see a default range
            histogram_bins(
                float(lo),
                float(cut_from),
                width,
                field=f"rdf.{field_name}_bin",
                range_name=field_name,
            )
            bins = _bins(hi - lo, width, cut=hi < cut_from)
            names = packing.mineral_names
            n_kinds = len(names) if cfg.per_mineral and len(names) > 1 else 1
            pairs = n_kinds * n_kinds
            check_memory(
                BIN_BYTES * bins * pairs,
                f"{bins:,} bins x {pairs:,} mineral pairs",
                field=f"rdf.{field_name}_bin",
                given=width,
            )
            total, per = rdf_histogram(
                np.ascontiguousarray(pts[:, 0]),
                np.ascontiguousarray(pts[:, 1]),
                kinds if n_kinds > 1 else np.zeros(len(pts), dtype=np.int64),
                n_kinds,
                lo,
                width,
                bins,
                a,
                b,
                window=w,
                n_real=n_real,
            )
            centres = np.asarray(lo + width * (np.arange(bins) + 0.5), dtype=np.float64)
            edges = np.asarray(lo + width * np.arange(bins + 1), dtype=np.float64)
            shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
            self.expected[field_name] = 0.5 * n_pts * (n_pts - 1.0) * shell / area
            self.edges[field_name] = edges
            self.curves[field_name] = {"r": centres, "total": total}
            fine: dict[str, FloatArray] = {"r": centres, "total": total}
            merged: dict[str, BinnedCurve] = {}
            if n_kinds > 1:
                r_mid = 0.5 * (lo + hi)
                merged, self.pair_kinds = pair_curves(
                    per,
                    names,
                    kind_counts.tolist(),
                    edges,
                    shell,
                    2.0 * np.pi * r_mid * width / area,
                    cfg.min_pairs_per_bin,
                )
                fine.update({key: per[p, q] for key, (p, q) in self.pair_kinds.items()})
            self.curves_fine[field_name] = fine
            self.pair_curves[field_name] = merged
            pair_bins[field_name] = {key: merged_width(c, width) for key, c in merged.items()}
        near = self.curves.get("near")
        peak = None
        if near is not None:
            peak = first_peak(near["r"], near["total"], self.expected["near"])
        self.peak = peak
        far = self.curves.get("far")
        self._results = {
            "eta": eta_of(packing),
            "interior_margin": margin,
            "n_points": int(sel.sum()),
            "window_kind": w.kind,
            "window": [a, b],
            **peak_results(peak),
            "first_peak_highest_bin_r": None if peak is None else peak.highest_bin_r,
            "pair_bins": pair_bins,
            "far_mean": float(np.nanmean(far["total"])) if far is not None else None,
            "notes": notes,
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars: the first peak (or plateau), far-field mean of g, points used, bin widths."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)

    def tables(self) -> dict[str, dict[str, Any]]:
        """g(r) per field: ``rdf_<field>`` (r, total) and ``rdf_<field>_pairs`` (merged bins)."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return rdf_tables(self.curves, self.pair_curves, self.pair_kinds)
