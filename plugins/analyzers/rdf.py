"""Radial distribution function of particle centres (SPEC §6), in 2D and 3D.

``g(r)`` over the interior window ``W`` with an edge correction, so that
``g -> 1`` for an uncorrelated pattern at every ``r`` the window admits
(:mod:`~regopack.plugins.analyzers.rdf_histogram`):

- a rectangle ``a x b`` (a box ``a x b x c``): the translation correction,
  every pair at separation ``(dx, dy)`` weighted by ``|W| / ((a - |dx|)(b - |dy|))``
  (``|W| / ((a - |dx|)(b - |dy|)(c - |dz|))``), the measure of ``W ∩ (W + d)``
  in which a pair at that separation can lie whole (``r < min(a, b)``);
- a circle or convex polygon: the isotropic covariogram correction, every pair
  at distance ``r`` weighted by ``|W| / gamma(r)``, with ``gamma(r)`` the mean
  area of ``W ∩ (W + r u)`` over directions ``u`` (exact for the circle;
  :data:`~regopack.plugins.analyzers.rdf_histogram.COVARIOGRAM_DIRECTIONS`
  directions for a polygon);
- a periodic rectangle or box: no edges; pairs are counted through the
  nearest periodic image (``r`` below half the shortest side).

``g(r) = |W|^2 / (N (N - 1) / 2) * H(r) / S(r)``, with ``H`` the weighted
count of pairs in the bin and ``S`` the area (volume) of its shell. Per
mineral pair ``(A, B)`` the normalisation uses ``N_A N_B``
(``N_A (N_A - 1) / 2`` when ``A = B``); a pair's bins are merged until each holds
enough pairs (:func:`regopack.plugins.analyzers.rdf_peak.count_bins`), and its
curve is tabled over its merged bins, each with its own edges ``r_lo``,
``r_hi`` (table ``rdf_<field>_pairs``). The top of the near-field curve is
fitted, and reported as the first peak, with its standard error, only when it
is a distinct peak; otherwise as a plateau
(:func:`regopack.plugins.analyzers.rdf_peak.first_peak`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from regopack.base.limits import BIN_BYTES, LimitError, check_memory, histogram_bins
from regopack.geometry.domain import Circle, ConvexPolygon, PeriodicRectangle
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    Measured,
    eta_of,
    interior_margin,
    interior_mask,
    interior_window,
    periodic_images,
    scaled_defaults,
)
from regopack.plugins.analyzers.rdf_histogram import rdf3d_histogram, rdf_histogram, shells
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
IntArray = NDArray[np.int64]

RDF_DEFAULTS: dict[int, dict[str, Any]] = {
    2: {"near": (0.0, 10.0), "near_bin": 0.1, "far": (100.0, 340.0), "far_bin": 2.0},
    3: {"near": (0.0, 10.0), "near_bin": 0.1, "far": (10.0, 60.0), "far_bin": 0.5},
}
"""Default ranges and bin widths of r by dimension, at the built-in scale (``d_min = 2``); for
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
            "Far-field range of r (length unit); default: [50, 170] d_min ([100, 340] at "
            "d_min = 2) in 2D, [5, 30] d_min ([10, 60]) in 3D."
        ),
    )
    far_bin: float | None = Field(
        None,
        gt=0,
        description="Bin width in the far field; default: d_min (2.0 at d_min = 2) in 2D, "
        "d_min / 4 (0.5) in 3D.",
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


class Rdf(Measured):
    """Radial distribution function, total and per mineral pair, near and far field.

    Scalars: the first peak (or plateau), the far-field mean of g, the points
    used, the window and the bin widths of the mineral pairs. After
    :meth:`compute`, by field (``"near"``, ``"far"``): :attr:`curves` holds
    ``r`` (bin centres) and ``total``; :attr:`curves_fine` those and every
    pair ``"A-B"`` at the same bins; :attr:`pair_curves` every pair over its
    merged bins (a :class:`~regopack.plugins.analyzers.rdf_peak.BinnedCurve`);
    :attr:`edges` the bin edges and :attr:`expected` the pairs an uncorrelated
    pattern puts into each bin. :attr:`pair_kinds` gives the indices of the
    minerals of each pair and :attr:`peak` the top of the near field.
    """

    name = "rdf"

    def __init__(self, config: RdfConfig | None = None) -> None:
        self._asked = config or RdfConfig()
        self.config = self._asked

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Histogram the centre pairs inside the interior window."""
        dimension = packing.domain.dimension
        # after compute, the config holds the ranges and bin widths used
        self.config = cfg = scaled_defaults(self._asked, packing, RDF_DEFAULTS[dimension])
        assert cfg.near is not None and cfg.far is not None
        assert cfg.near_bin is not None and cfg.far_bin is not None
        margin = interior_margin(packing, cfg.margin)
        w = interior_window(packing, margin)
        sides = [w.width, w.height] if dimension == 2 else [float(s) for s in w.size]
        sel = interior_mask(packing, margin)
        pts = packing.centre[sel]
        kinds = packing.mineral[sel].astype(np.int64)
        n_pts = len(pts)
        n_real: int | None = None
        limit = 0.5 * min(sides) if w.periodic else min(sides)
        if isinstance(w, PeriodicRectangle):  # the 3D kernel takes the nearest image itself
            reach = min(limit, max(cfg.near[1], cfg.far[1]))
            ext, origin = periodic_images(packing, reach)
            ghosts = np.arange(packing.n_particles, len(origin))
            n_real = n_pts
            pts = np.concatenate([pts, ext.centre[ghosts]])
            kinds = np.concatenate([kinds, packing.mineral[origin[ghosts]]]).astype(np.int64)
        if dimension == 3:
            measure = w.volume
        else:
            measure = w.area if isinstance(w, Circle | ConvexPolygon) else sides[0] * sides[1]
        names = packing.mineral_names
        n_kinds = len(names) if cfg.per_mineral and len(names) > 1 else 1
        kind_counts = np.bincount(kinds[:n_pts], minlength=len(names))
        self.curves: dict[str, dict[str, FloatArray]] = {}
        self.curves_fine: dict[str, dict[str, FloatArray]] = {}
        self.pair_curves: dict[str, dict[str, BinnedCurve]] = {}
        self.pair_kinds: dict[str, tuple[int, int]] = {}
        self.expected: dict[str, FloatArray] = {}
        self.edges: dict[str, FloatArray] = {}
        pair_bins: dict[str, dict[str, float]] = {}
        notes = []
        for field_name, (lo, hi), width in (
            ("near", cfg.near, cfg.near_bin),
            ("far", cfg.far, cfg.far_bin),
        ):
            cut_from = hi
            if hi >= limit:
                dims = " x ".join(f"{s:g}" for s in sides)
                notes.append(f"{field_name} field cut at {limit:g}: the window is {dims}")
                hi = float(np.nextafter(limit, 0.0))
            if lo >= hi or not measure > 0:
                continue
            # the range as set (or by default), before the window cuts it: the same bound
            # as the settings' own check, which cannot see a default range
            histogram_bins(
                float(lo),
                float(cut_from),
                width,
                field=f"{self.name}.{field_name}_bin",
                range_name=field_name,
            )
            bins = _bins(hi - lo, width, cut=hi < cut_from)
            pairs = n_kinds * n_kinds
            check_memory(
                BIN_BYTES * bins * pairs,
                f"{bins:,} bins x {pairs:,} mineral pairs",
                field=f"{self.name}.{field_name}_bin",
                given=width,
            )
            by_kind = kinds if n_kinds > 1 else np.zeros(len(pts), dtype=np.int64)
            if dimension == 3:
                total, per = rdf3d_histogram(pts, by_kind, n_kinds, lo, width, bins, w)
            else:
                x, y = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
                a, b = sides
                total, per = rdf_histogram(
                    x, y, by_kind, n_kinds, lo, width, bins, a, b, window=w, n_real=n_real
                )
            centres = np.asarray(lo + width * (np.arange(bins) + 0.5), dtype=np.float64)
            edges = np.asarray(lo + width * np.arange(bins + 1), dtype=np.float64)
            shell = shells(edges, dimension)
            self.expected[field_name] = 0.5 * n_pts * (n_pts - 1.0) * shell / measure
            self.edges[field_name] = edges
            self.curves[field_name] = {"r": centres, "total": total}
            fine: dict[str, FloatArray] = {"r": centres, "total": total}
            merged: dict[str, BinnedCurve] = {}
            if n_kinds > 1:
                r_mid = 0.5 * (lo + hi)
                sphere = 2.0 * np.pi * r_mid if dimension == 2 else 4.0 * np.pi * r_mid * r_mid
                merged, self.pair_kinds = pair_curves(
                    per,
                    names,
                    kind_counts.tolist(),
                    edges,
                    shell,
                    sphere * width / measure,
                    cfg.min_pairs_per_bin,
                )
                fine.update({key: per[p, q] for key, (p, q) in self.pair_kinds.items()})
            self.curves_fine[field_name] = fine
            self.pair_curves[field_name] = merged
            pair_bins[field_name] = {key: merged_width(c, width) for key, c in merged.items()}
        near = self.curves.get("near")
        self.peak = peak = None
        if near is not None and n_pts > 1:
            self.peak = peak = first_peak(near["r"], near["total"], self.expected["near"])
        far = self.curves.get("far")
        far_mean = None
        if far is not None and np.isfinite(far["total"]).any():
            far_mean = float(np.nanmean(far["total"]))
        res: dict[str, Any] = {
            "eta": eta_of(packing),
            "interior_margin": margin,
            "n_points": n_pts,
            "window_kind": w.kind,
            "window": sides,
            **peak_results(peak),
        }
        if dimension == 2:
            res["first_peak_highest_bin_r"] = None if peak is None else peak.highest_bin_r
        self._results = {**res, "pair_bins": pair_bins, "far_mean": far_mean, "notes": notes}
        return self

    def tables(self) -> dict[str, dict[str, Any]]:
        """g(r) per field: ``rdf_<field>`` (r, total) and ``rdf_<field>_pairs`` (merged bins)."""
        self._need()
        return rdf_tables(self.curves, self.pair_curves, self.pair_kinds)
