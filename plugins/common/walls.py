"""Compiled wall constraints of the built-in inserters, for every domain kind.

A domain is handed to the kernels as a mode and a small float array
(:func:`wall_arrays`):

- ``WALL_BOX``: ``[[xmin, xmax, ymin, ymax]]``, a walled rectangle;
- ``WALL_HALFPLANES``: one row ``[nx, ny, b]`` per wall of a convex polygon,
  inside is ``n . x <= b``;
- ``WALL_CIRCLE``: ``[[cx, cy, R]]``;
- ``WALL_PERIODIC``: ``[[xmin, xmax, ymin, ymax]]``, no walls: the sides wrap.

A particle of outline ``v_j`` (relative to its reference point) centred at
``x`` lies inside a convex container exactly when every vertex ``x + v_j``
does, so the admissible centres are an intersection of half-planes (polygon
walls) or of disks of radius ``R`` about ``c - v_j`` (circular wall). The
clipping functions return the closed parameter interval of a segment that
lies in that set: a particle touching a wall is admissible.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.errors import GeometryError
from regopack.base.limits import LimitError
from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle

FloatArray = NDArray[np.float64]

WALL_BOX, WALL_HALFPLANES, WALL_CIRCLE, WALL_PERIODIC = range(4)


def wall_arrays(domain: Domain) -> tuple[int, FloatArray]:
    """Return the kernel mode and wall array of ``domain`` (see the module docstring).

    Raises
    ------
    GeometryError
        For a domain kind the built-in inserters do not know.
    """
    if isinstance(domain, PeriodicRectangle):
        return WALL_PERIODIC, domain.bounds().reshape(1, 4)
    if isinstance(domain, Rectangle):
        return WALL_BOX, domain.bounds().reshape(1, 4)
    if isinstance(domain, ConvexPolygon):
        normal, offset = domain.halfplanes()
        return WALL_HALFPLANES, np.ascontiguousarray(np.column_stack([normal, offset]))
    if isinstance(domain, Circle):
        return WALL_CIRCLE, np.array([[domain.cx, domain.cy, domain.radius]])
    raise GeometryError(f"the built-in inserters do not support domains of kind {domain.kind!r}")


class PeriodicSizeError(LimitError, GeometryError):
    """A periodic domain too small for its particles; names the shorter side's field."""


def check_periodic_size(domain: Domain, circumradius: FloatArray) -> None:
    """Raise :class:`PeriodicSizeError` when a periodic domain is too small for its particles.

    Both periods must exceed four times the largest circumradius: two
    particles then overlap through one periodic image at most, and the
    neighbour search of the inserters needs the images one period away only.
    """
    if not isinstance(domain, PeriodicRectangle) or circumradius.shape[0] == 0:
        return
    need = 4.0 * float(circumradius.max())
    short = min(domain.width, domain.height)
    if not short > need:
        field = "domain.width" if domain.width <= domain.height else "domain.height"
        raise PeriodicSizeError(
            field,
            short,
            f"a periodic domain must be wider and higher than 4 x the largest particle "
            f"circumradius ({need:.6g}); give a larger domain or smaller particles",
        )


@numba.njit(cache=True)
def wrap_periodic(x: float, lo: float, hi: float) -> float:
    """Map ``x`` into ``[lo, hi)``."""
    period = hi - lo
    out = lo + (x - lo) - period * math.floor((x - lo) / period)
    if out >= hi:
        out -= period
    if out < lo:
        out = lo
    return out


@numba.njit(cache=True)
def point_fits(
    x: float,
    y: float,
    vx: FloatArray,
    vy: FloatArray,
    start: int,
    stop: int,
    mode: int,
    walls: FloatArray,
    rho: float = 0.0,
) -> bool:
    """Return whether the outline ``v[start:stop]`` centred at ``(x, y)`` lies inside the walls.

    ``rho`` rounds the outline (its Minkowski sum with a disk of that radius).
    """
    if mode == WALL_PERIODIC:
        return True
    for j in range(start, stop):
        px = x + vx[j]
        py = y + vy[j]
        if mode == WALL_BOX:
            if (
                px - rho < walls[0, 0]
                or px + rho > walls[0, 1]
                or py - rho < walls[0, 2]
                or py + rho > walls[0, 3]
            ):
                return False
        elif mode == WALL_HALFPLANES:
            for e in range(walls.shape[0]):
                if walls[e, 0] * px + walls[e, 1] * py + rho > walls[e, 2]:
                    return False
        else:
            if math.hypot(px - walls[0, 0], py - walls[0, 1]) + rho > walls[0, 2]:
                return False
    return True


