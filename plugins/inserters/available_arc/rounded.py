"""Compiled available-arc analysis for rounded particles (disks and rounded polygons).

A rounded particle is a convex core outline (a single vertex for a disk)
grown by a disk of radius ``rho``. The envelope of two of them is the
Minkowski sum of the cores (the merge of :mod:`geometry`) grown by the sum of
the radii, so its boundary alternates circular arcs (about the core's
vertices, between the normals of the adjacent edges) and straight edges (the
core's edges moved out by the radius). Arcs wider than a quarter turn are
split, so that every piece subtends less than pi as seen from the candidate's
centre (which lies in the envelope's core).

Every piece is parametrised by ``u`` in ``[0, 1]``. The points where a piece
crosses the boundary of an interferer's envelope or a wall split it; the
middle of each sub-interval decides whether it is covered (inside the open
interior of an interferer's envelope, or outside the walls). Touching is
free, as for polygons.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.walls import WALL_BOX, WALL_CIRCLE, WALL_HALFPLANES
from regopack.plugins.inserters.available_arc.disk_bound import sort_covers
from regopack.plugins.inserters.available_arc.geometry import angle_slot, close_arcs, inside_open

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

QUARTER = 0.5 * math.pi
SLACK = 1e-9
"""Relative widening of the parameter ranges in which crossings are accepted."""


@numba.njit(cache=True)
def envelope_pieces(
    wx: FloatArray, wy: FloatArray, wex: FloatArray, wey: FloatArray, n: int, rho: float
) -> FloatArray:
    """Boundary pieces of the core polygon ``w`` grown by ``rho``, counter-clockwise.

    Returns ``(k, 6)`` rows ``[kind, a, b, c, d, e]``: a segment (kind 0)
    from ``(a, b)`` to ``(c, d)``; an arc (kind 1) about ``(a, b)`` of radius
    ``c`` from angle ``d`` to angle ``e`` (``d <= e``). Pieces of zero length
    are left out. With ``rho = 0`` only the core's edges remain.
    """
    out = np.empty((5 * n + 4, 6))
    k = 0
    # outward normal angle of edge j: direction angle minus a quarter turn
    prev = math.atan2(wey[n - 1], wex[n - 1]) - QUARTER
    for j in range(n):
        beta = math.atan2(wey[j], wex[j]) - QUARTER
        if rho > 0.0:
            span = beta - prev
            span -= 2.0 * math.pi * math.floor(span / (2.0 * math.pi))
            if span > 2.0 * math.pi - 1e-9:
                span = 0.0  # parallel edges whose angles round the wrong way
            if n == 1 or (span == 0.0 and _all_same(wx, wy, n)):
                span = 2.0 * math.pi  # a point core: the whole circle
            if span > 0.0:
                parts = math.ceil(span / QUARTER)
                step = span / parts
                for p in range(parts):
                    out[k, 0] = 1.0
                    out[k, 1] = wx[j]
                    out[k, 2] = wy[j]
                    out[k, 3] = rho
                    out[k, 4] = prev + p * step
                    out[k, 5] = prev + (p + 1) * step if p + 1 < parts else prev + span
                    k += 1
        j2 = j + 1 if j + 1 < n else 0
        nx = math.cos(beta)
        ny = math.sin(beta)
        ax = wx[j] + rho * nx
        ay = wy[j] + rho * ny
        bx = wx[j2] + rho * nx
        by = wy[j2] + rho * ny
        if ax != bx or ay != by:
            out[k, 0] = 0.0
            out[k, 1] = ax
            out[k, 2] = ay
            out[k, 3] = bx
            out[k, 4] = by
            out[k, 5] = 0.0
            k += 1
        prev = beta
    return out[:k]


@numba.njit(cache=True)
def _all_same(wx: FloatArray, wy: FloatArray, n: int) -> bool:
    for j in range(1, n):
        if wx[j] != wx[0] or wy[j] != wy[0]:
            return False
    return True


@numba.njit(cache=True)
def piece_point(piece: FloatArray, u: float) -> tuple[float, float]:
    """Point at parameter ``u`` of a piece."""
    if piece[0] == 0.0:
        return piece[1] + u * (piece[3] - piece[1]), piece[2] + u * (piece[4] - piece[2])
    phi = piece[4] + u * (piece[5] - piece[4])
    return piece[1] + piece[3] * math.cos(phi), piece[2] + piece[3] * math.sin(phi)


@numba.njit(cache=True)
def _on_arc(phi: float, lo: float, hi: float) -> float:
    """Parameter of angle ``phi`` on the arc ``[lo, hi]``, or -1 when it is off the arc."""
    span = hi - lo
    d = phi - lo
    d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi))
    slack = SLACK * max(span, 1e-300) + 1e-15
    if d > span + slack:
        if d > 2.0 * math.pi - slack:  # just below lo
            return 0.0
        return -1.0
    return min(d / span, 1.0) if span > 0.0 else 0.0


@numba.njit(cache=True)
def _line_circle(
    ax: float, ay: float, dx: float, dy: float, cx: float, cy: float, r: float
) -> tuple[int, float, float]:
    """Parameters ``t`` where ``a + t d`` meets the circle; their count first."""
    aa = dx * dx + dy * dy
    if aa == 0.0:
        return 0, 0.0, 0.0
    px = ax - cx
    py = ay - cy
    b = px * dx + py * dy
    c = px * px + py * py - r * r
    disc = b * b - aa * c
    if disc < 0.0:
        return 0, 0.0, 0.0
    root = math.sqrt(disc)
    q = -(b + root) if b >= 0.0 else -(b - root)
    if q == 0.0:
        return 1, 0.0, 0.0
    return 2, q / aa, c / q


@numba.njit(cache=True)
def piece_bound(piece: FloatArray) -> tuple[float, float, float]:
    """Centre and radius of a disk that contains the piece.

    A segment: its midpoint and half length. An arc (at most a quarter turn):
    the midpoint of its chord, with half the chord plus the arc's height.
    """
    xa, ya = piece_point(piece, 0.0)
    xb, yb = piece_point(piece, 1.0)
    mx = 0.5 * (xa + xb)
    my = 0.5 * (ya + yb)
    half = 0.5 * math.hypot(xb - xa, yb - ya)
    if piece[0] == 0.0:
        return mx, my, half
    height = piece[3] - math.hypot(mx - piece[1], my - piece[2])
    return mx, my, half + max(height, 0.0)


@numba.njit(cache=True)
def _as_line(other: FloatArray) -> tuple[float, float, float, float]:
    """Start point and direction of a segment (kind 0) or a line (kind 2)."""
    if other[0] == 0.0:
        return other[1], other[2], other[3] - other[1], other[4] - other[2]
    return other[1], other[2], other[3], other[4]


@numba.njit(cache=True)
def crossings(piece: FloatArray, other: FloatArray, out: FloatArray, k: int) -> int:
    """Append to ``out[k:]`` the parameters on ``piece`` where it meets ``other``.

    ``other`` is a piece (segment, arc) or a line (kind 2: point ``(a, b)``,
    direction ``(c, d)``) or a full circle (kind 3: centre ``(a, b)``, radius
    ``c``). Parameters strictly between 0 and 1 are kept; returns the new count.
    """
    lo = SLACK
    hi = 1.0 - SLACK
    if piece[0] == 0.0:
        ax = piece[1]
        ay = piece[2]
        dx = piece[3] - ax
        dy = piece[4] - ay
        if other[0] == 0.0 or other[0] == 2.0:
            ox, oy, fx, fy = _as_line(other)
            det = dx * fy - dy * fx
            if det == 0.0:
                return k
            gx = ox - ax
            gy = oy - ay
            t = (gx * fy - gy * fx) / det
            s = (gx * dy - gy * dx) / det
            if other[0] == 0.0 and (s < -SLACK or s > 1.0 + SLACK):
                return k
            if lo < t < hi:
                out[k] = t
                k += 1
            return k
        cnt, t1, t2 = _line_circle(ax, ay, dx, dy, other[1], other[2], other[3])
        for c in range(cnt):
            t = t1 if c == 0 else t2
            if not lo < t < hi:
                continue
            if other[0] == 1.0:
                px = ax + t * dx - other[1]
                py = ay + t * dy - other[2]
                if _on_arc(math.atan2(py, px), other[4], other[5]) < 0.0:
                    continue
            out[k] = t
            k += 1
        return k
    # piece is an arc about (cx, cy) of radius r
    cx = piece[1]
    cy = piece[2]
    r = piece[3]
    if other[0] == 0.0 or other[0] == 2.0:
        ox, oy, fx, fy = _as_line(other)
        cnt, s1, s2 = _line_circle(ox, oy, fx, fy, cx, cy, r)
        for c in range(cnt):
            s = s1 if c == 0 else s2
            if other[0] == 0.0 and (s < -SLACK or s > 1.0 + SLACK):
                continue
            u = _on_arc(math.atan2(oy + s * fy - cy, ox + s * fx - cx), piece[4], piece[5])
            if lo < u < hi:
                out[k] = u
                k += 1
        return k
    # circle-circle
    ox = other[1] - cx
    oy = other[2] - cy
    r2 = other[3]
    d = math.hypot(ox, oy)
    if d == 0.0 or d > r + r2 or d < abs(r - r2):
        return k
    a = (r * r - r2 * r2 + d * d) / (2.0 * d)
    h2 = r * r - a * a
    h = math.sqrt(h2) if h2 > 0.0 else 0.0
    mx = a * ox / d
    my = a * oy / d
    for c in range(2):
        sg = 1.0 if c == 0 else -1.0
        px = mx - sg * h * oy / d
        py = my + sg * h * ox / d
        if other[0] == 1.0:
            if _on_arc(math.atan2(py + cy - other[2], px + cx - other[1]), other[4], other[5]) < 0:
                continue
        u = _on_arc(math.atan2(py, px), piece[4], piece[5])
        if lo < u < hi:
            out[k] = u
            k += 1
    return k


@numba.njit(cache=True)
def inside_rounded(
    px: float,
    py: float,
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
    n: int,
    rho: float,
) -> bool:
    """Return whether ``p`` lies in the open interior of core polygon ``w`` grown by ``rho``."""
    if inside_open(px, py, wx, wy, wex, wey, n):
        return True
    if rho <= 0.0:
        return False
    r2 = rho * rho
    for j in range(n):
        j2 = j + 1 if j + 1 < n else 0
        ax = wx[j]
        ay = wy[j]
        dx = wx[j2] - ax
        dy = wy[j2] - ay
        ll = dx * dx + dy * dy
        t = 0.0
        if ll > 0.0:
            t = ((px - ax) * dx + (py - ay) * dy) / ll
            t = min(max(t, 0.0), 1.0)
        ex = ax + t * dx - px
        ey = ay + t * dy - py
        if ex * ex + ey * ey < r2:
            return True
    return False


@numba.njit(cache=True)
def piece_angles(pieces: FloatArray, out: FloatArray) -> None:
    """Unwrapped polar angle of the start of every piece (``out[k]`` closes the loop).

    Every piece subtends less than pi from the origin, which lies in the core.
    """
    k = pieces.shape[0]
    x0, y0 = piece_point(pieces[0], 0.0)
    out[0] = math.atan2(y0, x0)
    for p in range(k):
        xa, ya = piece_point(pieces[p], 0.0)
        q = p + 1 if p + 1 < k else 0
        xb, yb = piece_point(pieces[q], 0.0)
        out[p + 1] = out[p] + math.atan2(xa * yb - ya * xb, xa * xb + ya * yb)


@numba.njit(cache=True)
def angle_on_piece(pieces: FloatArray, va: FloatArray, p: int, u: float) -> float:
    """Polar angle of the point at parameter ``u`` of piece ``p``."""
    if u <= 0.0:
        return va[p]
    if u >= 1.0:
        return va[p + 1]
    xa, ya = piece_point(pieces[p], 0.0)
    x, y = piece_point(pieces[p], u)
    return va[p] + math.atan2(xa * y - ya * x, xa * x + ya * y)


@numba.njit(cache=True)
def ray_hit(piece: FloatArray, angle: float) -> tuple[float, float]:
    """Where the ray from the origin at polar ``angle`` meets the piece (its nearest point)."""
    ux = math.cos(angle)
    uy = math.sin(angle)
    if piece[0] == 0.0:
        ax = piece[1]
        ay = piece[2]
        ex = piece[3] - ax
        ey = piece[4] - ay
        den = ux * ey - uy * ex
        t = 0.0
        if den != 0.0:
            t = (ax * uy - ay * ux) / den
        t = min(max(t, 0.0), 1.0)
        return ax + t * ex, ay + t * ey
    cnt, t1, t2 = _line_circle(0.0, 0.0, ux, uy, piece[1], piece[2], piece[3])
    if cnt == 0:  # rounding at a tangent ray: the foot of the perpendicular
        t = ux * piece[1] + uy * piece[2]
        return t * ux, t * uy
    t = max(t1, t2)
    px = t * ux
    py = t * uy
    u = _on_arc(math.atan2(py - piece[2], px - piece[1]), piece[4], piece[5])
    if u < 0.0:  # off the arc by rounding: the nearer end
        xa, ya = piece_point(piece, 0.0)
        xb, yb = piece_point(piece, 1.0)
        if (xa - px) ** 2 + (ya - py) ** 2 <= (xb - px) ** 2 + (yb - py) ** 2:
            return xa, ya
        return xb, yb
    return px, py


class RoundedWalls(NamedTuple):
    """The walls as a rounded analysis tests a centre against them (see :func:`_fits`)."""

    mode: int
    walls: FloatArray
    box: FloatArray
    """The closed box of centres (absolute), for a walled rectangle."""
    woff: FloatArray
    """The half-planes' offsets for the new particle, for a polygon."""
    qx: FloatArray
    """The new particle's reflected core (``mq`` vertices), for a circle."""
    qy: FloatArray
    mq: int
    inner: float
    """The circular wall's radius less the new particle's rounding."""


