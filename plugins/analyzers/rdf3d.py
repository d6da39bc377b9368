"""Radial distribution function of the centres of a 3D packing, with the box's edge correction.

``g(r)`` over the interior window ``W`` (a box ``a x b x c``), every pair at
separation ``(dx, dy, dz)`` weighted by the translation correction
``|W| / ((a - |dx|)(b - |dy|)(c - |dz|))``: the volume of ``W ∩ (W + d)``
is the volume of the window in which a pair at that separation can lie
whole, so an uncorrelated pattern gives ``g = 1`` at every ``r < min(a, b, c)``.
In a periodic box pairs are counted through their nearest image, without a
correction, up to half the shortest side.

``g(r) = |W|^2 / (N (N - 1) / 2) * H(r) / V_shell(r)``, with ``H`` the
weighted count of pairs in the bin and ``V_shell = 4/3 pi (r_2^3 - r_1^3)``;
per mineral pair ``(A, B)`` the count of pairs is ``N_A N_B`` (``N_A (N_A - 1) / 2``
when ``A = B``), and a pair's bins are merged until each expects enough pairs,
and tabled with their own edges, as in 2D; the first peak is reported only
when the top of the near-field curve is a distinct peak, as in 2D.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from regopack.base.limits import BIN_BYTES, LimitError, check_memory, histogram_bins
from regopack.geometry.domain import Box
from regopack.plugins.analyzers.common import eta_of, scaled_defaults
from regopack.plugins.analyzers.common3d import (
    as_packing3d,
    interior_margin3d,
    interior_mask3d,
    interior_window3d,
)
from regopack.plugins.analyzers.rdf import _bins
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


RDF3D_DEFAULTS: dict[str, Any] = {
    "near": (0.0, 10.0),
    "near_bin": 0.1,
    "far": (10.0, 60.0),
    "far_bin": 0.5,
}
"""Default ranges and bin widths of r at the built-in scale (``d_min = 2``); for
another packing each is times :func:`~regopack.base.units.length_scale` (``d_min / 2``)."""


class Rdf3DConfig(BaseModel):
    """Parameters of the 3D radial distribution function."""

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
            "Far-field range of r (length unit); default: [5, 30] d_min ([10, 60] at d_min = 2)."
        ),
    )
    far_bin: float | None = Field(
        None,
        gt=0,
        description="Bin width in the far field; default: d_min / 4 (0.5 at d_min = 2).",
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
    def _check(self) -> Rdf3DConfig:
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


def rdf3d_histogram(
    points: FloatArray,
    kind: IntArray,
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    window: Box,
) -> tuple[FloatArray, FloatArray]:
    """Edge-corrected ``g(r)`` of ``points`` in ``window``, total and per kind pair.

    Parameters
    ----------
    points
        ``(n, 3)`` centres, all inside ``window``.
    kind
        ``(n,)`` kind of each point, in ``[0, n_kinds)``.
    r_lo, width, bins
        The bins ``[r_lo + k width, r_lo + (k + 1) width)``.
    window
        A walled box (translation correction) or a periodic box (nearest image).

    Returns
    -------
    total, per_kind
        ``(bins,)`` and ``(n_kinds, n_kinds, bins)`` (symmetric) curves; NaN
        where a kind pair has no pairs to normalise by.
    """
    from regopack.plugins.analyzers.rdf3d_kernel import weighted_pair_histogram3d

    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    kind = np.ascontiguousarray(kind, dtype=np.int64)
    n = pts.shape[0]
    # the compiled kernel indexes without checks: refuse what would write out of bounds
    if kind.shape != (n,) or (n and (int(kind.min()) < 0 or int(kind.max()) >= n_kinds)):
        raise ValueError(f"kind must be {n} integers in [0, {n_kinds})")
    if not np.isfinite(pts).all():
        raise ValueError("the points must be finite")
    if not (bins >= 1 and math.isfinite(width) and width > 0 and math.isfinite(r_lo) and r_lo >= 0):
        raise ValueError(f"bins ({bins}) must be >= 1, width ({width}) > 0 and r_lo ({r_lo}) >= 0")
    side = np.array(window.size, dtype=np.float64)
    per_pair = weighted_pair_histogram3d(
        pts, kind, n_kinds, float(r_lo), float(width), int(bins), side, bool(window.periodic)
    )
    edges = r_lo + width * np.arange(bins + 1)
    shell = 4.0 / 3.0 * np.pi * (edges[1:] ** 3 - edges[:-1] ** 3)
    volume = float(np.prod(side))
    counts = np.bincount(kind, minlength=n_kinds).astype(np.float64)
    total = per_pair.sum(axis=(0, 1)) * volume**2 / (max(n * (n - 1.0) / 2.0, 1e-300) * shell)
    per = np.full_like(per_pair, np.nan)
    for p in range(n_kinds):
        for q in range(p, n_kinds):
            norm = counts[p] * (counts[p] - 1.0) / 2.0 if p == q else counts[p] * counts[q]
            if norm > 0:
                per[p, q] = per_pair[p, q] * volume**2 / (norm * shell)
                per[q, p] = per[p, q]
    return total, per


class Rdf3D(Analyzer):
    """Radial distribution function of a 3D packing, total and per mineral pair, near and far.

    After :meth:`compute` it holds what :class:`~regopack.plugins.analyzers.rdf.Rdf`
    holds: :attr:`curves`, :attr:`curves_fine`, :attr:`pair_curves`,
    :attr:`edges`, :attr:`expected`, :attr:`pair_kinds` and :attr:`peak`.
    """

    name = "rdf3d"

    def __init__(self, config: Rdf3DConfig | None = None) -> None:
        self._asked = config or Rdf3DConfig()
        self.config = self._asked
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Histogram the centre pairs inside the interior window."""
        p3 = as_packing3d(packing, self)
        # after compute, the config holds the ranges and bin widths used
        self.config = cfg = scaled_defaults(self._asked, p3, RDF3D_DEFAULTS)
        assert cfg.near is not None and cfg.far is not None
        assert cfg.near_bin is not None and cfg.far_bin is not None
        margin = interior_margin3d(p3, cfg.margin)
        w = interior_window3d(p3, margin)
        size = w.size
        sel = interior_mask3d(p3, margin)
        pts = p3.centre[sel]
        kinds = p3.mineral[sel].astype(np.int64)
        limit = 0.5 * min(size) if w.periodic else min(size)
        volume = w.volume
        n_pts = len(pts)
        names = p3.mineral_names
        n_kinds = len(names) if cfg.per_mineral and len(names) > 1 else 1
        kind_counts = np.bincount(kinds, minlength=len(names))
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
                dims = " x ".join(f"{s:g}" for s in size)
                notes.append(f"{field_name} field cut at {limit:g}: the window is {dims}")
                hi = float(np.nextafter(limit, 0.0))
            if lo >= hi or not volume > 0:
                continue
            # the range as set (or by default), before the window cuts it: the same bound
            # as the settings' own check, which cannot see a default range
            histogram_bins(
                float(lo),
                float(cut_from),
                width,
                field=f"rdf3d.{field_name}_bin",
                range_name=field_name,
            )
            bins = _bins(hi - lo, width, cut=hi < cut_from)
            pairs = n_kinds * n_kinds
            check_memory(
                BIN_BYTES * bins * pairs,
                f"{bins:,} bins x {pairs:,} mineral pairs",
                field=f"rdf3d.{field_name}_bin",
                given=width,
            )
            total, per = rdf3d_histogram(
                pts,
                kinds if n_kinds > 1 else np.zeros(n_pts, dtype=np.int64),
                n_kinds,
                lo,
                width,
                bins,
                w,
            )
            centres = np.asarray(lo + width * (np.arange(bins) + 0.5), dtype=np.float64)
            edges = np.asarray(lo + width * np.arange(bins + 1), dtype=np.float64)
            shell = 4.0 / 3.0 * np.pi * (edges[1:] ** 3 - edges[:-1] ** 3)
            self.expected[field_name] = 0.5 * n_pts * (n_pts - 1.0) * shell / volume
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
                    4.0 * np.pi * r_mid * r_mid * width / volume,
                    cfg.min_pairs_per_bin,
                )
                fine.update({key: per[p, q] for key, (p, q) in self.pair_kinds.items()})
            self.curves_fine[field_name] = fine
            self.pair_curves[field_name] = merged
            pair_bins[field_name] = {key: merged_width(c, width) for key, c in merged.items()}
        near = self.curves.get("near")
        peak = None
        if near is not None and n_pts > 1:
            peak = first_peak(near["r"], near["total"], self.expected["near"])
        self.peak = peak
        far = self.curves.get("far")
        far_mean = None
        if far is not None and np.isfinite(far["total"]).any():
            far_mean = float(np.nanmean(far["total"]))
        self._results = {
            "eta": eta_of(p3),  # type: ignore[arg-type]
            "interior_margin": margin,
            "n_points": int(n_pts),
            "window_kind": w.kind,
            "window": [float(s) for s in size],
            **peak_results(peak),
            "pair_bins": pair_bins,
            "far_mean": far_mean,
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
