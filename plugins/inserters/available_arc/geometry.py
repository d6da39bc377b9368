"""Compiled convex-polygon geometry of the available-arc inserter.

Particles are kept in a canonical form (:func:`prepare_outlines`): vertices
counter-clockwise, vertex ``j`` the start of edge ``j``, edges ordered by
direction angle starting from the smallest one in ``[0, 2 pi)``. The envelope
``E = P ⊕ (-Q)`` is then a linear merge of the two edge sequences.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

TWO_PI = 2.0 * math.pi
DEGENERATE_EDGE = 1e-12
"""Edges shorter than this fraction of the circumradius take their predecessor's direction."""


@numba.njit(cache=True)
def prepare_outlines(
    vertices: FloatArray, offsets: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Bring every outline to canonical form.

    Returns
    -------
    vx, vy
        Vertices, rotated so that edge 0 has the smallest direction angle.
    ex, ey
        Unit direction of every edge (``v_j -> v_{j+1}``).
    ang
        Direction angle of every edge in ``[0, 2 pi)``, non-decreasing per particle.
    circum
        Circumradius of every particle about its reference point.
    box
        ``(n, 4)`` local bounding box ``xmin, xmax, ymin, ymax``.
    """
    total = vertices.shape[0]
    n = offsets.shape[0] - 1
    vx = np.empty(total)
    vy = np.empty(total)
    ex = np.empty(total)
    ey = np.empty(total)
    ang = np.empty(total)
    circum = np.zeros(n)
    box = np.zeros((n, 4))
    for p in range(n):
        s = offsets[p]
        m = offsets[p + 1] - s
        rad = 0.0
        for j in range(m):
            d = math.hypot(vertices[s + j, 0], vertices[s + j, 1])
            if d > rad:
                rad = d
        circum[p] = rad
        tol = DEGENERATE_EDGE * rad
        raw = np.empty(m)
        good = np.zeros(m, dtype=np.bool_)
        for j in range(m):
            j2 = j + 1 if j + 1 < m else 0
            dx = vertices[s + j2, 0] - vertices[s + j, 0]
            dy = vertices[s + j2, 1] - vertices[s + j, 1]
            a = math.atan2(dy, dx)
            if a < 0.0:
                a += TWO_PI
            if a >= TWO_PI:
                a = 0.0
            raw[j] = a
            good[j] = math.hypot(dx, dy) > tol
        # start at the smallest direction among proper edges
        # start at the proper edge where the cyclic sequence of directions wraps
        # through 0 (its proper predecessor's angle is larger by more than pi).
        # The smallest angle is not enough: collinear edges that rounding puts a
        # hair above it would then be ordered last.
        start = -1
        prev = -1
        for j in range(m - 1, -1, -1):
            if good[j]:
                prev = j
                break
        for j in range(m):
            if not good[j]:
                continue
            if raw[j] < raw[prev] - math.pi:
                start = j
                break
            prev = j
        if start < 0:  # no proper edge, or no wrap found: fall back to the smallest angle
            for j in range(m):
                if good[j] and (start < 0 or raw[j] < raw[start]):
                    start = j
        if start < 0:
            start = 0
        last = raw[start]
        bx0 = np.inf
        bx1 = -np.inf
        by0 = np.inf
        by1 = -np.inf
        for jj in range(m):
            j = (start + jj) % m
            o = s + jj
            vx[o] = vertices[s + j, 0]
            vy[o] = vertices[s + j, 1]
            a = raw[j]
            if not good[j] or a < last:
                a = last  # degenerate edge (or rounding): keep the order
            ang[o] = a
            last = a
            bx0 = min(bx0, vx[o])
            bx1 = max(bx1, vx[o])
            by0 = min(by0, vy[o])
            by1 = max(by1, vy[o])
        box[p, 0] = bx0
        box[p, 1] = bx1
        box[p, 2] = by0
        box[p, 3] = by1
        for jj in range(m):
            ex[s + jj] = math.cos(ang[s + jj])
            ey[s + jj] = math.sin(ang[s + jj])
    return vx, vy, ex, ey, ang, circum, box


@numba.njit(cache=True)
def reflect_outline(
    q: int,
    vx: FloatArray,
    vy: FloatArray,
    ex: FloatArray,
    ey: FloatArray,
    ang: FloatArray,
    offsets: IntArray,
    rx: FloatArray,
    ry: FloatArray,
    rex: FloatArray,
    rey: FloatArray,
    rang: FloatArray,
) -> int:
    """Write ``-Q`` of particle ``q`` in canonical form into the ``r*`` buffers; return its size."""
    s = offsets[q]
    m = offsets[q + 1] - s
    j0 = 0
    for j in range(m):
        if ang[s + j] >= math.pi:
            j0 = j
            break
    below_two_pi = np.nextafter(TWO_PI, 0.0)
    for jj in range(m):
        j = (j0 + jj) % m
        rx[jj] = -vx[s + j]
        ry[jj] = -vy[s + j]
        rex[jj] = -ex[s + j]
        rey[jj] = -ey[s + j]
        a = ang[s + j]
        if a >= math.pi:
            a -= math.pi  # in [0, pi)
        else:
            # in [pi, 2 pi); an angle just below pi must not round up to 2 pi and wrap
            a = min(a + math.pi, below_two_pi)
        rang[jj] = a
    # rounding can leave the first angle just below the last one; keep the order
    for jj in range(1, m):
        if rang[jj] < rang[jj - 1]:
            rang[jj] = rang[jj - 1]
    return m


@numba.njit(cache=True)
def minkowski_envelope(
    p: int,
    vx: FloatArray,
    vy: FloatArray,
    ex: FloatArray,
    ey: FloatArray,
    ang: FloatArray,
    offsets: IntArray,
    rx: FloatArray,
    ry: FloatArray,
    rex: FloatArray,
    rey: FloatArray,
    rang: FloatArray,
    mq: int,
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
) -> int:
    """Merge ``P`` (particle ``p``) with the canonical ``-Q`` buffers into ``E = P ⊕ (-Q)``.

    Vertices (relative to P's reference point) go to ``wx, wy``; the unit
    direction of the edge that starts at each vertex goes to ``wex, wey``.
    Returns the number of vertices, ``m_P + m_Q``.
    """
    # unsigned indices: an index that cannot be negative needs no wraparound test,
    # which otherwise costs each access of this loop a few instructions
    zero = np.uint64(0)
    one = np.uint64(1)
    s = np.uint64(offsets[p])
    mp = np.uint64(offsets[p + 1]) - s
    mqu = np.uint64(mq)
    ip = zero
    iq = zero
    n = zero
    while ip < mp or iq < mqu:
        pi_ = ip if ip < mp else zero
        qi = iq if iq < mqu else zero
        wx[n] = vx[s + pi_] + rx[qi]
        wy[n] = vy[s + pi_] + ry[qi]
        if iq >= mqu or (ip < mp and ang[s + ip] <= rang[iq]):
            wex[n] = ex[s + ip]
            wey[n] = ey[s + ip]
            ip += one
        else:
            wex[n] = rex[iq]
            wey[n] = rey[iq]
            iq += one
        n += one
    return int(n)


@numba.njit(cache=True, error_model="numpy", fastmath={"nnan", "nsz"})
def clip_open_interior(
    ax: float,
    ay: float,
    dx: float,
    dy: float,
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
    n: int,
) -> tuple[float, float]:
    """Parameter interval ``(lo, hi)`` of ``a + s d`` inside the open interior of a convex polygon.

    The polygon is given by its vertices ``w`` and unit edge directions ``we``
    (counter-clockwise). The interval is empty when ``lo >= hi`` (its ends are
    then of no use). Every side is clipped, with no early exit and no branch on
    the side's direction, so that the loop compiles to vector instructions: a
    non-empty interval is the largest lower and the smallest upper end, as a
    clip that stops at the first empty one gives. The compiler may assume no
    NaN (the inputs are finite) and ignore the sign of a zero, which only an
    end at exactly 0 can carry and which no comparison of the callers tells
    apart; no product is fused and no sum reordered.
    """
    lo = -np.inf
    hi = np.inf
    shut = False
    for j in range(n):
        # cross(e, a + s d - w) > 0  <=>  f0 + s f1 > 0
        f0 = wex[j] * (ay - wy[j]) - wey[j] * (ax - wx[j])
        f1 = wex[j] * dy - wey[j] * dx
        up = f1 > 0.0
        down = f1 < 0.0
        t = -f0 / (f1 if up or down else 1.0)
        lo = max(lo, t if up else -np.inf)
        hi = min(hi, t if down else np.inf)
        shut |= not up and not down and f0 <= 0.0
    if shut:
        return 1.0, 0.0
    return lo, hi


@numba.njit(cache=True)
def inside_open(
    px: float,
    py: float,
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
    n: int,
) -> bool:
    """Return whether point ``p`` lies in the open interior of a convex polygon.

    Every side is tested, with no early exit: the loop then compiles to vector
    instructions, and most points tested lie inside, where every side is needed.
    """
    inside = True
    for j in range(n):
        inside &= not (wex[j] * (py - wy[j]) - wey[j] * (px - wx[j]) <= 0.0)
    return inside


@numba.njit(cache=True)
def clip_closed_box(
    ax: float, ay: float, dx: float, dy: float, x0: float, x1: float, y0: float, y1: float
) -> tuple[float, float]:
    """Parameter interval ``[lo, hi]`` of ``a + s d`` inside the closed box (empty if lo > hi)."""
    if x0 > x1 or y0 > y1:
        return 1.0, 0.0  # an empty box
    lo = -np.inf
    hi = np.inf
    if dx == 0.0:
        if ax < x0 or ax > x1:
            return 1.0, 0.0
    else:
        t0 = (x0 - ax) / dx
        t1 = (x1 - ax) / dx
        if t0 > t1:
            t0, t1 = t1, t0
        lo = max(lo, t0)
        hi = min(hi, t1)
    if dy == 0.0:
        if ay < y0 or ay > y1:
            return 1.0, 0.0
    else:
        t0 = (y0 - ay) / dy
        t1 = (y1 - ay) / dy
        if t0 > t1:
            t0, t1 = t1, t0
        lo = max(lo, t0)
        hi = min(hi, t1)
    return lo, hi


@numba.njit(cache=True)
def segment_point_distance(
    ax: float, ay: float, bx: float, by: float, px: float, py: float
) -> float:
    """Distance from point ``p`` to the segment ``a b``."""
    dx = bx - ax
    dy = by - ay
    ll = dx * dx + dy * dy
    t = 0.0
    if ll > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / ll
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


@numba.njit(cache=True)
def angle_slot(va: FloatArray, n: int, angle: float) -> tuple[float, int]:
    """Find where polar ``angle`` falls among the ``n`` slots ``va[j] .. va[j + 1]`` of a turn.

    ``va`` holds ``n + 1`` ascending angles, the last one turn after the first.
    Returns ``angle`` moved by whole turns to ``[va[0], va[n])`` and the slot
    ``j`` that holds it (the last slot for an angle past every bound).
    """
    period = va[n] - va[0]
    a = angle - va[0]
    a = a - period * math.floor(a / period)
    a += va[0]
    j = 0
    while j < n - 1 and va[j + 1] < a:
        j += 1
    return a, j


@numba.njit(cache=True)
def close_arcs(arcs: FloatArray, na: int, wraps: bool, period: float) -> FloatArray:
    """Finish the ``na`` arcs collected around an envelope.

    When ``wraps`` (the first arc starts at the envelope's start and the last
    one ends there), the last arc is joined to the first, which then starts
    ``period`` below. Arcs of zero angular length (single free points) are
    dropped.
    """
    if na >= 2 and wraps:
        arcs[0, 0] = arcs[na - 1, 0] - period
        na -= 1
    out = 0
    for a in range(na):
        if arcs[a, 1] > arcs[a, 0]:
            arcs[out, 0] = arcs[a, 0]
            arcs[out, 1] = arcs[a, 1]
            out += 1
    return arcs[:out]