class RoundedInterferers(NamedTuple):
    """The interferers of a rounded analysis, relative to the candidate's centre ``pc``.

    Interferer ``f < nf`` has its core in row ``slot[f]`` of ``o*`` (``on`` vertices,
    relative to its own centre, which is at ``(odx[f], ody[f])`` from ``pc``; ``orad``:
    the core's radius about that centre) and rounding ``orho[f]``.
    """

    nf: int
    slot: IntArray
    odx: FloatArray
    ody: FloatArray
    ox: FloatArray
    oy: FloatArray
    oex: FloatArray
    oey: FloatArray
    on: IntArray
    orad: FloatArray
    orho: FloatArray


@numba.njit(cache=True)
def _fits(x: float, y: float, wl: RoundedWalls) -> bool:
    """Whether a centre at ``(x, y)`` (absolute) keeps the new particle inside the walls."""
    mode, walls, box, woff, qx, qy, mq, inner = wl
    if mode == WALL_BOX:
        return box[0] <= x <= box[1] and box[2] <= y <= box[3]
    if mode == WALL_HALFPLANES:
        for e in range(walls.shape[0]):
            if walls[e, 0] * x + walls[e, 1] * y > woff[e]:
                return False
        return True
    if mode == WALL_CIRCLE:
        for j in range(mq):
            # the reflected core holds -v: the vertex is at x - q
            if math.hypot(x - qx[j] - walls[0, 0], y - qy[j] - walls[0, 1]) > inner:
                return False
        return True
    return True


