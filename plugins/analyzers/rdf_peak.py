"""The first peak of g(r) with its uncertainty, and g(r) bins chosen from the pair counts.

A histogram estimate of g(r) has, in a bin that an uncorrelated pattern would
fill with E pairs, about g E pairs, so its value is uncertain by
``sqrt(g / E)`` (Poisson). Three consequences:

- the highest bin is a noisy estimate of the peak's position.
  :func:`first_peak` fits a parabola, by weighted least squares, to the bins at
  the top of the peak (where a Savitzky–Golay smoothing of the curve is above
  half-way from 1 to its maximum, at least five bins) and reports its
  vertex. Its standard error is the larger of the error propagated from the
  fit's covariance (scaled up by the reduced χ² when the parabola fits worse
  than the noise) and the spread of the peaks fitted to Poisson resamples of
  the curve, which also covers a fitted window that jumps between competing
  maxima;
- a top is not always a peak: g(r) may rise to a plateau, or to a broad hump
  with a flat top, where the vertex of a parabola is a position the curve
  does not single out (the vertex then sits between the hump's shoulders,
  as precisely placed as they are, whatever the top looks like). The top is
  a *distinct* peak only when it both stands out and is rounded:

  - its *contrast*, the drop from the fitted maximum to the smoothed curve
    at the first bin outside the fitted window, in units of the noise of the
    difference ``sqrt(err_top^2 + g / E)`` (the standard error of the fitted
    height and the Poisson noise of that bin), is at least
    :data:`DISTINCT_CONTRAST` on both sides; a window that reaches an end of
    the range has no contrast;
  - its *roundness*, the drop of the smoothed curve from the vertex to
    half-way to an edge of the window, as a share of its drop from the
    vertex to that edge (the outermost fitted bin), is at least
    :data:`MIN_ROUNDNESS` on both sides: a parabola's is a quarter, a
    Gaussian's about a third, a flat top's about 0, however well it is
    sampled.

  Without a distinct peak the fitted window (its bin centres ``r_lo`` to
  ``r_hi``) is reported as the plateau;
- a pair of rare minerals has few pairs per bin. :func:`count_bins` merges
  adjacent bins until an uncorrelated pattern would put ``min_count`` pairs into
  each one at a reference distance, and :func:`merge_bins` gives the merged
  bins with their own edges.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "DISTINCT_CONTRAST",
    "MIN_ROUNDNESS",
    "BinnedCurve",
    "PeakFit",
    "count_bins",
    "first_peak",
    "merge_bins",
    "merged_width",
    "pair_curves",
    "pair_table",
    "peak_results",
    "rdf_tables",
]

TOP_SHARE = 0.5
"""Bins whose smoothed g is above this share of the way from 1 to the maximum are fitted."""

MIN_FIT_BINS = 5
"""Fewest bins a parabola is fitted to."""

SMOOTH_BINS = 7
"""Window (bins) of the Savitzky–Golay smoothing that locates the peak."""

RESAMPLES = 200
"""Poisson resamples of the curve that measure the spread of the fitted peak."""

RESAMPLE_SEED = 20260612
"""Seed of the resampling generator: the same packing always reports the same error."""

DISTINCT_CONTRAST = 3.0
"""A distinct peak stands this many noise units above the curve just outside its fitted
window, on both sides (see the module's description)."""

MIN_ROUNDNESS = 0.125
"""A distinct peak's curve has fallen, half-way to either edge of the fitted window, by at
least this share of its fall at that edge: half a parabola's (a quarter)."""


@dataclass(frozen=True)
class PeakFit:
    """The top of g(r): the first peak, when it is a distinct one.

    Attributes
    ----------
    r, r_err
        Position of the fitted maximum and its standard error (length unit);
        a peak's position only when :attr:`distinct`.
    g
        Height of the fitted parabola at ``r`` (of the smoothed curve's highest
        bin when nothing was fitted).
    r_lo, r_hi
        Range of the bin centres that were fitted: the top of the curve, and
        the extent of the plateau when the top is not a distinct peak.
    highest_bin_r
        Centre of the highest bin (the unfitted estimate).
    fitted
        False when no parabola could be fitted and ``r`` is the smoothed
        curve's highest bin.
    g_err
        Standard error of ``g`` (NaN when nothing was fitted).
    contrast
        How far the top stands above the smoothed curve just outside the
        fitted window, in noise units, on the side where it stands lower
        (NaN when nothing was fitted or the window reaches an end of the range).
    roundness
        How far the smoothed curve has fallen half-way from the top to an
        edge of the window, as a share of its fall at that edge (the smaller
        of the two sides): a quarter for a parabola, 0 for a flat top.
    """

    r: float
    r_err: float
    g: float
    r_lo: float
    r_hi: float
    highest_bin_r: float
    fitted: bool = True
    g_err: float = math.nan
    contrast: float = math.nan
    roundness: float = math.nan

    @property
    def distinct(self) -> bool:
        """Whether the top is a peak: fitted, standing out and rounded (see the module)."""
        return bool(
            self.fitted and self.contrast >= DISTINCT_CONTRAST and self.roundness >= MIN_ROUNDNESS
        )


class _Top(NamedTuple):
    """A fitted top: position, its error, height, its error, window (bin indices), fitted."""

    r: float
    err: float
    g: float
    g_err: float
    lo: int
    hi: int
    fitted: bool


def _smooth(g: FloatArray) -> FloatArray:
    """Savitzky–Golay smoothing (quadratic, :data:`SMOOTH_BINS` bins) of finite curves.

    ``g`` is one curve or a ``(m, n)`` stack of them, smoothed along the last axis.
    """
    from scipy.signal import savgol_filter

    n = g.shape[-1]
    window = min(SMOOTH_BINS, n if n % 2 else n - 1)
    if window < 3:
        return g.copy()
    return np.asarray(savgol_filter(g, window, 2, mode="interp", axis=-1), dtype=np.float64)


def _window(smooth: FloatArray, top: int) -> tuple[int, int]:
    """Bins about ``top`` where the smoothed g is above :data:`TOP_SHARE` of the way from 1."""
    level = smooth[top] - (1.0 - TOP_SHARE) * (smooth[top] - min(1.0, smooth[top]))
    lo = top
    while lo > 0 and smooth[lo - 1] >= level:
        lo -= 1
    hi = top
    while hi < smooth.size - 1 and smooth[hi + 1] >= level:
        hi += 1
    while hi - lo + 1 < MIN_FIT_BINS:
        lo, hi = (lo - 1, hi) if lo > 0 else (lo, hi + 1)
    return lo, hi


def _fit(
    r: FloatArray,
    g: FloatArray,
    e: FloatArray,
    smooth: FloatArray | None = None,
    position_only: bool = False,
) -> _Top:
    """Fit the top of the highest peak (bin indices ``lo``, ``hi`` of the fitted window).

    ``smooth`` is ``g`` smoothed, when already known; with ``position_only``
    the errors and the height are not computed (returned as NaN).
    """
    if smooth is None:
        smooth = _smooth(g)
    top = int(np.argmax(smooth))
    nan = math.nan
    if r.size < MIN_FIT_BINS:
        half = 0.5 * float(r[-1] - r[0]) if r.size > 1 else 0.0
        return _Top(float(r[top]), half, float(smooth[top]), nan, 0, r.size - 1, False)
    lo, hi = _window(smooth, top)
    x = r[lo : hi + 1] - r[top]
    y = g[lo : hi + 1]
    # Poisson error of each bin, from the smoothed g so that no bin gets zero weight
    sigma = np.sqrt(np.maximum(smooth[lo : hi + 1], 1.0 / e[lo : hi + 1]) / e[lo : hi + 1])
    design = np.column_stack([np.ones_like(x), x, x * x]) / sigma[:, None]
    coef, *_ = np.linalg.lstsq(design, y / sigma, rcond=None)
    c0, c1, c2 = (float(c) for c in coef)
    half = 0.5 * float(r[hi] - r[lo])
    vertex = -c1 / (2.0 * c2) if c2 < 0 else nan
    if not float(x[0]) <= vertex <= float(x[-1]):
        return _Top(float(r[top]), half, float(smooth[top]), nan, lo, hi, False)
    if position_only:
        return _Top(float(r[top] + vertex), nan, nan, nan, lo, hi, True)
    cov = np.linalg.pinv(design.T @ design)
    dof = x.size - 3
    if dof > 0:
        chi2 = float(np.sum(((y - (c0 + c1 * x + c2 * x * x)) / sigma) ** 2)) / dof
        cov = cov * max(1.0, chi2)
    jac = np.array([0.0, -1.0 / (2.0 * c2), c1 / (2.0 * c2 * c2)])
    err = float(np.sqrt(max(float(jac @ cov @ jac), 0.0)))
    at = np.array([1.0, vertex, vertex * vertex])  # the height's gradient (flat in the vertex)
    g_err = float(np.sqrt(max(float(at @ cov @ at), 0.0)))
    height = c0 + c1 * vertex + c2 * vertex * vertex
    return _Top(float(r[top] + vertex), err, height, g_err, lo, hi, True)


def _shape(top: _Top, r: FloatArray, smooth: FloatArray, e: FloatArray) -> tuple[float, float]:
    """Contrast and roundness of a fitted top (see the module); NaN for a top not fitted.

    The contrast is the smaller drop, in noise units, from the fitted maximum
    to the smoothed curve at the first bin outside the window; the roundness
    the smaller ratio of the smoothed curve's drop from the vertex to half-way
    to an edge of the window to its drop to that edge (the outermost fitted bin).
    """
    nan = math.nan
    if not top.fitted or not math.isfinite(top.g_err):
        return nan, nan
    contrast, roundness = math.inf, math.inf
    peak = float(np.interp(top.r, r, smooth))  # the curve's top, not the parabola's
    for out, edge in ((top.lo - 1, top.lo), (top.hi + 1, top.hi)):
        if not 0 <= out < smooth.size:
            return nan, nan
        noise = math.sqrt(max(float(smooth[out]), 1.0 / float(e[out])) / float(e[out]))
        contrast = min(contrast, (top.g - float(smooth[out])) / math.hypot(top.g_err, noise))
        half = float(np.interp(0.5 * (top.r + float(r[edge])), r, smooth))
        fall = peak - float(smooth[edge])
        roundness = min(roundness, (peak - half) / fall if fall > 0 else nan)
    return contrast, roundness


def _resampled_error(r: FloatArray, g: FloatArray, e: FloatArray, resamples: int) -> float:
    """Spread of the tops fitted to Poisson resamples of the curve (a fixed seed)."""
    rng = np.random.default_rng(RESAMPLE_SEED)
    counts = g * e
    samples = np.stack([rng.poisson(counts) / e for _ in range(int(resamples))])
    smoothed = _smooth(samples)
    found = [
        _fit(r, samples[k], e, smoothed[k], position_only=True).r for k in range(samples.shape[0])
    ]
    return float(np.std(found, ddof=1))


def first_peak(
    r: FloatArray, g: FloatArray, expected: FloatArray, resamples: int = RESAMPLES
) -> PeakFit | None:
    """Fit the top of ``g(r)`` and tell whether it is a distinct peak (see the module).

    Parameters
    ----------
    r
        Bin centres, evenly spaced.
    g
        g(r) in each bin (NaN where undefined).
    expected
        Pairs an uncorrelated pattern puts into each bin; ``g`` is uncertain
        by ``sqrt(g / expected)``.
    resamples
        Poisson resamples of the curve whose spread of fitted peaks bounds the
        error from below (0: the fit's own error only).

    Returns
    -------
    PeakFit or None
        ``None`` when no bin is finite with pairs expected, or when g is zero
        in every bin (no pair at all). With fewer than five such bins, or when
        the parabola has no maximum inside the fitted bins, the top is the
        smoothed curve's highest bin, ``fitted`` is false, the error is at
        least half the fitted range and the top is not a distinct peak.

    Examples
    --------
    A peak at 3.27 between bins of 0.1, with 3000 r pairs per bin expected:

    >>> rng = np.random.default_rng(1)
    >>> r = np.arange(0.05, 10.0, 0.1)
    >>> expected = 3000 * r
    >>> g = rng.poisson((1 + np.exp(-((r - 3.27) ** 2) / 0.5)) * expected) / expected
    >>> fit = first_peak(r, g, expected)
    >>> abs(fit.r - 3.27) < 2 * fit.r_err < 0.05, round(fit.highest_bin_r, 2), fit.distinct
    (True, 3.25, True)

    A curve that rises to 1.3 and stays there has a top, but no peak; the
    fitted window is the plateau:

    >>> plateau = np.clip((r - 2.0) / 1.5, 0.0, 1.3)
    >>> top = first_peak(r, rng.poisson(plateau * expected) / expected, expected)
    >>> top.distinct, round(top.r_hi, 2)
    (False, 9.95)
    """
    r = np.asarray(r, dtype=np.float64)
    g = np.asarray(g, dtype=np.float64)
    expected = np.asarray(expected, dtype=np.float64)
    ok = np.isfinite(g) & np.isfinite(expected) & (expected > 0)
    if not ok.any() or not np.any(g[ok] > 0):
        return None
    idx = np.flatnonzero(ok)
    r_ok, g_ok, e_ok = r[idx], g[idx], expected[idx]
    smooth = _smooth(g_ok)
    top = _fit(r_ok, g_ok, e_ok, smooth)
    contrast, roundness = _shape(top, r_ok, smooth, e_ok)
    err = top.err
    if resamples > 0 and r_ok.size >= MIN_FIT_BINS:
        # the error of the parabola alone misses how the fitted window itself
        # moves with the noise (between competing maxima): resample the counts
        err = max(err, _resampled_error(r_ok, g_ok, e_ok, resamples))
    return PeakFit(
        r=float(top.r),
        r_err=float(err),
        g=float(top.g),
        r_lo=float(r_ok[top.lo]),
        r_hi=float(r_ok[top.hi]),
        highest_bin_r=float(r_ok[int(np.argmax(g_ok))]),
        fitted=bool(top.fitted),
        g_err=float(top.g_err),
        contrast=float(contrast),
        roundness=float(roundness),
    )


def count_bins(expected_per_bin: float, min_count: float, bins: int) -> int:
    """Adjacent bins to merge so that a merged bin expects at least ``min_count`` pairs.

    Examples
    --------
    >>> count_bins(30.0, 100, 100), count_bins(500.0, 100, 100), count_bins(0.01, 100, 100)
    (4, 1, 100)
    """
    if min_count <= 0 or expected_per_bin >= min_count:
        return 1
    if not expected_per_bin > 0:
        return bins
    return int(min(bins, math.ceil(min_count / expected_per_bin)))


@dataclass(frozen=True)
class BinnedCurve:
    """g(r) over bins ``[r_lo, r_hi)`` of their own widths: a mineral pair's merged bins.

    Attributes
    ----------
    r_lo, r_hi
        Edges of each bin (length unit).
    g
        g(r) over each bin (NaN where the pair has no pairs to normalise by).
    """

    r_lo: FloatArray
    r_hi: FloatArray
    g: FloatArray

    @property
    def edges(self) -> FloatArray:
        """The ``len(g) + 1`` edges of the bins, as ``Axes.stairs`` takes them."""
        return np.append(self.r_lo, self.r_hi[-1:])

    @property
    def widest(self) -> float:
        """Width of the widest bin (0 without bins)."""
        return float(np.max(self.r_hi - self.r_lo)) if self.g.size else 0.0


def merged_width(curve: BinnedCurve, width: float) -> float:
    """Width of the widest bin of ``curve``, a whole number of fine bins of ``width``.

    Examples
    --------
    >>> merged_width(merge_bins(0.1 * np.arange(11), np.ones(10), np.ones(10), 3), 0.1)
    0.4
    """
    return float(width * round(curve.widest / width))


def _groups(bins: int, factor: int) -> IntArray:
    """Group ``bins`` bins ``factor`` at a time; a short last group joins the one before."""
    groups = np.arange(bins, dtype=np.int64) // max(factor, 1)
    last = int(groups[-1]) if bins else 0
    if factor > 1 and bins % factor and last > 0:
        groups[groups == last] = last - 1
    return groups


def merge_bins(edges: FloatArray, g: FloatArray, shell: FloatArray, factor: int) -> BinnedCurve:
    """Merge g(r) over groups of ``factor`` adjacent bins, each group one bin with its edges.

    The merged value is the shell-weighted mean of the group (what the
    estimator gives for the merged bin; ``shell`` is the area or volume of
    each fine bin's shell); a last group shorter than ``factor`` joins the
    one before it. NaN bins are left out of a group's mean.

    Examples
    --------
    >>> m = merge_bins(np.arange(6.0), np.array([1.0, 3.0, 2.0, 2.0, 5.0]), np.ones(5), 2)
    >>> m.r_lo.tolist(), m.r_hi.tolist(), m.g.tolist()
    ([0.0, 2.0], [2.0, 5.0], [2.0, 3.0])
    """
    edges = np.asarray(edges, dtype=np.float64)
    g = np.asarray(g, dtype=np.float64)
    if factor <= 1:
        return BinnedCurve(edges[:-1].copy(), edges[1:].copy(), g.copy())
    groups = _groups(g.size, factor)
    first = np.flatnonzero(np.diff(groups, prepend=-1))
    last = np.append(first[1:], g.size) - 1
    ok = np.isfinite(g)
    weight = np.where(ok, shell, 0.0)
    top = np.bincount(groups, weights=np.where(ok, g, 0.0) * weight)
    bottom = np.bincount(groups, weights=weight)
    with np.errstate(invalid="ignore", divide="ignore"):
        merged = np.where(bottom > 0, top / np.where(bottom > 0, bottom, 1.0), np.nan)
    return BinnedCurve(edges[first], edges[last + 1], np.asarray(merged, dtype=np.float64))


def pair_curves(
    per: FloatArray,
    names: Sequence[str],
    counts: Sequence[float],
    edges: FloatArray,
    shell: FloatArray,
    pairs_per_bin: float,
    min_count: float,
) -> tuple[dict[str, BinnedCurve], dict[str, tuple[int, int]]]:
    """Every mineral pair's curve over bins merged until each expects ``min_count`` pairs.

    Parameters
    ----------
    per
        ``(k, k, bins)`` g(r) of every pair of kinds, at the fine bins.
    names, counts
        Name and number of points of each kind.
    edges, shell
        The fine bins' edges and shell measures (area in 2D, volume in 3D).
    pairs_per_bin
        Pairs an uncorrelated pattern puts into one fine bin in the middle of
        the range, per pair of points (the shell there over the window's measure).
    min_count
        Pairs each merged bin should expect (:func:`count_bins`).

    Returns
    -------
    curves, kinds
        ``"A-B"`` → its :class:`BinnedCurve`, and ``"A-B"`` → ``(a, b)``, the
        indices of its kinds, in scene order (``a <= b``).
    """
    curves: dict[str, BinnedCurve] = {}
    kinds: dict[str, tuple[int, int]] = {}
    bins = per.shape[-1]
    for p, name_a in enumerate(names):
        for q in range(p, len(names)):
            cp, cq = float(counts[p]), float(counts[q])
            norm = cp * (cp - 1.0) / 2.0 if p == q else cp * cq
            factor = count_bins(norm * pairs_per_bin, min_count, bins)
            key = f"{name_a}-{names[q]}"
            curves[key] = merge_bins(edges, per[p, q], shell, factor)
            kinds[key] = (p, q)
    return curves, kinds


def pair_table(
    curves: Mapping[str, BinnedCurve], kinds: Mapping[str, tuple[int, int]]
) -> dict[str, NDArray[Any]]:
    """One row per merged bin of every pair curve: the long table ``rdf_<field>_pairs``.

    Columns ``mineral_a``, ``mineral_b`` (indices in scene order), ``r_lo``,
    ``r_hi`` (the bin's edges), ``r`` (its middle) and ``g``.

    Examples
    --------
    >>> c = BinnedCurve(np.array([0.0, 2.0]), np.array([2.0, 5.0]), np.array([0.1, 1.2]))
    >>> t = pair_table({"a-b": c}, {"a-b": (0, 1)})
    >>> list(t), t["r"].tolist()
    (['mineral_a', 'mineral_b', 'r_lo', 'r_hi', 'r', 'g'], [1.0, 3.5])
    """
    parts: dict[str, list[NDArray[Any]]] = {k: [] for k in ("a", "b", "lo", "hi", "g")}
    for key, curve in curves.items():
        a, b = kinds[key]
        parts["a"].append(np.full(curve.g.size, a, dtype=np.int64))
        parts["b"].append(np.full(curve.g.size, b, dtype=np.int64))
        parts["lo"].append(curve.r_lo)
        parts["hi"].append(curve.r_hi)
        parts["g"].append(curve.g)
    cols = {
        k: np.concatenate(v) if v else np.zeros(0, dtype=np.int64 if k in "ab" else np.float64)
        for k, v in parts.items()
    }
    return {
        "mineral_a": cols["a"],
        "mineral_b": cols["b"],
        "r_lo": cols["lo"],
        "r_hi": cols["hi"],
        "r": 0.5 * (cols["lo"] + cols["hi"]),
        "g": cols["g"],
    }


def rdf_tables(
    curves: Mapping[str, Mapping[str, FloatArray]],
    merged: Mapping[str, Mapping[str, BinnedCurve]],
    kinds: Mapping[str, tuple[int, int]],
) -> dict[str, dict[str, Any]]:
    """Tables of the rdf analyzers: ``rdf_<field>`` (``r``, ``total``) and ``rdf_<field>_pairs``.

    The pair table (:func:`pair_table`) follows its field's table, when the
    field has pair curves.
    """
    out: dict[str, dict[str, Any]] = {}
    for name, columns in curves.items():
        out[f"rdf_{name}"] = dict(columns)
        if merged.get(name):
            out[f"rdf_{name}_pairs"] = pair_table(merged[name], kinds)
    return out


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def peak_results(peak: PeakFit | None) -> dict[str, Any]:
    """Return the ``first_peak_*`` results of the rdf analyzers: a position only for a peak.

    Without a distinct peak, ``first_plateau`` gives the extent of the top
    (the fitted bin centres) and the position and its error are ``None``.

    Examples
    --------
    >>> top = PeakFit(4.7, 0.2, 1.26, 3.85, 5.35, 4.25, contrast=2.6)
    >>> res = peak_results(top)
    >>> res["first_peak_r"], res["first_peak_distinct"], res["first_plateau"]
    (None, False, [3.85, 5.35])
    """
    if peak is None:
        keys = ("r", "r_err", "distinct", "contrast", "roundness", "g", "fit_range", "fitted")
        return {**{f"first_peak_{k}": None for k in keys}, "first_plateau": None}
    distinct = peak.distinct
    top = [peak.r_lo, peak.r_hi]
    return {
        "first_peak_r": peak.r if distinct else None,
        "first_peak_r_err": peak.r_err if distinct else None,
        "first_peak_distinct": distinct,
        "first_peak_contrast": _finite(peak.contrast),
        "first_peak_roundness": _finite(peak.roundness),
        "first_peak_g": peak.g,
        "first_peak_fit_range": top,
        "first_plateau": None if distinct else top,
        "first_peak_fitted": peak.fitted,
    }
