"""The volume of a sphere inside an axis-aligned box, for the interior volume fraction.

The sphere is cut into horizontal disks; the area of a disk inside a
rectangle is exact (the chord length integrated in closed form between the
abscissae where the disk's edge crosses the rectangle's sides), and the
disks are integrated over height by adaptive quadrature (``scipy.integrate.quad``,
relative error about 1e-10). A ball that one face of the box cuts, the most
common case by far, is the ball less a spherical cap, in closed form.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import quad


def _chord_integral(x: float, r: float) -> float:
    """Antiderivative of ``sqrt(r^2 - x^2)``."""
    x = min(max(x, -r), r)
    return 0.5 * (x * math.sqrt(max(r * r - x * x, 0.0)) + r * r * math.asin(x / r))


def disk_in_rectangle(r: float, x0: float, x1: float, y0: float, y1: float) -> float:
    """Area of the disk of radius ``r`` about the origin inside ``[x0, x1] x [y0, y1]``.

    Examples
    --------
    >>> round(disk_in_rectangle(1.0, -2, 2, -2, 2), 12) == round(math.pi, 12)
    True
    >>> round(disk_in_rectangle(1.0, 0, 2, 0, 2), 12) == round(math.pi / 4, 12)
    True
    """
    if r <= 0.0:
        return 0.0
    a = max(x0, -r)
    b = min(x1, r)
    if a >= b or y0 >= y1:
        return 0.0
    cuts = {a, b}
    for y in (y0, y1):
        if abs(y) < r:
            x = math.sqrt(r * r - y * y)
            cuts.update(v for v in (-x, x) if a < v < b)
    xs = sorted(cuts)
    area = 0.0
    for lo, hi in itertools.pairwise(xs):
        mid = 0.5 * (lo + hi)
        s = math.sqrt(max(r * r - mid * mid, 0.0))
        top_is_edge = s < y1
        bottom_is_edge = -s > y0
        if min(y1, s) <= max(y0, -s):
            continue
        chord = _chord_integral(hi, r) - _chord_integral(lo, r)
        width = hi - lo
        top = chord if top_is_edge else y1 * width
        bottom = -chord if bottom_is_edge else y0 * width
        area += top - bottom
    return area


def sphere_in_box(centre: ArrayLike, r: float, lo: ArrayLike, hi: ArrayLike) -> float:
    """Volume of the ball of radius ``r`` about ``centre`` inside the box ``[lo, hi]``.

    Examples
    --------
    >>> v = sphere_in_box([0, 0, 0], 1.0, [0, 0, 0], [5, 5, 5])
    >>> abs(v - math.pi / 6) < 1e-9
    True
    """
    c = np.asarray(centre, dtype=np.float64)
    b0 = np.asarray(lo, dtype=np.float64) - c
    b1 = np.asarray(hi, dtype=np.float64) - c
    z0 = max(float(b0[2]), -r)
    z1 = min(float(b1[2]), r)
    if z0 >= z1:
        return 0.0
    # signed distances from the centre to the six faces, positive inside
    inside = np.concatenate([-b0, b1])
    if np.all(inside > -r):
        cut = np.flatnonzero(inside < r)
        if cut.size == 0:
            return 4.0 / 3.0 * math.pi * r**3
        if cut.size == 1:  # one face cuts the ball: a cap or the ball less one, in closed form
            d = float(inside[cut[0]])
            if d < 0.0:  # the centre lies outside: the part inside is the cap itself
                h = r + d
                return math.pi * h * h * (3.0 * r - h) / 3.0
            h = r - d
            return 4.0 / 3.0 * math.pi * r**3 - math.pi * h * h * (3.0 * r - h) / 3.0

    def area(z: float) -> float:
        return disk_in_rectangle(
            math.sqrt(max(r * r - z * z, 0.0)),
            float(b0[0]),
            float(b1[0]),
            float(b0[1]),
            float(b1[1]),
        )

    # the disk's edge meets a side of the rectangle, or a corner, at these heights
    points = []
    for d in (b0[0], b1[0], b0[1], b1[1]):
        if abs(d) < r:
            points.append(math.sqrt(r * r - d * d))
    for dx in (b0[0], b1[0]):
        for dy in (b0[1], b1[1]):
            if dx * dx + dy * dy < r * r:
                points.append(math.sqrt(r * r - dx * dx - dy * dy))
    breaks = sorted({p for z in points for p in (z, -z) if z0 < p < z1})
    value, _ = quad(area, z0, z1, points=breaks or None, epsabs=0.0, epsrel=1e-11, limit=200)
    return float(value)


def lens_volume(r1: float, r2: float, d: float) -> float:
    """Volume shared by two balls of radii ``r1``, ``r2`` whose centres are ``d`` apart.

    Examples
    --------
    >>> lens_volume(1.0, 1.0, 2.0)
    0.0
    >>> abs(lens_volume(1.0, 1.0, 0.0) - 4 / 3 * math.pi) < 1e-12
    True
    """
    if d >= r1 + r2:
        return 0.0
    small = min(r1, r2)
    if d <= abs(r1 - r2):
        return 4.0 / 3.0 * math.pi * small**3
    s = r1 + r2 - d
    return math.pi * s * s * (d * d + 2.0 * d * (r1 + r2) - 3.0 * (r1 - r2) ** 2) / (12.0 * d)