@numba.njit(cache=True)
def _wall_lines(wl: RoundedWalls, pcx: float, pcy: float) -> FloatArray:
    """Boundaries of the admissible centres relative to ``pc``: lines (kind 2), circles (3)."""
    mode, walls, box, woff, qx, qy, mq, inner = wl
    if mode == WALL_BOX:
        out = np.zeros((4, 6))
        for e in range(4):
            out[e, 0] = 2.0
        out[0, 1] = box[0] - pcx
        out[0, 4] = 1.0
        out[1, 1] = box[1] - pcx
        out[1, 4] = 1.0
        out[2, 2] = box[2] - pcy
        out[2, 3] = 1.0
        out[3, 2] = box[3] - pcy
        out[3, 3] = 1.0
        return out
    if mode == WALL_HALFPLANES:
        k = walls.shape[0]
        out = np.zeros((k, 6))
        for e in range(k):
            nx = walls[e, 0]
            ny = walls[e, 1]
            off = woff[e] - (nx * pcx + ny * pcy)
            out[e, 0] = 2.0
            out[e, 1] = nx * off
            out[e, 2] = ny * off
            out[e, 3] = -ny
            out[e, 4] = nx
        return out
    if mode == WALL_CIRCLE:
        out = np.zeros((mq, 6))
        for j in range(mq):
            out[j, 0] = 3.0
            out[j, 1] = walls[0, 0] + qx[j] - pcx
            out[j, 2] = walls[0, 1] + qy[j] - pcy
            out[j, 3] = inner
        return out
    return np.zeros((0, 6))


