r"""A cylinder's side wall as the available-surface analyses see it: an inscribed prism.

The exact analyses know caps (spheres) and planes (polyhedra); the side of
a cylinder is neither. The inserter therefore keeps every particle inside
the regular prism of ``N`` facets inscribed in the cylinder (its edges on
the wall), which lies inside the cylinder: containment is exact, and a
particle that touches a facet lies at most the prism's *sagitta*

.. math:: s = R \, (1 - \cos(\pi / N))

from the true wall. ``N`` is the least number of facets whose sagitta is at
most the scene's ``wall_gap`` times the population's smallest equivalent
diameter (:func:`prism_wall`), so the gap scales with the particles.

A facet ``m`` has the outward normal ``n_m = (cos t_m, sin t_m, 0)``,
``t_m = 2 pi m / N``, and lies at ``a = R cos(pi / N)`` from the axis. A
particle ``Q`` whose reference point is at ``x`` stays inside it when
``n_m · (x - axis) <= a - h_Q(n_m)``, ``h_Q`` its support function about the
reference point (its radius for a sphere). An analysis asks only for the
facets whose admissible plane comes within its reach of the candidate
(:func:`wall_planes`): an angular window about the candidate's azimuth,
found in closed form, so its cost does not grow with ``N``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.errors import ConfigError

FloatArray = NDArray[np.float64]

MIN_FACETS = 8
"""Fewest facets of the prism, however loose the gap allowed."""
MAX_FACETS = 1 << 22
"""Most facets of the prism (a cylinder of 10⁶ smallest diameters with a gap of 1e-3)."""
NO_WALL = np.zeros(0)
"""The wall record of a domain without a curved wall."""


def facet_count(radius: float, gap: float) -> int:
    """Fewest facets (at least :data:`MIN_FACETS`) of an inscribed prism with sagitta ≤ ``gap``.

    ``1 - cos(pi / N) = 2 sin²(pi / 2N)``, solved for ``N`` without the
    cancellation of ``1 - cos`` at small angles.

    Examples
    --------
    >>> facet_count(1.0, 1.0)
    8
    >>> facet_count(100.0, 0.001)
    703
    """
    if not (radius > 0 and gap > 0):
        raise ValueError(f"radius {radius!r} and gap {gap!r} must be > 0")
    ratio = gap / (2.0 * radius)
    if ratio >= 0.5:
        return MIN_FACETS
    n = math.ceil(math.pi / (2.0 * math.asin(math.sqrt(ratio))))
    while n > MIN_FACETS and sagitta(radius, n - 1) <= gap:
        n -= 1  # the rounding of asin may leave one facet too many
    while sagitta(radius, n) > gap:
        n += 1
    return max(MIN_FACETS, n)


def sagitta(radius: float, facets: int) -> float:
    """Largest distance from the prism's facets to the cylinder: ``R (1 - cos(pi / N))``."""
    half = math.sin(math.pi / (2.0 * facets))
    return 2.0 * radius * half * half


def prism_wall(cx: float, cy: float, radius: float, d_min: float, gap: float) -> FloatArray:
    """Return the wall record ``[cx, cy, a, N]`` of the prism inscribed in the cylinder.

    Parameters
    ----------
    cx, cy
        The cylinder's axis.
    radius
        Its radius.
    d_min
        The population's smallest equivalent diameter.
    gap
        Largest sagitta allowed, as a fraction of ``d_min``.

    Raises
    ------
    ConfigError
        When the prism would need more than :data:`MAX_FACETS` facets.
    """
    allowed = gap * d_min
    n = facet_count(radius, allowed) if allowed < 2.0 * radius else MIN_FACETS
    if n > MAX_FACETS:
        raise ConfigError(
            f"insertion.wall_gap = {gap:g}: a cylinder of radius {radius:g} keeps a gap of "
            f"{allowed:g} from its wall only with {n} facets (at most {MAX_FACETS}); "
            "give a larger insertion.wall_gap"
        )
    return np.array([cx, cy, radius - sagitta(radius, n), float(n)])


@numba.njit(cache=True)
def wall_planes(
    wall: FloatArray, c: FloatArray, reach: float, qv: FloatArray, r: float
) -> FloatArray:
    """Admissible planes ``n · x <= b`` of the facets that come within ``reach`` of ``c``.

    Parameters
    ----------
    wall
        The record of :func:`prism_wall` (empty: no curved wall, no plane).
    c
        ``(3,)`` the candidate's centre.
    reach
        How far from ``c`` the analysis looks (the envelope's or the sphere
        of centres' radius).
    qv
        ``(v, 3)`` the new particle's vertices about its reference point; for
        a sphere an empty array, and ``r`` its radius.
    r
        The sphere's radius (ignored with vertices).

    Returns
    -------
    ``(m, 4)`` rows ``n_x, n_y, n_z, b`` (``n_z = 0``), ``b`` in the domain's
    coordinates; every facet whose plane lies closer to ``c`` than ``reach``
    is among them.
    """
    if wall.shape[0] == 0:
        return np.empty((0, 4))
    cx = wall[0]
    cy = wall[1]
    a = wall[2]
    nf = int(wall[3])
    px = c[0] - cx
    py = c[1] - cy
    rho = math.sqrt(px * px + py * py)
    hmax = r
    if qv.shape[0] > 0:
        hmax = 0.0
        for v in range(qv.shape[0]):
            hmax = max(hmax, math.sqrt(qv[v, 0] * qv[v, 0] + qv[v, 1] * qv[v, 1]))
    # a facet's plane is within reach only if n · p > a - h - reach >= a - hmax - reach
    lim = a - hmax - reach
    two_pi = 2.0 * math.pi
    if lim >= rho:
        return np.empty((0, 4))
    if rho <= 0.0 or lim <= -rho:
        m0 = 0
        m1 = nf - 1
    else:
        half = math.acos(lim / rho)
        theta = math.atan2(py, px)
        m0 = math.floor((theta - half) * nf / two_pi) - 1
        m1 = math.ceil((theta + half) * nf / two_pi) + 1
        if m1 - m0 + 1 > nf:
            m0 = 0
            m1 = nf - 1
    out = np.empty((m1 - m0 + 1, 4))
    k = 0
    for mm in range(m0, m1 + 1):
        m = mm % nf
        t = two_pi * m / nf
        nx = math.cos(t)
        ny = math.sin(t)
        h = r
        if qv.shape[0] > 0:
            h = -np.inf
            for v in range(qv.shape[0]):
                h = max(h, nx * qv[v, 0] + ny * qv[v, 1])
        b = nx * cx + ny * cy + a - h
        if b - (nx * c[0] + ny * c[1]) < reach:
            out[k, 0] = nx
            out[k, 1] = ny
            out[k, 2] = 0.0
            out[k, 3] = b
            k += 1
    return out[:k]


def inside_prism(wall: FloatArray, x: FloatArray, qv: FloatArray, r: float) -> bool:
    """Whether a particle with reference point ``x`` lies inside the prism (every facet checked)."""
    if wall.shape[0] == 0:
        return True
    nf = int(wall[3])
    t = 2.0 * math.pi * np.arange(nf) / nf
    n = np.column_stack([np.cos(t), np.sin(t)])
    h = np.full(nf, r) if qv.shape[0] == 0 else (qv[:, :2] @ n.T).max(axis=0)
    b = n @ wall[:2] + wall[2] - h
    return bool(np.all(n @ np.asarray(x[:2], dtype=np.float64) <= b))
