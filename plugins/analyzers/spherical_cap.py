"""The equivalent spherical cap of a 3D contact region (the 3D counterpart of the bow).

A contact region of volume ``V`` whose projection on the contact plane has
the area ``A`` is given the spherical cap of the same base area and volume:
its height ``delta`` and the radius of its sphere describe the contact as the
circular segment does in 2D (:mod:`regopack.plugins.analyzers.segment`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def equivalent_cap(volume: FloatArray, area: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Spherical cap with base area ``area`` and volume ``volume``: its height and sphere radius.

    The cap of base radius ``a = sqrt(area / pi)`` and height ``h`` has the
    volume ``pi h (3 a^2 + h^2) / 6``; ``h`` is the one positive root of that
    cubic, found by Newton's method from above (the cubic is convex for
    ``h > 0``, so the iterates fall monotonically onto the root, without
    cancellation however thin the cap). The sphere radius is
    ``(a^2 + h^2) / (2 h)``. Both are 0 where the volume or the area is not positive.

    Examples
    --------
    A hemisphere of radius 1:

    >>> h, r = equivalent_cap(np.array([2 * np.pi / 3]), np.array([np.pi]))
    >>> round(float(h[0]), 12), round(float(r[0]), 12)
    (1.0, 1.0)
    """
    volume = np.asarray(volume, dtype=np.float64)
    area = np.asarray(area, dtype=np.float64)
    ok = (volume > 0) & (area > 0)
    a2 = np.where(ok, area / np.pi, 1.0)
    v6 = np.where(ok, 6.0 * volume / np.pi, 0.0)
    # both starting points lie above the root: f(2V/A) = (2V/A)^3, f(cbrt(6V/pi)) = 3 a^2 h > 0
    h = np.minimum(2.0 * np.where(ok, volume / np.where(ok, area, 1.0), 0.0), np.cbrt(v6))
    for _ in range(100):
        step = (h * h * h + 3.0 * a2 * h - v6) / (3.0 * h * h + 3.0 * a2)
        h = h - step
        if not np.any(step > 1e-15 * h):
            break
    h = np.where(ok, h, 0.0)
    radius = np.where(ok & (h > 0), (a2 + h * h) / (2.0 * np.where(h > 0, h, 1.0)), 0.0)
    return h, radius
