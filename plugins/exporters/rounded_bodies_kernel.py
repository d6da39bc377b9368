"""Compiled batch of :mod:`regopack.plugins.exporters.rounded_bodies` for many particles at once.

:func:`rounded_bodies` cleans, erodes and measures every particle of a packing
with the same rules as :func:`~regopack.plugins.exporters.rounded_bodies.clean_outline`,
:func:`~regopack.plugins.exporters.rounded_bodies.erode_convex` and
:func:`~regopack.plugins.exporters.rounded_bodies.rounded_moments`, which stay the
readable reference the tests compare it with.
"""

from __future__ import annotations

import math

import numba
import numpy as np

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.geometry.population import FloatArray, IntArray
from regopack.plugins.common.halfplane_clip import clip_halfplane

__all__ = ["rounded_bodies"]

OK, NO_OUTLINE, TOO_THIN = 0, 1, 2
"""Status of one particle in :func:`rounded_bodies`."""


@numba.njit(cache=True)
def _clean(px: FloatArray, py: FloatArray, n: int, tol: float) -> int:
    """Clean ``p[:n]`` in place like ``clean_outline``; return the new count."""
    if n == 0:
        return 0
    xmin, xmax, ymin, ymax = px[0], px[0], py[0], py[0]
    for i in range(n):
        xmin, xmax = min(xmin, px[i]), max(xmax, px[i])
        ymin, ymax = min(ymin, py[i]), max(ymax, py[i])
    eps = tol * max(xmax - xmin, ymax - ymin)
    changed = True
    while changed and n > 1:
        changed = False
        for i in range(n):  # repeated vertices: drop the earlier one
            k = (i + 1) % n
            if math.hypot(px[k] - px[i], py[k] - py[i]) <= eps:
                for m in range(i, n - 1):
                    px[m], py[m] = px[m + 1], py[m + 1]
                n -= 1
                changed = True
                break
        if changed or n < 3:
            continue
        for i in range(n):  # collinear vertices
            a = i - 1 if i > 0 else n - 1
            c = (i + 1) % n
            ux, uy = px[c] - px[a], py[c] - py[a]
            length = math.hypot(ux, uy)
            if length <= eps or abs(ux * (py[i] - py[a]) - uy * (px[i] - px[a])) <= eps * length:
                for m in range(i, n - 1):
                    px[m], py[m] = px[m + 1], py[m + 1]
                n -= 1
                changed = True
                break
    return n


@numba.njit(cache=True)
def _erode(
    vx: FloatArray,
    vy: FloatArray,
    n: int,
    r: float,
    px: FloatArray,
    py: FloatArray,
    qx: FloatArray,
    qy: FloatArray,
) -> int:
    """Erode ``v[:n]`` by ``r`` into ``p`` like ``erode_convex`` (before cleaning)."""
    for i in range(n):
        px[i], py[i] = vx[i], vy[i]
    count = n
    for i in range(n):
        k = (i + 1) % n
        ex, ey = vx[k] - vx[i], vy[k] - vy[i]
        length = math.hypot(ex, ey)
        if length == 0.0:
            continue
        a, b = ey / length, -ex / length
        c = a * vx[i] + b * vy[i] - r
        out = clip_halfplane(px, py, count, a, b, c, qx, qy)
        for j in range(out):
            px[j], py[j] = qx[j], qy[j]
        count = out
        if count < 3:
            return 0
    return count


