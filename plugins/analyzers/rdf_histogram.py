"""Edge-corrected pair histograms of the radial distribution function, by window.

:func:`rdf_histogram` counts the centre pairs of a 2D window (a rectangle,
circle, convex polygon or periodic rectangle), :func:`rdf3d_histogram` those of
a box (walled or periodic), each with the window's edge correction (see
:mod:`regopack.plugins.analyzers.rdf`). Both check what their compiled kernel
(:mod:`~regopack.plugins.analyzers.rdf_kernel`,
:mod:`~regopack.plugins.analyzers.rdf3d_kernel`) indexes without checks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import (
    Box,
    Circle,
    ConvexPolygon,
    Cylinder,
    PeriodicRectangle,
    PlaneDomain,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

COVARIOGRAM_DIRECTIONS = 90
"""Directions over which a polygon window's covariogram is averaged."""


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
    images of the first ``n_real`` (see
    :func:`~regopack.plugins.analyzers.common.periodic_images`).

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
    kind = _checked_kinds(x, y, kind, n_kinds, n_real)
    _check_bins(r_lo, width, bins)
    from regopack.plugins.analyzers.rdf_kernel import weighted_pair_histogram

    edges = r_lo + width * np.arange(bins + 1)
    # every call passes every argument (the defaults spelt out), so that the kernel is
    # compiled once for all windows rather than once per set of omitted arguments
    if isinstance(window, PeriodicRectangle):
        assert n_real is not None
        hist = weighted_pair_histogram(
            x, y, kind, n_kinds, r_lo, width, bins, a, b, False, n_real
        ) / (a * b)
        area = a * b
        x, kind = x[:n_real], kind[:n_real]
    elif isinstance(window, Circle | ConvexPolygon):
        counts_r = weighted_pair_histogram(x, y, kind, n_kinds, r_lo, width, bins, a, b, False, -1)
        gamma = covariogram(window, 0.5 * (edges[:-1] + edges[1:]))
        with np.errstate(divide="ignore", invalid="ignore"):
            hist = np.where(gamma > 0, counts_r / gamma, np.nan)
        area = window.area
    else:
        hist = weighted_pair_histogram(x, y, kind, n_kinds, r_lo, width, bins, a, b, True, -1)
        area = a * b
    return _normalised(hist, kind, n_kinds, area, shells(edges, 2))