@numba.njit(cache=True)
def rounded_arcs(
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
    n: int,
    rho: float,
    pcx: float,
    pcy: float,
    others: RoundedInterferers,
    wl: RoundedWalls,
) -> FloatArray:
    """Available arcs (polar angles about the candidate) of a rounded envelope.

    ``w`` (``n`` vertices) is the envelope's core relative to the candidate
    centre ``pc`` and ``rho`` its rounding; ``others`` are the interferers and
    ``wl`` the walls. Same conventions as ``kernel.analyze_candidate``.
    """
    nf, slot, odx, ody, ox, oy, oex, oey, on, orad, orho = others
    if _all_same(wx, wy, n) and wx[0] == 0.0 and wy[0] == 0.0:
        disks = True
        for f in range(nf):
            sl = slot[f]
            if not _all_same(ox[sl], oy[sl], on[sl]):
                disks = False
                break
        if disks:
            ocx = np.empty(nf)
            ocy = np.empty(nf)
            for f in range(nf):
                ocx[f] = odx[f] + ox[slot[f], 0]
                ocy[f] = ody[f] + oy[slot[f], 0]
            return disk_arcs(
                rho, pcx, pcy, nf, ocx, ocy, orho,
                wl.mode, wl.walls, wl.box, wl.woff, wl.qx, wl.qy, wl.inner,
            )  # fmt: skip
    pieces = envelope_pieces(wx, wy, wex, wey, n, rho)
    npc = pieces.shape[0]
    va = np.empty(npc + 1)
    piece_angles(pieces, va)
    # interferer pieces, relative to pc
    start = np.zeros(nf + 1, dtype=np.int64)
    total = 0
    for f in range(nf):
        total += 5 * on[slot[f]] + 4
    opieces = np.empty((total, 6))
    tx = np.empty(on.max() if nf > 0 else 1)
    ty = np.empty(tx.shape[0])
    for f in range(nf):
        sl = slot[f]
        for j in range(on[sl]):
            tx[j] = ox[sl, j] + odx[f]
            ty[j] = oy[sl, j] + ody[f]
        got = envelope_pieces(tx, ty, oex[sl], oey[sl], on[sl], orho[f])
        opieces[start[f] : start[f] + got.shape[0]] = got
        start[f + 1] = start[f] + got.shape[0]
    obound = np.empty((start[nf], 3))
    for q in range(start[nf]):
        obound[q, 0], obound[q, 1], obound[q, 2] = piece_bound(opieces[q])
    lines = _wall_lines(wl, pcx, pcy)
    cuts = np.empty(2 * (total + lines.shape[0]) + 2)
    arcs = np.empty((2 * npc + 2 * (total + lines.shape[0]) + 2, 2))
    na = 0
    joined = -1  # the last arc ends at the end of this piece
    first_at_zero = False
    for p in range(npc):
        pc_ = pieces[p]
        bx, by, br = piece_bound(pc_)
        nc = 0
        cuts[nc] = 0.0
        nc += 1
        cuts[nc] = 1.0
        nc += 1
        for f in range(nf):
            reach = orad[slot[f]] + orho[f] + br
            if (odx[f] - bx) ** 2 + (ody[f] - by) ** 2 >= reach * reach:
                continue
            for q in range(start[f], start[f + 1]):
                both = (br + obound[q, 2]) * (1.0 + 1e-9)
                if (obound[q, 0] - bx) ** 2 + (obound[q, 1] - by) ** 2 > both * both:
                    continue  # the two pieces cannot meet
                nc = crossings(pc_, opieces[q], cuts, nc)
        for q in range(lines.shape[0]):
            nc = crossings(pc_, lines[q], cuts, nc)
        cuts[:nc].sort()
        for c in range(nc - 1):
            ua = cuts[c]
            ub = cuts[c + 1]
            if ub <= ua:
                continue
            mx, my = piece_point(pc_, 0.5 * (ua + ub))
            free = _fits(mx + pcx, my + pcy, wl)
            if free:
                for f in range(nf):
                    sl = slot[f]
                    gx = mx - odx[f]
                    gy = my - ody[f]
                    reach = orad[sl] + orho[f]
                    if gx * gx + gy * gy >= reach * reach:
                        continue
                    if inside_rounded(gx, gy, ox[sl], oy[sl], oex[sl], oey[sl], on[sl], orho[f]):
                        free = False
                        break
            if not free:
                continue
            a1 = angle_on_piece(pieces, va, p, ub)
            if ua == 0.0 and joined == p and na > 0:
                arcs[na - 1, 1] = a1
            else:
                if ua == 0.0 and p == 0:
                    first_at_zero = True
                arcs[na, 0] = angle_on_piece(pieces, va, p, ua)
                arcs[na, 1] = a1
                na += 1
            joined = p + 1 if ub == 1.0 else -1
    return close_arcs(arcs, na, first_at_zero and joined == npc, va[npc] - va[0])


