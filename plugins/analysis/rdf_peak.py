"""The first peak of g(r) with its uncertainty, and g(r) bins chosen from the pair counts.

A histogram estimate of g(r) has, in a bin that an uncorrelated pattern would
fill with E pairs, about g E pairs, so its value is uncertain by
``sqrt(g / E)`` (Poisson). Two consequences:

- the highest bin is a noisy estimate of the peak's position.
  :func:`first_peak` fits a parabola, by weighted least squares, to the bins at
  the top of the peak (where a Savitzky–Golay smoothing of the curve is above
  half-way from 1 to its maximum, at least five bins) and reports its
  vertex. Its standard error is the larger of the error propagated from the
  fit's covariance (scaled up by the reduced χ² when the parabola fits worse
  than the noise) and the spread of the peaks fitted to Poisson resamples of
  the curve, which also covers a fitted window that jumps between competing
  maxima;
- a pair of rare minerals has few pairs per bin. :func:`count_bins` merges
  adjacent bins until an uncorrelated pattern would put ``min_count`` pairs into
  each one at a reference distance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = ["PeakFit", "count_bins", "first_peak", "merge_bins"]

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


@dataclass(frozen=True)
class PeakFit:
    """The first peak of g(r).

    Attributes
    ----------
    r, r_err
        Position of the peak and its standard error (length unit).
    g
        Height of the fitted parabola at ``r``.
    r_lo, r_hi
        Range of the bin centres that were fitted.
    highest_bin_r
        Centre of the highest bin (the unfitted estimate).
    fitted
        False when no parabola could be fitted and ``r`` is the smoothed
        curve's highest bin.
    """

    r: float
    r_err: float
    g: float
    r_lo: float
    r_hi: float
    highest_bin_r: float
    fitted: bool = True


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


def _fit(
    r: FloatArray,
    g: FloatArray,
    e: FloatArray,
    smooth: FloatArray | None = None,
    position_only: bool = False,
) -> tuple[float, float, float, int, int, bool]:
    """Fit the top of the highest peak: ``(r, error, g, lo, hi, fitted)`` (bin indices lo, hi).

    ``smooth`` is ``g`` smoothed, when already known; with ``position_only``
    the error is not computed (returned as NaN).
    """
    if smooth is None:
        smooth = _smooth(g)
    top = int(np.argmax(smooth))
    if r.size < MIN_FIT_BINS:
        half = 0.5 * float(r[-1] - r[0]) if r.size > 1 else 0.0
        return float(r[top]), half, float(smooth[top]), 0, r.size - 1, False
    level = smooth[top] - (1.0 - TOP_SHARE) * (smooth[top] - min(1.0, smooth[top]))
    lo = top
    while lo > 0 and smooth[lo - 1] >= level:
        lo -= 1
    hi = top
    while hi < r.size - 1 and smooth[hi + 1] >= level:
        hi += 1
    while hi - lo + 1 < MIN_FIT_BINS:
        lo, hi = (lo - 1, hi) if lo > 0 else (lo, hi + 1)
    x = r[lo : hi + 1] - r[top]
    y = g[lo : hi + 1]
    # Poisson error of each bin, from the smoothed g so that no bin gets zero weight
    sigma = np.sqrt(np.maximum(smooth[lo : hi + 1], 1.0 / e[lo : hi + 1]) / e[lo : hi + 1])
    design = np.column_stack([np.ones_like(x), x, x * x]) / sigma[:, None]
    coef, *_ = np.linalg.lstsq(design, y / sigma, rcond=None)
    c0, c1, c2 = (float(c) for c in coef)
    half = 0.5 * float(r[hi] - r[lo])
    if not c2 < 0:
        return float(r[top]), half, float(smooth[top]), lo, hi, False
    vertex = -c1 / (2.0 * c2)
    if not float(x[0]) <= vertex <= float(x[-1]):
        return float(r[top]), half, float(smooth[top]), lo, hi, False
    if position_only:
        return float(r[top] + vertex), math.nan, math.nan, lo, hi, True
    cov = np.linalg.pinv(design.T @ design)
    dof = x.size - 3
    if dof > 0:
        chi2 = float(np.sum(((y - (c0 + c1 * x + c2 * x * x)) / sigma) ** 2)) / dof
        cov = cov * max(1.0, chi2)
    jac = np.array([0.0, -1.0 / (2.0 * c2), c1 / (2.0 * c2 * c2)])
    err = float(np.sqrt(max(float(jac @ cov @ jac), 0.0)))
    return float(r[top] + vertex), err, c0 + c1 * vertex + c2 * vertex * vertex, lo, hi, True


def first_peak(
    r: FloatArray, g: FloatArray, expected: FloatArray, resamples: int = RESAMPLES
) -> PeakFit | None:
    """Fit the highest peak of ``g(r)`` (see the module's description).

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
        the parabola has no maximum inside the fitted bins, the peak is the
        smoothed curve's highest bin, ``fitted`` is false and the error is at
        least half the fitted range.

    Examples
    --------
    A peak at 3.27 between bins of 0.1, with 300 r pairs per bin expected:

    >>> rng = np.random.default_rng(1)
    >>> r = np.arange(0.05, 10.0, 0.1)
    >>> expected = 300 * r
    >>> g = rng.poisson((1 + np.exp(-((r - 3.27) ** 2) / 0.5)) * expected) / expected
    >>> fit = first_peak(r, g, expected)
    >>> abs(fit.r - 3.27) < 2 * fit.r_err < 0.05, round(fit.highest_bin_r, 2), fit.fitted
    (True, 3.35, True)
    """
    r = np.asarray(r, dtype=np.float64)
    g = np.asarray(g, dtype=np.float64)
    expected = np.asarray(expected, dtype=np.float64)
    ok = np.isfinite(g) & np.isfinite(expected) & (expected > 0)
    if not ok.any() or not np.any(g[ok] > 0):
        return None
    idx = np.flatnonzero(ok)
    r_ok, g_ok, e_ok = r[idx], g[idx], expected[idx]
    highest = float(r_ok[int(np.argmax(g_ok))])
    peak_r, err, peak_g, lo, hi, fitted = _fit(r_ok, g_ok, e_ok)
    if resamples > 0 and r_ok.size >= MIN_FIT_BINS:
        # the error of the parabola alone misses how the fitted window itself
        # moves with the noise (between competing maxima): resample the counts
        rng = np.random.default_rng(RESAMPLE_SEED)
        counts = g_ok * e_ok
        samples = np.stack([rng.poisson(counts) / e_ok for _ in range(int(resamples))])
        smoothed = _smooth(samples)
        found = [
            _fit(r_ok, samples[k], e_ok, smoothed[k], position_only=True)[0]
            for k in range(samples.shape[0])
        ]
        err = max(err, float(np.std(found, ddof=1)))
    return PeakFit(
        float(peak_r),
        float(err),
        float(peak_g),
        float(r_ok[lo]),
        float(r_ok[hi]),
        highest,
        bool(fitted),
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


def merge_bins(g: FloatArray, shell: FloatArray, factor: int) -> FloatArray:
    """g(r) over groups of ``factor`` bins, repeated over each group's bins.

    The merged value is the shell-area-weighted mean of the group (what the
    estimator gives for the merged bin); a last group shorter than
    ``factor`` joins the one before it. NaN bins are left out of a group's mean.

    Examples
    --------
    >>> merge_bins(np.array([1.0, 3.0, 2.0, 2.0, 5.0]), np.ones(5), 2).tolist()
    [2.0, 2.0, 3.0, 3.0, 3.0]
    """
    g = np.asarray(g, dtype=np.float64)
    if factor <= 1 or g.size == 0:
        return g.copy()
    groups = np.arange(g.size) // factor
    last = groups[-1]
    if g.size % factor and last > 0:
        groups[groups == last] = last - 1
    ok = np.isfinite(g)
    weight = np.where(ok, shell, 0.0)
    top = np.bincount(groups, weights=np.where(ok, g, 0.0) * weight)
    bottom = np.bincount(groups, weights=weight)
    with np.errstate(invalid="ignore", divide="ignore"):
        merged = np.where(bottom > 0, top / np.where(bottom > 0, bottom, 1.0), np.nan)
    return np.asarray(merged[groups], dtype=np.float64)
