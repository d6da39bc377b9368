"""Compiled convex-polygon primitives in a face's plane.

Polygons are counter-clockwise vertex lists in the 2D frame ``(e1, e2)`` of a
plane with unit normal ``nrm`` (``e1 × e2 = nrm``, see :func:`plane_frame`), so
counter-clockwise in the frame is counter-clockwise seen from the side the
normal points to.

Except for :func:`convex_hull_2d`, the primitives read and write polygons
as pairs of rows of one 2D scratch array, named by row index: a compiled
call then passes one array instead of up to eight, which saves the
reference counting of every array argument (it dominated the cost of the
small polygons these functions see).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SMALL_SORT = 24
"""Inputs up to this size are sorted by insertion, larger ones by merge sort."""
SWEEP_DIRECTION = (math.cos(1.0), math.sin(1.0))
"""Direction along which the hull sweeps its points (at one radian from ``e1``)."""


@numba.njit(cache=True)
def plane_frame(nx: float, ny: float, nz: float) -> tuple[float, float, float, float, float, float]:
    """Return unit vectors ``e1, e2`` (six floats) with ``e1 × e2 = n`` for a unit ``n``."""
    ax = abs(nx)
    ay = abs(ny)
    az = abs(nz)
    # e1 = n × (the axis of n's smallest component), normalised
    if ax <= ay and ax <= az:
        e1x, e1y, e1z = 0.0, nz, -ny
    elif ay <= az:
        e1x, e1y, e1z = -nz, 0.0, nx
    else:
        e1x, e1y, e1z = ny, -nx, 0.0
    inv = 1.0 / math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x *= inv
    e1y *= inv
    e1z *= inv
    e2x = ny * e1z - nz * e1y
    e2y = nz * e1x - nx * e1z
    e2z = nx * e1y - ny * e1x
    return e1x, e1y, e1z, e2x, e2y, e2z


@numba.njit(cache=True)
def _sweep_order(x: FloatArray, y: FloatArray, n: int, order: IntArray, at: int) -> None:
    """Sort ``(x, y)[:n]`` along :data:`SWEEP_DIRECTION`, ties by the normal one.

    Writes the indices to ``order[at:at + n]``. A direction that is not a
    lattice direction keeps points on a common line (the side of a face,
    often axis-aligned) from being ordered by rounding noise alone.
    """
    c, s = SWEEP_DIRECTION
    if n > SMALL_SORT:
        u = np.empty(n)
        w = np.empty(n)
        for i in range(n):
            u[i] = c * x[i] + s * y[i]
            w[i] = c * y[i] - s * x[i]
        by_w = np.argsort(w, kind="mergesort")
        order[at : at + n] = by_w[np.argsort(u[by_w], kind="mergesort")]
        return
    for i in range(n):
        ui = c * x[i] + s * y[i]
        wi = c * y[i] - s * x[i]
        j = i
        while j > 0:
            o = order[at + j - 1]
            uo = c * x[o] + s * y[o]
            if uo < ui or (uo == ui and c * y[o] - s * x[o] <= wi):
                break
            order[at + j] = o
            j -= 1
        order[at + j] = i


@numba.njit(cache=True)
def convex_hull_2d(x: FloatArray, y: FloatArray, n: int, tol: float, out: IntArray) -> int:
    """Counter-clockwise convex hull of the points ``(x, y)[:n]``.

    Writes the indices of the hull's corners to ``out`` and returns their
    number; ``out`` needs room for ``2 n + 1`` (its tail holds the sweep
    order). A point closer than ``tol`` to the line through its neighbours
    on the hull is not a corner (nor is a duplicate), so points that all lie
    within ``tol`` of a line give at most 2 corners. Andrew's monotone chain,
    sweeping along :data:`SWEEP_DIRECTION`.
    """
    if n <= 1:
        if n == 1:
            out[0] = 0
        return n
    at = n + 1
    _sweep_order(x, y, n, out, at)
    k = 0
    for pass_ in range(2):
        floor = k + 1 if pass_ == 1 else 2
        for step in range(n) if pass_ == 0 else range(n - 2, -1, -1):
            i = out[at + step]
            while k >= floor:
                o = out[k - 2]
                a = out[k - 1]
                bx = x[i] - x[o]
                by = y[i] - y[o]
                # pop ``a`` unless it lies more than ``tol`` to the right of o -> i
                cross = (x[a] - x[o]) * by - (y[a] - y[o]) * bx
                if cross > tol * math.sqrt(bx * bx + by * by):
                    break
                k -= 1
            out[k] = i
            k += 1
    return k - 1  # the last corner repeats the first


@numba.njit(cache=True)
def split_polygon(
    rows: FloatArray, x: int, y: int, n: int, g: int, ix: int, iy: int, ox: int, oy: int
) -> tuple[int, int]:
    """Split a convex polygon along the zero line of an affine function.

    The polygon is ``rows[x, :n], rows[y, :n]`` and ``rows[g, :n]`` the
    function's values at its vertices (all rows of one 2D array, so that a
    call passes one array). The closed part ``g >= 0`` goes to rows ``ix,
    iy`` and the closed part ``g <= 0`` to rows ``ox, oy`` (``n + 1`` columns
    each at most); returns their vertex counts. A part with fewer than 3
    vertices is empty or degenerate.
    """
    return _split(rows, x, y, n, g, ix, iy, ox, oy, True)


@numba.njit(cache=True)
def clip_polygon(rows: FloatArray, x: int, y: int, n: int, g: int, ix: int, iy: int) -> int:
    """Write the closed part ``g >= 0`` of a convex polygon to rows ``ix, iy``.

    See :func:`split_polygon`; returns the part's vertex count.
    """
    return _split(rows, x, y, n, g, ix, iy, ix, iy, False)[0]


@numba.njit(cache=True, inline="always")
def _split(
    rows: FloatArray,
    x: int,
    y: int,
    n: int,
    g: int,
    ix: int,
    iy: int,
    ox: int,
    oy: int,
    outside: bool,
) -> tuple[int, int]:
    """:func:`split_polygon`; the part ``g <= 0`` is written only when ``outside`` (else 0).

    Inlined with ``outside`` a constant, so that the compiler drops the
    branches of the part not asked for.
    """
    nin = 0
    nout = 0
    for j in range(n):
        j2 = j + 1 if j + 1 < n else 0
        f1 = rows[g, j]
        f2 = rows[g, j2]
        if f1 >= 0.0:
            rows[ix, nin] = rows[x, j]
            rows[iy, nin] = rows[y, j]
            nin += 1
        if outside and f1 <= 0.0:
            rows[ox, nout] = rows[x, j]
            rows[oy, nout] = rows[y, j]
            nout += 1
        if (f1 > 0.0 and f2 < 0.0) or (f1 < 0.0 and f2 > 0.0):
            u = f1 / (f1 - f2)
            cx = rows[x, j] + u * (rows[x, j2] - rows[x, j])
            cy = rows[y, j] + u * (rows[y, j2] - rows[y, j])
            rows[ix, nin] = cx
            rows[iy, nin] = cy
            nin += 1
            if outside:
                rows[ox, nout] = cx
                rows[oy, nout] = cy
                nout += 1
    return nin, nout


@numba.njit(cache=True)
def copy_polygon(rows: FloatArray, x: int, y: int, n: int, tx: int, ty: int) -> None:
    """Copy the polygon in rows ``x, y`` to rows ``tx, ty``."""
    for i in range(n):
        rows[tx, i] = rows[x, i]
        rows[ty, i] = rows[y, i]


@numba.njit(cache=True)
def polygon_area(rows: FloatArray, x: int, y: int, start: int, n: int) -> float:
    """Signed area (positive when counter-clockwise) of the polygon in rows ``x, y``.

    Its vertices are columns ``start`` to ``start + n - 1``.
    """
    if n < 3:
        return 0.0
    s = 0.0
    x0 = rows[x, start]
    y0 = rows[y, start]
    for j in range(start + 1, start + n - 1):
        s += (rows[x, j] - x0) * (rows[y, j + 1] - y0) - (rows[x, j + 1] - x0) * (rows[y, j] - y0)
    return 0.5 * s


@numba.njit(cache=True)
def polygon_perimeter(rows: FloatArray, x: int, y: int, n: int) -> float:
    """Perimeter of the polygon in rows ``x, y`` (columns ``0`` to ``n - 1``)."""
    s = 0.0
    for j in range(n):
        j2 = j + 1 if j + 1 < n else 0
        dx = rows[x, j2] - rows[x, j]
        dy = rows[y, j2] - rows[y, j]
        s += math.sqrt(dx * dx + dy * dy)
    return s


@numba.njit(cache=True)
def thickness(rows: FloatArray, x: int, y: int, n: int) -> float:
    """``2 area / perimeter`` of a convex polygon: its width for a strip, radius for a disc."""
    if n < 3:
        return 0.0
    per = polygon_perimeter(rows, x, y, n)
    if per <= 0.0:
        return 0.0
    return 2.0 * polygon_area(rows, x, y, 0, n) / per


@numba.njit(cache=True)
def is_thin(rows: FloatArray, x: int, y: int, n: int, width: float) -> bool:
    """Whether the convex polygon's :func:`thickness` is at most ``width``.

    Decided without square roots when the polygon is clearly thicker: the
    L1 perimeter bounds the Euclidean one from above.
    """
    if n < 3:
        return True
    twice_area = 0.0
    l1 = 0.0
    x0 = rows[x, 0]
    y0 = rows[y, 0]
    for j in range(n):
        j2 = j + 1 if j + 1 < n else 0
        ax = rows[x, j] - x0
        ay = rows[y, j] - y0
        bx = rows[x, j2] - x0
        by = rows[y, j2] - y0
        twice_area += ax * by - bx * ay
        l1 += abs(bx - ax) + abs(by - ay)
    if twice_area > width * l1:
        return False
    return twice_area <= width * polygon_perimeter(rows, x, y, n)


@numba.njit(cache=True)
def bounding_box(rows: FloatArray, x: int, y: int, n: int) -> tuple[float, float, float, float]:
    """Centre and half sizes of the bounding box of the polygon in rows ``x, y``."""
    x0 = rows[x, 0]
    x1 = x0
    y0 = rows[y, 0]
    y1 = y0
    for i in range(1, n):
        x0 = min(x0, rows[x, i])
        x1 = max(x1, rows[x, i])
        y0 = min(y0, rows[y, i])
        y1 = max(y1, rows[y, i])
    return 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (x1 - x0), 0.5 * (y1 - y0)