@numba.njit(cache=True)
def _cover(lo: FloatArray, hi: FloatArray, k: int, centre: float, half: float) -> int:
    """Append the open interval ``(centre - half, centre + half)`` of angles; return the count.

    ``half >= pi`` covers the whole circle (one interval of length 2 pi).
    """
    if half <= 0.0:
        return k
    if half >= math.pi:
        lo[k] = 0.0
        hi[k] = 2.0 * math.pi
        return k + 1
    a = centre - half
    a -= 2.0 * math.pi * math.floor(a / (2.0 * math.pi))
    lo[k] = a
    hi[k] = a + 2.0 * half
    return k + 1


@numba.njit(cache=True)
def _circle_cover(r: float, cx: float, cy: float, r2: float) -> tuple[float, float]:
    """Angles of the circle of radius ``r`` about 0 inside the open disk ``(c, r2)``.

    Returns ``(centre, half)``: the arc ``(centre - half, centre + half)``;
    ``half >= pi`` for all of the circle, ``half <= 0`` for none of it.
    """
    d = math.hypot(cx, cy)
    if d + r <= r2:
        return 0.0, math.pi
    if d >= r + r2 or d + r2 <= r or d == 0.0:
        return 0.0, 0.0
    c = (r * r + d * d - r2 * r2) / (2.0 * r * d)
    return math.atan2(cy, cx), math.acos(min(max(c, -1.0), 1.0))


