"""The equivalent circular segment (bow) of a contact region (SPEC §5).

Given a contact region of area ``A`` and width (chord) ``b``, the circular
segment with the same chord and area has the central angle ``theta`` solving
``(theta - sin theta) / (8 sin^2(theta / 2)) = A / b^2``. Its radius is
``R = b / (2 sin(theta / 2))`` and its depth (sagitta)
``delta = R (1 - cos(theta / 2))``.

The left side grows from 0 (``theta -> 0``) through ``pi / 8`` (a half disk)
to infinity (``theta -> 2 pi``). The solver works in ``theta`` below ``pi``
and in ``phi = 2 pi - theta`` above, with series for the small-angle ends, so
it stays accurate and free of NaN for ratios from 1e-15 to 1e15.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
HALF_DISK = math.pi / 8.0


def _theta_minus_sin(x: FloatArray) -> FloatArray:
    """``x - sin x`` without cancellation for small ``x``."""
    small = np.abs(x) < 1e-2
    x2 = x * x
    series = x * x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)))
    return np.where(small, series, x - np.sin(x))


def segment_ratio(theta: ArrayLike) -> FloatArray:
    """Area over squared chord of the circular segment with central angle ``theta``.

    Examples
    --------
    >>> float(segment_ratio(np.pi)) == np.pi / 8
    True
    """
    t = np.asarray(theta, dtype=np.float64)
    lower = t <= math.pi
    phi = 2.0 * math.pi - t
    half = np.where(lower, t, phi) / 2.0
    # theta - sin(theta) = 2 pi - phi + sin(phi) above pi
    num = np.where(lower, _theta_minus_sin(t), 2.0 * math.pi - phi + np.sin(phi))
    return num / (8.0 * np.sin(half) ** 2)


def solve_theta(ratio: ArrayLike) -> FloatArray:
    """Central angle ``theta`` in ``(0, 2 pi)`` of the segment with ``A / b^2 = ratio``.

    Bisection on a bracket followed by Newton polishing, vectorised; ratios
    below 1e-9 use the series ``theta = 12 q (1 - 12 q^2 / 5 ...)`` directly.
    """
    q = np.asarray(ratio, dtype=np.float64)
    if np.any(~(q > 0)) or np.any(~np.isfinite(q)):
        raise ValueError("segment ratios must be positive and finite")
    lower = q <= HALF_DISK
    # work in x = theta (lower branch) or x = phi = 2 pi - theta (upper branch), x in (0, pi]
    lo = np.zeros_like(q)
    hi = np.full_like(q, math.pi)

    def g(x: FloatArray) -> FloatArray:
        theta = np.where(lower, x, 2.0 * math.pi - x)
        return segment_ratio(theta)

    for _ in range(64):
        mid = 0.5 * (lo + hi)
        val = g(mid)
        # on the lower branch g grows with x; on the upper branch it falls with x = phi
        go_up = np.where(lower, val < q, val > q)
        lo = np.where(go_up, mid, lo)
        hi = np.where(go_up, hi, mid)
        if np.all(hi - lo <= 1e-15 * np.maximum(hi, 1e-300)):
            break
    x = 0.5 * (lo + hi)
    tiny = q < 1e-9
    series = 12.0 * q * (1.0 - 12.0 * q * q / 5.0)
    x = np.where(tiny, series, x)
    return np.where(lower, x, 2.0 * math.pi - x)


def equivalent_segment(
    area: ArrayLike, chord: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Central angle, radius and depth of the segment with the given area and chord.

    Returns
    -------
    theta, radius, depth
        Arrays of the broadcast shape; ``depth`` is never negative.

    Examples
    --------
    >>> theta, radius, depth = equivalent_segment(np.pi / 2, 2.0)  # a half unit disk
    >>> bool(np.isclose(theta, np.pi) and np.isclose(radius, 1.0) and np.isclose(depth, 1.0))
    True
    """
    a = np.asarray(area, dtype=np.float64)
    b = np.asarray(chord, dtype=np.float64)
    theta = solve_theta(a / (b * b))
    lower = theta <= math.pi
    half = np.where(lower, theta, 2.0 * math.pi - theta) / 2.0
    s = np.sin(half)
    radius = b / (2.0 * s)
    # 1 - cos(theta / 2) = 2 sin^2(theta / 4) below pi; 1 + cos(phi / 2) above
    depth = np.where(lower, radius * 2.0 * np.sin(theta / 4.0) ** 2, radius * (1.0 + np.cos(half)))
    return theta, radius, depth