@numba.njit(cache=True)
def particle_offsets(
    vx: FloatArray, vy: FloatArray, start: int, stop: int, walls: FloatArray, out: FloatArray
) -> None:
    """Offsets ``b_e - h(n_e)`` of the admissible centres of one outline (polygon walls).

    ``h(n)`` is the outline's support value, so centre ``x`` is admissible
    exactly when ``n_e . x <= out[e]`` for every wall ``e``.
    """
    for e in range(walls.shape[0]):
        h = -np.inf
        for j in range(start, stop):
            p = walls[e, 0] * vx[j] + walls[e, 1] * vy[j]
            if p > h:
                h = p
        out[e] = walls[e, 2] - h


@numba.njit(cache=True)
def clip_closed_halfplanes(
    ax: float, ay: float, dx: float, dy: float, walls: FloatArray, offsets: FloatArray
) -> tuple[float, float]:
    """Interval ``[lo, hi]`` of ``a + s d`` with ``n_e . (a + s d) <= offsets[e]`` for all ``e``."""
    lo = -np.inf
    hi = np.inf
    for e in range(walls.shape[0]):
        f0 = walls[e, 0] * ax + walls[e, 1] * ay - offsets[e]
        f1 = walls[e, 0] * dx + walls[e, 1] * dy
        if f1 > 0.0:
            t = -f0 / f1
            if t < hi:
                hi = t
        elif f1 < 0.0:
            t = -f0 / f1
            if t > lo:
                lo = t
        elif f0 > 0.0:
            return 1.0, 0.0
        if lo > hi:
            return 1.0, 0.0
    return lo, hi


@numba.njit(cache=True)
def clip_closed_circle(
    ax: float,
    ay: float,
    dx: float,
    dy: float,
    qx: FloatArray,
    qy: FloatArray,
    m: int,
    sign: float,
    reach: float,
    walls: FloatArray,
) -> tuple[float, float]:
    """Interval ``[lo, hi]`` of centres ``a + s d`` that keep an outline inside a circular wall.

    The outline's vertices are ``sign * q[:m]`` relative to its centre (``sign
    = -1`` reads the reflected outline of the available-arc kernel), ``reach``
    is its circumradius, and ``walls[0] = [cx, cy, R]``.
    """
    cx = walls[0, 0]
    cy = walls[0, 1]
    r = walls[0, 2]
    # both ends farther than reach inside the wall: the whole segment fits
    inner = r - reach
    if inner >= 0.0:
        ea = math.hypot(ax - cx, ay - cy)
        eb = math.hypot(ax + dx - cx, ay + dy - cy)
        if ea <= inner and eb <= inner:
            return -np.inf, np.inf
    lo = -np.inf
    hi = np.inf
    aa = dx * dx + dy * dy
    r2 = r * r
    for j in range(m):
        px = ax + sign * qx[j] - cx
        py = ay + sign * qy[j] - cy
        c = px * px + py * py - r2
        if aa == 0.0:
            if c > 0.0:
                return 1.0, 0.0
            continue
        b = px * dx + py * dy
        disc = b * b - aa * c
        if disc < 0.0:
            return 1.0, 0.0
        root = math.sqrt(disc)
        q = -(b + root) if b >= 0.0 else -(b - root)
        if q == 0.0:  # b = 0 and c = 0: a double root at s = 0
            s1 = 0.0
            s2 = 0.0
        else:
            s1 = q / aa
            s2 = c / q
        if s1 > s2:
            s1, s2 = s2, s1
        if s1 > lo:
            lo = s1
        if s2 < hi:
            hi = s2
        if lo > hi:
            return 1.0, 0.0
    return lo, hi