@numba.njit(cache=True)
def disk_arcs(
    rho: float,
    pcx: float,
    pcy: float,
    nf: int,
    ocx: FloatArray,
    ocy: FloatArray,
    orho: FloatArray,
    mode: int,
    walls: FloatArray,
    box: FloatArray,
    woff: FloatArray,
    qx: FloatArray,
    qy: FloatArray,
    inner: float,
    scratch: FloatArray | None = None,
) -> FloatArray:
    """:func:`rounded_arcs` when the candidate, the new particle and every interferer are disks.

    The envelope is the circle of radius ``rho`` about the candidate; each
    interferer ``f``, the open disk of radius ``orho[f]`` about ``(ocx[f],
    ocy[f])`` (relative to the candidate's centre ``pc``), covers one open arc
    of it, and every wall (or, in a circle, the outside of the one admissible
    disk) covers one arc. The free arcs are the gaps between the covered
    ones, in polar angle from 0. ``scratch``: rows 4 and 5 hold the covers when they
    fit (see ``kernel.Work.fs``).
    """
    k_walls = 4 if mode == WALL_BOX else (walls.shape[0] if mode == WALL_HALFPLANES else 1)
    if scratch is not None and 2 * (nf + k_walls) <= scratch.shape[1]:
        lo = scratch[4]
        hi = scratch[5]
    else:
        lo = np.empty(2 * (nf + k_walls))
        hi = np.empty(2 * (nf + k_walls))
    k = 0
    for f in range(nf):
        centre, half = _circle_cover(rho, ocx[f], ocy[f], orho[f])
        k = _cover(lo, hi, k, centre, half)
    if mode == WALL_BOX or mode == WALL_HALFPLANES:
        for e in range(k_walls):
            if mode == WALL_BOX:
                nx = (-1.0, 1.0, 0.0, 0.0)[e]
                ny = (0.0, 0.0, -1.0, 1.0)[e]
                off = (-(box[0] - pcx), box[1] - pcx, -(box[2] - pcy), box[3] - pcy)[e]
            else:
                nx = walls[e, 0]
                ny = walls[e, 1]
                off = woff[e] - (nx * pcx + ny * pcy)
            # covered where rho (n . u) > off
            if off >= rho:
                continue
            half = math.pi if off <= -rho else math.acos(off / rho)
            k = _cover(lo, hi, k, math.atan2(ny, nx), half)
    elif mode == WALL_CIRCLE:
        # admissible: inside the disk of radius inner about c + q - pc
        centre, half = _circle_cover(
            rho, walls[0, 0] + qx[0] - pcx, walls[0, 1] + qy[0] - pcy, inner
        )
        if half < math.pi:  # outside that disk's arc is covered
            k = _cover(lo, hi, k, centre + math.pi, math.pi - max(half, 0.0))
    # free = the complement of the union of the covered intervals; an interval
    # that runs past 2 pi also covers the start of the circle: add that part
    out = np.empty((2 * k + 1, 2))
    if k == 0:
        out[0, 0] = 0.0
        out[0, 1] = 2.0 * math.pi
        return out[:1]
    m = k
    for idx in range(m):
        if hi[idx] > 2.0 * math.pi:
            lo[k] = lo[idx] - 2.0 * math.pi
            hi[k] = hi[idx] - 2.0 * math.pi
            k += 1
    sort_covers(lo, hi, k)
    # sweep once around from the start of the first covered interval
    start = lo[0]
    reach = hi[0]
    na = 0
    for idx in range(1, k):
        a = lo[idx]
        b = hi[idx]
        if a > reach:
            out[na, 0] = reach
            out[na, 1] = a
            na += 1
        if b > reach:
            reach = b
    if reach < start + 2.0 * math.pi:
        out[na, 0] = reach
        out[na, 1] = start + 2.0 * math.pi
        na += 1
    return out[:na]


@numba.njit(cache=True)
def rounded_locate(
    wx: FloatArray,
    wy: FloatArray,
    wex: FloatArray,
    wey: FloatArray,
    n: int,
    rho: float,
    angle: float,
) -> tuple[float, float]:
    """Point of the rounded envelope at polar ``angle`` (relative to the candidate)."""
    pieces = envelope_pieces(wx, wy, wex, wey, n, rho)
    npc = pieces.shape[0]
    va = np.empty(npc + 1)
    piece_angles(pieces, va)
    a, p = angle_slot(va, npc, angle)
    return ray_hit(pieces[p], a)