def _checked_kinds(
    x: FloatArray, y: FloatArray, kind: NDArray[np.int64], n_kinds: int, n_real: int | None
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
    if n_real is not None and not 0 <= n_real <= n:
        raise ValueError(f"n_real must lie in [0, {n}], not {n_real}")
    return kind


def _check_bins(r_lo: float, width: float, bins: int) -> None:
    """Refuse bins that a compiled kernel cannot index: none, or not finite and positive."""
    if not (bins >= 1 and math.isfinite(width) and width > 0 and math.isfinite(r_lo) and r_lo >= 0):
        raise ValueError(
            f"bins ({bins}) must be >= 1, width ({width}) > 0 and r_lo ({r_lo}) >= 0, finite"
        )


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


def rdf3d_histogram(
    points: FloatArray,
    kind: IntArray,
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    window: Box | Cylinder,
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
        A walled box (translation correction), a periodic box (nearest image)
        or a cylinder with a vertical axis (translation correction, see
        :func:`cylinder_pair_histogram`).

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
    _check_bins(r_lo, width, bins)
    edges = r_lo + width * np.arange(bins + 1)
    if isinstance(window, Cylinder):
        per_pair = cylinder_pair_histogram(pts, kind, n_kinds, r_lo, width, bins, window)
        return _normalised(per_pair, kind, n_kinds, window.volume, shells(edges, 3))
    side = np.array(window.size, dtype=np.float64)
    per_pair = weighted_pair_histogram3d(
        pts, kind, n_kinds, float(r_lo), float(width), int(bins), side, bool(window.periodic)
    )
    return _normalised(per_pair, kind, n_kinds, float(np.prod(side)), shells(edges, 3))


def cylinder_pair_histogram(
    points: FloatArray,
    kind: IntArray,
    n_kinds: int,
    r_lo: float,
    width: float,
    bins: int,
    window: Cylinder,
) -> FloatArray:
    """Pair-distance histogram of ``(n, 3)`` points in a vertical cylinder, translation-weighted.

    A pair at separation ``(dx, dy, dz)`` weighs ``1 / gamma``, where
    ``gamma = (H - |dz|) L(hypot(dx, dy))`` is the volume of the window
    ``W ∩ (W + d)`` (``H`` its height, ``L(s) = 2 R^2 acos(s / 2R) - (s / 2)
    sqrt(4 R^2 - s^2)`` the area two disks of its radius ``R`` share at a
    distance ``s``): the Ohser–Stoyan correction of the box, for the
    cylinder. ``gamma > 0`` for ``r < min(2R, H)``; farther pairs are left
    out. Unordered pairs are counted once, in cell ``[min(kind), max(kind)]``
    of the ``(n_kinds, n_kinds, bins)`` result.
    """
    from scipy.spatial import cKDTree

    out = np.zeros((n_kinds, n_kinds, bins))
    r_hi = r_lo + width * bins
    if len(points) < 2:
        return out
    ij = cKDTree(points).query_pairs(r_hi, output_type="ndarray")
    d = points[ij[:, 1]] - points[ij[:, 0]]
    r = np.sqrt(np.einsum("ij,ij->i", d, d))
    k = np.floor((r - r_lo) / width).astype(np.int64)
    keep = (r >= r_lo) & (k >= 0) & (k < bins)
    ij, d, k = ij[keep], d[keep], k[keep]
    radius = window.radius
    s = np.minimum(np.hypot(d[:, 0], d[:, 1]) / (2.0 * radius), 1.0)
    lens = 2.0 * radius * radius * (np.arccos(s) - s * np.sqrt(np.maximum(1.0 - s * s, 0.0)))
    gamma = (window.height - np.abs(d[:, 2])) * lens
    ok = gamma > 0
    a, b = kind[ij[ok, 0]], kind[ij[ok, 1]]
    np.add.at(out, (np.minimum(a, b), np.maximum(a, b), k[ok]), 1.0 / gamma[ok])
    return out


def shells(edges: NDArray[Any], dimension: int) -> FloatArray:
    """Area (2D) or volume (3D) of the shell between each pair of consecutive radii ``edges``."""
    if dimension == 2:
        return np.asarray(np.pi * (edges[1:] ** 2 - edges[:-1] ** 2), dtype=np.float64)
    return np.asarray(4.0 / 3.0 * np.pi * (edges[1:] ** 3 - edges[:-1] ** 3), dtype=np.float64)


def _normalised(
    hist: FloatArray, kind: IntArray, n_kinds: int, measure: float, shell: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``g(r)`` from the weighted pair counts ``hist`` of a window of area or volume ``measure``.

    ``g = |W|^2 / N_pairs * H / shell``, with ``N (N - 1) / 2`` pairs in all and,
    per kind pair ``(A, B)``, ``N_A N_B`` (``N_A (N_A - 1) / 2`` when ``A = B``);
    NaN where a kind pair has no pairs to normalise by.
    """
    counts = np.bincount(kind, minlength=n_kinds).astype(np.float64)
    measure2 = measure**2
    n = float(len(kind))
    total = hist.sum(axis=(0, 1)) * measure2 / (max(n * (n - 1.0) / 2.0, 1e-300) * shell)
    per = np.full_like(hist, np.nan)
    for p in range(n_kinds):
        for q in range(p, n_kinds):
            norm = counts[p] * (counts[p] - 1.0) / 2.0 if p == q else counts[p] * counts[q]
            if norm > 0:
                per[p, q] = hist[p, q] * measure2 / (norm * shell)
                per[q, p] = per[p, q]
    return total, per
