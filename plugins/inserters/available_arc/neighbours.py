"""Per-particle neighbour lists: the possible interferers of a candidate, nearest first.

A buried candidate is analysed again and again (once for every new record-low
radius), and each analysis looks up the particles near it. The lists keep, for
every placed particle ``q``, the placed particles ``o`` with

    |c_q - c_o| < reach_q + reach_o + 2 cap,

sorted by ``gap = |c_q - c_o| - reach_o`` and stored with their offsets
``c_o - c_q``. Every interferer of candidate ``q`` for a new particle of reach
at most ``cap`` is in the list, before the first entry whose gap exceeds
``reach_q + 2 reach_new``, so a query reads one short contiguous block instead
of the grid cells. A list that would outgrow its capacity is dropped
(``count = -1``) and its particle goes back to the grid.

The lists live in a pool of rows: ``row[q]`` is the row of ``q``'s list (-1:
none), and the free rows are a stack (``free[:top]``). A particle placed when
the pool is empty gets no list and uses the grid; a candidate that can never
be analysed again (one the sweep has left behind) gives its row back with
:func:`release_row`, so the pool holds only the lists still in use.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.inserters.available_arc.grid import cell_range

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

GAP_SLACK = 1e-9
"""Relative slack of the list cut-offs, far above the rounding of the gaps."""
IMAGE_QUERIES = 9
"""Stamp values one registration in a periodic domain may take (a query per image)."""


class ListPool(NamedTuple):
    """The pool of neighbour lists: per row, the entries sorted by gap, and the free rows."""

    o: NDArray[np.int32]
    gap: FloatArray
    dx: FloatArray
    dy: FloatArray
    n: IntArray
    """Entries per row; -1 for a dropped list."""
    img: NDArray[np.int8]
    """Per entry in a periodic domain: which image of the neighbour it is (:func:`image_code`)."""
    row: IntArray
    """Per particle: the row of its list, -1 for none."""
    free: IntArray
    """The stack of free rows (``free[:top]``)."""


class GridView(NamedTuple):
    """The neighbour grid as a query reads it (see :mod:`.grid`)."""

    par: FloatArray
    """Origin ``x0, y0`` and the cell size."""
    dim: IntArray
    """Cells along x and y."""
    head: IntArray
    nxt: IntArray
    item: IntArray
    stamp: IntArray
    """Per particle: the last query that listed it."""


@numba.njit(cache=True, inline="always")
def image_shifts(x: float, span: float, lo: float, hi: float) -> tuple[int, float, float]:
    """Shifts of the image queries along one periodic axis ``[lo, hi)`` about ``x``.

    Returns ``(n, s1, s2)``: ``n`` queries, the first unshifted, the next
    ``s1`` and ``s2`` (a period up, down) when ``x`` lies within ``span`` of
    the low or the high side. The analysis and the neighbour lists choose
    their images by this one rule.
    """
    period = hi - lo
    n = 1
    s1 = s2 = 0.0
    if x - span < lo:
        s1 = period
        n += 1
    if x + span > hi:
        if n == 1:
            s1 = -period
        else:
            s2 = -period
        n += 1
    return n, s1, s2


@numba.njit(cache=True, inline="always")
def image_shift(q: int, s1: float, s2: float) -> float:
    """Shift of image query ``q`` along one axis (0: none; 1, 2: ``s1``, ``s2``)."""
    return 0.0 if q == 0 else (s1 if q == 1 else s2)


@numba.njit(cache=True, inline="always")
def _axis_query(a: int, n: int, s1: float, s2: float) -> int:
    """Query index along one axis of a shift of code ``a`` (0 none, 1 up, 2 down); -1: none."""
    if a == 0:
        return 0
    up = a == 1
    if n >= 2 and (s1 > 0.0) == up:
        return 1
    if n == 3 and (s2 > 0.0) == up:
        return 2
    return -1


@numba.njit(cache=True, inline="always")
def image_query(
    code: int, nsx: int, sx1: float, sx2: float, nsy: int, sy1: float, sy2: float
) -> int:
    """Index of the image query that looks for the image of ``code``; -1 when none does.

    The queries are those :func:`image_shifts` chose, numbered ``qx + nsx * qy``.
    """
    qx = _axis_query(code % 3, nsx, sx1, sx2)
    qy = _axis_query(code // 3, nsy, sy1, sy2)
    if qx < 0 or qy < 0:
        return -1
    return qx + nsx * qy


@numba.njit(cache=True)
def image_code(sx: float, sy: float) -> int:
    """Code of the periodic image shifted by ``(sx, sy)``: per axis 0 none, 1 up, 2 down."""
    ax = 0 if sx == 0.0 else (1 if sx > 0.0 else 2)
    ay = 0 if sy == 0.0 else (1 if sy > 0.0 else 2)
    return ax + 3 * ay


@numba.njit(cache=True)
def _add_entry(
    q: int,
    o: int,
    gap: float,
    dx: float,
    dy: float,
    code: int,
    nb_o: NDArray[np.int32],
    nb_gap: FloatArray,
    nb_dx: FloatArray,
    nb_dy: FloatArray,
    nb_n: IntArray,
    img: NDArray[np.int8],
) -> None:
    """Insert ``o`` into list row ``q`` at its place by gap; drop the list when full."""
    cnt = nb_n[q]
    if cnt < 0:
        return
    if cnt == nb_o.shape[1]:
        nb_n[q] = -1
        return
    e = cnt
    while e > 0 and nb_gap[q, e - 1] > gap:
        nb_o[q, e] = nb_o[q, e - 1]
        nb_gap[q, e] = nb_gap[q, e - 1]
        nb_dx[q, e] = nb_dx[q, e - 1]
        nb_dy[q, e] = nb_dy[q, e - 1]
        img[q, e] = img[q, e - 1]
        e -= 1
    nb_o[q, e] = o
    nb_gap[q, e] = gap
    nb_dx[q, e] = dx
    nb_dy[q, e] = dy
    img[q, e] = code
    nb_n[q] = cnt + 1


@numba.njit(cache=True)
def register_neighbours(
    p: int,
    token: int,
    top: int,
    cx: FloatArray,
    cy: FloatArray,
    reach: FloatArray,
    grid: GridView,
    lists: ListPool,
    cap: float,
    maxreach: float,
    periodic: bool = False,
    bounds: FloatArray | None = None,
    shut: FloatArray | None = None,
    floor: float = 0.0,
) -> int:
    """Start ``p``'s list and add ``p`` to its neighbours' lists; return the new stack top.

    Call after ``p`` is placed and before it is registered in the grid;
    ``token`` must be a fresh stamp value (in a periodic domain, the
    :data:`IMAGE_QUERIES` values from ``token`` on). ``p`` takes the row on
    top of the free stack ``lists.free[:top]``, or none when the stack is empty.
    The lists cover new particles of reach up to ``cap``; ``maxreach`` is the
    largest reach in the grid.

    In a periodic domain (``bounds``: xmin, xmax, ymin, ymax) the grid is also
    searched about ``p``'s images one period away, and each entry records its
    image (``img``) and its offset computed as the analysis's grid search
    computes it from that image, so that both find the same interferers at the
    same offsets.

    A neighbour ``o`` with ``shut[o] <= floor`` (a disk bound shuts it for every
    particle of the scene, ``floor`` being the smallest radius: it is never
    analysed again) gives its row back instead of taking ``p``.
    """
    gpar, gdim, head, nxt, item, stamp = grid
    nb_o, nb_gap, nb_dx, nb_dy, nb_n, img, row, free = lists
    x = cx[p]
    y = cy[p]
    rp = reach[p]
    rp_row = -1
    if top > 0:
        top -= 1
        rp_row = free[top]
        nb_n[rp_row] = 0
    row[p] = rp_row
    stamp[p] = token
    # o qualifies when |c_p - c_o| < (rp + ro + 2 cap)(1 + slack): its grid disk
    # (radius ro <= maxreach) then reaches into this box
    half = (rp + 2.0 * cap) + (rp + maxreach + 2.0 * cap) * 2.0 * GAP_SLACK
    nsx = 1
    nsy = 1
    sx1 = sx2 = sy1 = sy2 = 0.0
    if periodic and bounds is not None:
        span = half + maxreach
        nsx, sx1, sx2 = image_shifts(x, span, bounds[0], bounds[1])
        nsy, sy1, sy2 = image_shifts(y, span, bounds[2], bounds[3])
    nx = gdim[0]
    for qs in range(nsx * nsy):
        qx = qs % nsx
        qy = qs // nsx
        ix = image_shift(qx, sx1, sx2)
        iy = image_shift(qy, sy1, sy2)
        tq = token + qs
        # the image of p this query is about; from o, p's entry is o's image -i
        qcx = x
        qcy = y
        if qs > 0:
            qcx += ix
            qcy += iy
            stamp[p] = tq
        code = image_code(ix, iy)
        back = image_code(-ix, -iy)
        ia, ib = cell_range(qcx - half, qcx + half, gpar[0], gpar[2], gdim[0])
        ja, jb = cell_range(qcy - half, qcy + half, gpar[1], gpar[2], gdim[1])
        for gj in range(ja, jb + 1):
            for gi in range(ia, ib + 1):
                e = head[gj * nx + gi]
                while e >= 0:
                    o = item[e]
                    e = nxt[e]
                    if stamp[o] == tq:
                        continue
                    stamp[o] = tq
                    dx = cx[o] - qcx
                    dy = cy[o] - qcy
                    d = math.sqrt(dx * dx + dy * dy)
                    ro = reach[o]
                    lim = (rp + ro + 2.0 * cap) * (1.0 + GAP_SLACK)
                    # p's entry in o's list: the offset the grid search about o's
                    # image -i computes, which can round apart from -(dx, dy) far
                    # from the origin; each list is tested on its own distance
                    if qs == 0:
                        bx = x - cx[o]
                        by = y - cy[o]
                        bd = d
                    else:
                        ox_ = cx[o]
                        oy_ = cy[o]
                        ox_ += -ix
                        oy_ += -iy
                        bx = x - ox_
                        by = y - oy_
                        bd = math.sqrt(bx * bx + by * by)
                    if rp_row >= 0 and d < lim:
                        _add_entry(
                            rp_row, o, d - ro, dx, dy, code, nb_o, nb_gap, nb_dx, nb_dy, nb_n, img
                        )
                    ro_row = row[o]
                    if ro_row >= 0 and shut is not None and shut[o] <= floor:
                        top = release_row(o, row, free, top)
                    elif ro_row >= 0 and bd < lim:
                        _add_entry(
                            ro_row, p, bd - rp, bx, by, back, nb_o, nb_gap, nb_dx, nb_dy, nb_n, img
                        )
        if qs > 0 and rp_row >= 0:
            # p's own image: p is not in the grid yet
            dx = x - qcx
            dy = y - qcy
            d = math.sqrt(dx * dx + dy * dy)
            if d < (rp + rp + 2.0 * cap) * (1.0 + GAP_SLACK):
                _add_entry(rp_row, p, d - rp, dx, dy, code, nb_o, nb_gap, nb_dx, nb_dy, nb_n, img)
    return top


@numba.njit(cache=True)
def release_row(q: int, row: IntArray, free: IntArray, top: int) -> int:
    """Give ``q``'s list row back to the free stack; return the new stack top."""
    r = row[q]
    if r < 0:
        return top
    row[q] = -1
    free[top] = r
    return top + 1


def list_capacity(n: int, enabled: bool, capacity: int) -> tuple[int, int]:
    """Shape ``(rows, columns)`` of the list arrays (one dummy entry when disabled)."""
    return (n, capacity) if enabled and n > 0 else (1, 1)


def free_stack(rows: int, enabled: bool) -> IntArray:
    """Free-row stack of a new pool: row 0 on top, so rows are taken in order."""
    return np.arange(rows - 1, -1, -1, dtype=np.int64) if enabled else np.zeros(1, np.int64)