@numba.njit(cache=True)
def _add_polygon(m: FloatArray, x0: float, y0: float, x1: float, y1: float) -> None:
    """Add one edge's shoelace terms to the raw moments ``m``."""
    cross = x0 * y1 - x1 * y0
    m[0] += cross / 2.0
    m[1] += (x0 + x1) * cross / 6.0
    m[2] += (y0 + y1) * cross / 6.0
    m[3] += (x0 * x0 + x0 * x1 + x1 * x1) * cross / 12.0
    m[4] += (y0 * y0 + y0 * y1 + y1 * y1) * cross / 12.0
    m[5] += (x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross / 24.0


@numba.njit(cache=True)
def _add_sector(m: FloatArray, px: float, py: float, r: float, a: float, b: float) -> None:
    """Add the raw moments of a sector of radius ``r`` at ``p`` from ``a`` to ``b``."""
    da = b - a
    area = 0.5 * r * r * da
    mx = r**3 / 3.0 * (math.sin(b) - math.sin(a))
    my = r**3 / 3.0 * (math.cos(a) - math.cos(b))
    r4 = r**4
    s2 = math.sin(2 * b) - math.sin(2 * a)
    m[0] += area
    m[1] += mx + px * area
    m[2] += my + py * area
    m[3] += r4 / 8.0 * (da + 0.5 * s2) + 2 * px * mx + px * px * area
    m[4] += r4 / 8.0 * (da - 0.5 * s2) + 2 * py * my + py * py * area
    m[5] += r4 / 16.0 * (math.cos(2 * a) - math.cos(2 * b)) + px * my + py * mx + px * py * area


@numba.njit(cache=True)
def _moments(px: FloatArray, py: FloatArray, n: int, r: float, m: FloatArray) -> None:
    """Raw moments of the core ``p[:n]`` grown by ``r`` into ``m`` (like ``rounded_moments``)."""
    m[:] = 0.0
    if n >= 3:
        for i in range(n):
            k = (i + 1) % n
            _add_polygon(m, px[i], py[i], px[k], py[k])
    if r <= 0.0:
        return
    if n == 1:
        _add_sector(m, px[0], py[0], r, 0.0, 2 * math.pi)
        return
    for i in range(n):
        k = (i + 1) % n
        ex, ey = px[k] - px[i], py[k] - py[i]
        length = math.hypot(ex, ey)
        nx, ny = ey / length * r, -ex / length * r
        xs = (px[i], px[i] + nx, px[k] + nx, px[k])
        ys = (py[i], py[i] + ny, py[k] + ny, py[k])
        for j in range(4):
            j2 = (j + 1) % 4
            _add_polygon(m, xs[j], ys[j], xs[j2], ys[j2])
    for i in range(n):
        h = i - 1 if i > 0 else n - 1
        k = (i + 1) % n
        before = math.atan2(-(px[i] - px[h]), py[i] - py[h])
        after = math.atan2(-(px[k] - px[i]), py[k] - py[i])
        turn = (after - before) % (2 * math.pi)
        _add_sector(m, px[i], py[i], r, before, before + turn)


@numba.njit(cache=True)
def _batch(
    vertices: FloatArray,
    offsets: IntArray,
    idx: IntArray,
    own: FloatArray,
    target: FloatArray,
    tol: float,
    tries: int,
    out_vertices: FloatArray,
    out_counts: IntArray,
    out_r: FloatArray,
    out_m: FloatArray,
    status: IntArray,
) -> None:
    width = 4
    for j in idx:
        width = max(width, offsets[j + 1] - offsets[j] + 2)
    vx = np.empty(width)
    vy = np.empty(width)
    px = np.empty(2 * width)
    py = np.empty(2 * width)
    qx = np.empty(2 * width)
    qy = np.empty(2 * width)
    m = np.zeros(6)
    out = 0
    for k in range(idx.size):
        j = idx[k]
        n = offsets[j + 1] - offsets[j]
        for i in range(n):
            vx[i] = vertices[offsets[j] + i, 0]
            vy[i] = vertices[offsets[j] + i, 1]
        r = own[k]
        status[k] = OK
        if r > 0.0:  # a disk or a rounded polygon keeps its core and radius
            count = n if n == 1 else _clean(vx, vy, n, tol)
            for i in range(count):
                px[i], py[i] = vx[i], vy[i]
        else:
            n = _clean(vx, vy, n, tol)
            count = 0
            if n < 3:
                status[k] = NO_OUTLINE
            else:
                r = target[k]
                for attempt in range(tries):
                    count = _erode(vx, vy, n, r, px, py, qx, qy)
                    count = _clean(px, py, count, tol) if count >= 3 else 0
                    if count >= 3:
                        if attempt > 0:
                            status[k] = -1  # reduced
                        break
                    r *= 0.5
                if count < 3:
                    status[k] = TOO_THIN
        if status[k] > 0:
            out_counts[k] = 0
            continue
        _moments(px, py, count, r, m)
        out_m[k] = m
        out_r[k] = r
        out_counts[k] = count
        for i in range(count):
            out_vertices[out + i, 0] = px[i]
            out_vertices[out + i, 1] = py[i]
        out += count


def rounded_bodies(
    vertices: FloatArray,
    offsets: IntArray,
    idx: IntArray,
    own: FloatArray,
    target: FloatArray,
    tol: float,
    tries: int,
) -> tuple[FloatArray, IntArray, FloatArray, FloatArray, IntArray]:
    """Cores, radii and raw moments of the particles ``idx``.

    Parameters
    ----------
    vertices, offsets
        The packing's outlines (relative to the particle centres).
    idx
        Particles to process.
    own
        Each particle's own rounding radius (``> 0``: a disk or rounded polygon).
    target
        Rounding radius wanted for each sharp polygon.
    tol
        Cleaning tolerance relative to an outline's size.
    tries
        Times the radius is halved when the eroded core vanishes.

    Returns
    -------
    tuple
        ``(core_vertices, core_counts, radius, raw_moments, status)``: the cores
        one after another, their vertex counts, the radii, ``(n, 6)`` raw
        moments ``(A, ∫x, ∫y, ∫x², ∫y², ∫xy)`` about the particle centre, and a
        status per particle (0 fine, -1 radius halved, 1 fewer than 3 distinct
        vertices, 2 too thin).
    """
    n = idx.size
    sizes = offsets[idx + 1] - offsets[idx]
    out_vertices = np.empty((int(sizes.sum()) + 2 * n, 2))
    out_counts = np.zeros(n, dtype=np.int64)
    out_r = np.zeros(n)
    out_m = np.zeros((n, 6))
    status = np.zeros(n, dtype=np.int64)
    _batch(
        np.ascontiguousarray(vertices, dtype=np.float64),
        np.ascontiguousarray(offsets, dtype=np.int64),
        np.ascontiguousarray(idx, dtype=np.int64),
        np.ascontiguousarray(own, dtype=np.float64),
        np.ascontiguousarray(target, dtype=np.float64),
        float(tol),
        int(tries),
        out_vertices,
        out_counts,
        out_r,
        out_m,
        status,
    )
    return out_vertices[: int(out_counts.sum())], out_counts, out_r, out_m, status
