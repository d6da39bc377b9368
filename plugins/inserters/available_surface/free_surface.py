"""The free part of a candidate's envelope boundary, and uniform sampling on it.

For a candidate ``P_k`` and the new particle ``Q``, the centres at which ``Q``
touches ``P_k`` form the boundary of the envelope ``E_k = P_k ⊕ (-Q)`` placed
at ``P_k``'s centre ``c_k``. A centre is *free* when it also lies in the closed
box ``[lo, hi]`` of admissible centres (walls; infinite bounds for periodic
axes) and outside the open interior of every interferer's envelope
``E_j = P_j ⊕ (-Q)`` placed at ``c_j`` (``Q`` would overlap ``P_j``); touching
``P_j`` is allowed.

Method
------
Each face of ``E_k`` is handled in its own plane (a 2D frame about its
centroid). The face polygon is clipped by the box; then the interferers are
subtracted in turn from its convex pieces. ``int(E_j)`` meets the plane in an
open convex polygon, the intersection of one open half-plane per facet of
``E_j``: the face polygon is clipped by those half-planes first, which gives
the part ``C`` of the face inside ``E_j`` and the few lines that bound it
(facets whose line misses the face polygon play no part there). Every piece
is then split along those lines in turn: the part on the outer side of a
line is kept as a free piece, and what remains after the last line (inside
``C``) is dropped. A piece clear of ``C``'s bounding box, or outside one of the
lines, is kept whole, so the pieces stay convex and few.

Interferers are culled first by bounding spheres (``radii``), then facet by
facet: a facet whose plane misses ``E_k``'s circumsphere, or a face's
circumcircle, either leaves the whole face outside ``E_j`` or constrains
nothing there (the facet that last separated a face from ``E_j`` is tried
first on the next face); so are the few interferers that last covered a
whole face.

The pieces are returned with their areas; :func:`sample_free_point` picks a
piece by area and a point uniformly in it (a triangle fan), so the point is
uniform by area on the free surface.

Tolerance
---------
One length, ``tau = FREE_EPS * R_k`` (``R_k``: ``E_k``'s circumradius about
``c_k``), decides contacts:

- a point counts as inside an interferer only if it is deeper than ``tau``
  inside every facet plane, so a point on (or within ``tau`` of) the boundary
  of ``E_j`` is free: touching is allowed, and a face of ``E_k`` that lies in a
  facet plane of ``E_j`` loses nothing;
- the box is widened by ``tau``;
- a piece thinner than ``THIN_FACTOR * tau`` (``2 area / perimeter``, its width
  for a strip) counts as no free surface, and an interferer that would only
  remove such a sliver from a piece leaves it whole. Tangent points and lines
  (a slot into which ``Q`` fits exactly) thus give no free area, as long as
  the facets that meet there are inclined by more than about 7 degrees to
  the face: the shrinking widens such a line into a strip about
  ``tau / sin(angle)`` wide on each side.

A sampled centre may therefore make ``Q`` overlap a ``P_j`` or cross a wall by
up to about ``THIN_FACTOR * tau`` (``1.6e-11 R_k``); ``tau`` sits well above
rounding as long as the centres are within about ``1e3 R_k`` of each other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.inserters.available_surface.polygon import (
    bounding_box,
    clip_polygon,
    copy_polygon,
    is_thin,
    plane_frame,
    polygon_area,
    split_polygon,
)
from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

FREE_EPS = 1e-12
"""Contact tolerance, relative to the candidate envelope's circumradius."""
THIN_FACTOR = 16.0
"""Pieces thinner than this many tolerances count as no surface."""
COVER_MEMORY = 4
"""Interferers that last covered a whole face, tried first on the next face."""


class Interferers(NamedTuple):
    """Interferer envelopes ``E_j`` in H-representation, one after another.

    Attributes
    ----------
    normals, support
        ``(F, 3)`` unit outward facet normals and ``(F,)`` support values of
        all envelopes, relative to their own centres; envelope ``j`` owns rows
        ``offsets[j]:offsets[j + 1]``.
    offsets
        ``(n + 1,)`` row offsets.
    centres
        ``(n, 3)`` centres ``c_j`` (absolute).
    radii
        ``(n,)`` a bound of each envelope's circumradius about its centre,
        used for culling only (``inf`` disables it).
    """

    normals: FloatArray
    support: FloatArray
    offsets: IntArray
    centres: FloatArray
    radii: FloatArray


class FreeSurface(NamedTuple):
    """Free part of a candidate envelope's boundary, as convex planar pieces.

    Attributes
    ----------
    points
        ``(m, 3)`` piece corners in absolute coordinates, counter-clockwise
        seen from outside the envelope.
    offsets
        ``(npieces + 1,)``: piece ``i`` is ``points[offsets[i]:offsets[i + 1]]``.
    cumulative
        ``(npieces,)`` running total of the pieces' areas.
    face
        ``(npieces,)`` the envelope face each piece lies on.
    area
        Total free area (``cumulative[-1]``, or 0).
    """

    points: FloatArray
    offsets: IntArray
    cumulative: FloatArray
    face: IntArray
    area: float


def interferers_from(
    envelopes: Sequence[Polyhedron], centres: ArrayLike, radii: ArrayLike | None = None
) -> Interferers:
    """Pack envelopes and their centres into :class:`Interferers`.

    Parameters
    ----------
    envelopes
        The interferers' envelopes, relative to their centres.
    centres
        ``(n, 3)`` absolute centres.
    radii
        Circumradius bounds; by default the envelopes' circumradii.
    """
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    if len(c) != len(envelopes):
        raise ValueError(f"{len(envelopes)} envelopes but {len(c)} centres")
    sizes = [len(e.normals) for e in envelopes]
    if radii is None:
        r = np.array([float(np.max(np.linalg.norm(e.vertices, axis=1))) for e in envelopes])
    else:
        r = np.asarray(radii, dtype=np.float64).reshape(-1)
    return Interferers(
        normals=np.ascontiguousarray(
            np.concatenate([e.normals for e in envelopes]) if envelopes else np.empty((0, 3))
        ),
        support=np.concatenate([e.support for e in envelopes]) if envelopes else np.empty(0),
        offsets=np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
        centres=np.ascontiguousarray(c),
        radii=np.ascontiguousarray(r),
    )


# rows of the scratch array ``work``
W_RX, W_RY = 0, 1  # a piece being cut
W_IX, W_IY = 2, 3  # its part inside a line
W_OX, W_OY = 4, 5  # its part outside a line
W_G = 6  # values of the line's function at its vertices
W_FX, W_FY = 7, 8  # the face polygon, clipped by the box
W_KX, W_KY = 9, 10  # the part of the face inside one interferer (by turns with W_IX, W_IY)
N_WORK = 11
# the array ``geom``: rows 0-2 hold the lines a, b, c of one interferer on one
# face (inside: c - a s - b t >= 0); row G_FRAME the face's frame
G_FRAME = 3
# columns of the frame row: centroid o (relative to c_k), e1, e2, circumradius
# about o, then the bounding box of the part inside the interferer (centre, half sizes)
F_O, F_E1, F_E2, F_RADIUS, F_BOX = 0, 3, 6, 9, 10
N_FRAME = 14


@numba.njit(cache=True)
def _cull_interferers(
    centre: FloatArray, interferers: Interferers, rk: float, tau: float
) -> tuple[FloatArray, FloatArray, IntArray, bool]:
    """Select the interferers that can reach ``E_k``; give their facets in ``E_k``'s frame.

    A point ``x`` (relative to ``c_k``) is inside ``E_j`` when ``n · x < b`` for
    every facet, ``b = h + n · (c_j - c_k)``. Facets whose plane misses
    ``E_k``'s circumsphere on the inner side are dropped; an interferer with
    a facet that leaves the sphere outside is dropped.

    Returns
    -------
    facets
        ``(k, 4)``: the kept facets' normals and ``b``.
    shifts
        ``(na, 4)``: the kept interferers' centres relative to ``c_k`` and
        culling radii.
    index
        ``(2, na + 1)``: facet offsets of the kept interferers; and a second
        row for the caller (the last separating facet of each, ``-1``).
    covered
        True when ``E_k``'s circumsphere lies inside an interferer (nothing is free).
    """
    nint = interferers.offsets.shape[0] - 1
    total = interferers.normals.shape[0]
    facets = np.empty((total, 4))
    shifts = np.empty((nint, 4))
    index = np.full((2, nint + 1), -1, dtype=np.int64)
    index[0, 0] = 0
    na = 0
    used = 0
    for j in range(nint):
        dx = interferers.centres[j, 0] - centre[0]
        dy = interferers.centres[j, 1] - centre[1]
        dz = interferers.centres[j, 2] - centre[2]
        if math.sqrt(dx * dx + dy * dy + dz * dz) > rk + interferers.radii[j] + tau:
            continue
        start = used
        apart = False
        for m in range(interferers.offsets[j], interferers.offsets[j + 1]):
            nx = interferers.normals[m, 0]
            ny = interferers.normals[m, 1]
            nz = interferers.normals[m, 2]
            b = interferers.support[m] + nx * dx + ny * dy + nz * dz
            if b + rk <= tau:  # E_k's circumsphere is outside this facet's plane
                apart = True
                break
            if b - rk >= tau:  # the plane does not reach E_k's circumsphere
                continue
            facets[used, 0] = nx
            facets[used, 1] = ny
            facets[used, 2] = nz
            facets[used, 3] = b
            used += 1
        if apart:
            used = start
            continue
        if used == start:  # E_k's circumsphere lies inside E_j
            return facets[:0], shifts[:0], index[:, :1], True
        shifts[na, 0] = dx
        shifts[na, 1] = dy
        shifts[na, 2] = dz
        shifts[na, 3] = interferers.radii[j]
        na += 1
        index[0, na] = used
    return facets[:used], shifts[:na], index[:, : na + 1], False


@numba.njit(cache=True)
def _face_polygon(
    envelope: Polyhedron,
    f: int,
    blo: FloatArray,
    bhi: FloatArray,
    walls: FloatArray,
    geom: FloatArray,
    work: FloatArray,
) -> int:
    """Face ``f`` in its plane's 2D frame, clipped by the box and ``walls``; return its size.

    ``walls`` are rows ``n, b`` of half-spaces ``n · x <= b`` relative to the
    candidate's centre (a cylinder's facets).

    Writes the frame to row ``G_FRAME`` of ``geom`` and the polygon to rows
    ``W_FX, W_FY`` of ``work``.
    """
    ev = envelope.vertices
    s0 = envelope.face_offsets[f]
    m = envelope.face_offsets[f + 1] - s0
    o0 = 0.0
    o1 = 0.0
    o2 = 0.0
    for i in range(m):
        v = envelope.face_vertices[s0 + i]
        o0 += ev[v, 0]
        o1 += ev[v, 1]
        o2 += ev[v, 2]
    o0 /= m
    o1 /= m
    o2 /= m
    e1x, e1y, e1z, e2x, e2y, e2z = plane_frame(
        envelope.normals[f, 0], envelope.normals[f, 1], envelope.normals[f, 2]
    )
    rf = 0.0
    for i in range(m):
        v = envelope.face_vertices[s0 + i]
        px = ev[v, 0] - o0
        py = ev[v, 1] - o1
        pz = ev[v, 2] - o2
        work[W_FX, i] = e1x * px + e1y * py + e1z * pz
        work[W_FY, i] = e2x * px + e2y * py + e2z * pz
        rf = max(rf, math.sqrt(px * px + py * py + pz * pz))
    fr = G_FRAME
    geom[fr, F_O] = o0
    geom[fr, F_O + 1] = o1
    geom[fr, F_O + 2] = o2
    geom[fr, F_E1] = e1x
    geom[fr, F_E1 + 1] = e1y
    geom[fr, F_E1 + 2] = e1z
    geom[fr, F_E2] = e2x
    geom[fr, F_E2 + 1] = e2y
    geom[fr, F_E2 + 2] = e2z
    geom[fr, F_RADIUS] = rf
    n = m
    # the box: x_a = o_a + s e1_a + t e2_a within [blo_a, bhi_a]
    for a in range(3):
        oa = geom[fr, F_O + a]
        ea = geom[fr, F_E1 + a]
        fa = geom[fr, F_E2 + a]
        for side in range(2):
            if side == 0 and oa - rf < blo[a]:  # keep (oa - blo) + ea s + fa t >= 0
                c0 = oa - blo[a]
                sa = ea
                sb = fa
            elif side == 1 and oa + rf > bhi[a]:  # keep (bhi - oa) - ea s - fa t >= 0
                c0 = bhi[a] - oa
                sa = -ea
                sb = -fa
            else:
                continue
            for i in range(n):
                work[W_G, i] = c0 + sa * work[W_FX, i] + sb * work[W_FY, i]
            n = clip_polygon(work, W_FX, W_FY, n, W_G, W_IX, W_IY)
            copy_polygon(work, W_IX, W_IY, n, W_FX, W_FY)
            if n < 3:
                return 0
    for w in range(walls.shape[0]):  # keep (b - n·o) - (n·e1) s - (n·e2) t >= 0
        c0 = walls[w, 3]
        sa = 0.0
        sb = 0.0
        for a in range(3):
            c0 -= walls[w, a] * geom[fr, F_O + a]
            sa -= walls[w, a] * geom[fr, F_E1 + a]
            sb -= walls[w, a] * geom[fr, F_E2 + a]
        if c0 >= rf:
            continue  # the whole face is on the inner side
        for i in range(n):
            work[W_G, i] = c0 + sa * work[W_FX, i] + sb * work[W_FY, i]
        n = clip_polygon(work, W_FX, W_FY, n, W_G, W_IX, W_IY)
        copy_polygon(work, W_IX, W_IY, n, W_FX, W_FY)
        if n < 3:
            return 0
    return n


@numba.njit(cache=True, inline="always")
def _line_values(
    work: FloatArray, x: int, y: int, n: int, la: float, lb: float, lc: float
) -> tuple[float, float]:
    """Write ``lc - la s - lb t`` at the polygon's vertices to row ``W_G``; return its range.

    The polygon is rows ``x, y`` of ``work`` (``n`` vertices); returns the
    least and the greatest value.
    """
    gmin = np.inf
    gmax = -np.inf
    for i in range(n):
        gi = lc - la * work[x, i] - lb * work[y, i]
        work[W_G, i] = gi
        gmin = min(gmin, gi)
        gmax = max(gmax, gi)
    return gmin, gmax


@numba.njit(cache=True)
def _covered_part(
    q: int,
    n: int,
    facets: FloatArray,
    index: IntArray,
    geom: FloatArray,
    work: FloatArray,
    tau: float,
    thin: float,
) -> int:
    """Find the lines along which interferer ``q`` cuts the face polygon (``n`` vertices).

    Clips the polygon by the half-planes ``c - a s - b t >= 0`` of the
    interferer's facets (its interior shrunk by ``tau``), in rows ``W_KX,
    W_KY`` and ``W_IX, W_IY`` by turns, and writes the lines that cut it to
    rows 0-2 of ``geom`` and the clipped polygon's bounding box to the frame.
    Returns the number of lines; 0 when the whole face is inside the
    interferer; -1 when the interferer misses the face or covers only a
    sliver of it.
    """
    fr = G_FRAME
    o0 = geom[fr, F_O]
    o1 = geom[fr, F_O + 1]
    o2 = geom[fr, F_O + 2]
    rf = geom[fr, F_RADIUS]
    # the facet that last put a face outside E_q often does it again
    k = index[1, q]
    if (
        k >= 0
        and facets[k, 3] - (facets[k, 0] * o0 + facets[k, 1] * o1 + facets[k, 2] * o2) + rf <= tau
    ):
        return -1
    # the clipped polygon alternates between two pairs of rows (the face's own first)
    kx = W_FX
    ky = W_FY
    kn = n
    nl = 0
    bx, by, hx, hy = bounding_box(work, kx, ky, kn)
    for k in range(index[0, q], index[0, q + 1]):
        nx = facets[k, 0]
        ny = facets[k, 1]
        nz = facets[k, 2]
        go = facets[k, 3] - (nx * o0 + ny * o1 + nz * o2)
        if go + rf <= tau:  # the face's circumcircle is outside this facet
            index[1, q] = k
            return -1
        if go - rf >= tau:  # the face's circumcircle is inside this facet
            continue
        la = nx * geom[fr, F_E1] + ny * geom[fr, F_E1 + 1] + nz * geom[fr, F_E1 + 2]
        lb = nx * geom[fr, F_E2] + ny * geom[fr, F_E2 + 1] + nz * geom[fr, F_E2 + 2]
        lc = go - tau
        # the same test on the bounding box, which also sees the facets that
        # are nearly parallel to the face
        gc = lc - la * bx - lb * by
        spread = abs(la) * hx + abs(lb) * hy
        if gc - spread >= 0.0:
            continue
        if gc + spread <= 0.0:
            return -1
        gmin, gmax = _line_values(work, kx, ky, kn, la, lb, lc)
        if gmin >= 0.0:
            continue
        if gmax <= 0.0:
            return -1
        tx = W_KX if kx != W_KX else W_IX
        kn = clip_polygon(work, kx, ky, kn, W_G, tx, tx + 1)
        if kn < 3:
            return -1
        kx = tx
        ky = tx + 1
        bx, by, hx, hy = bounding_box(work, kx, ky, kn)
        geom[0, nl] = la
        geom[1, nl] = lb
        geom[2, nl] = lc
        nl += 1
    if nl > 0 and is_thin(work, kx, ky, kn, thin):
        return -1
    geom[fr, F_BOX] = bx
    geom[fr, F_BOX + 1] = by
    geom[fr, F_BOX + 2] = hx
    geom[fr, F_BOX + 3] = hy
    return nl


@numba.njit(cache=True)
def _subtract(
    nl: int,
    geom: FloatArray,
    pieces: FloatArray,
    poff: IntArray,
    gen: int,
    ncur: int,
    thin: float,
    work: FloatArray,
) -> int:
    """Subtract the convex region cut out by the ``nl`` lines from the pieces of generation ``gen``.

    Pieces of generation ``gen`` are rows ``2 gen, 2 gen + 1`` of ``pieces``
    with offsets in row ``gen`` of ``poff``; the result goes to generation
    ``1 - gen``. Each piece is split along the lines in turn: the parts
    outside a line are kept, the rest (inside all lines) is dropped; a piece
    clear of the region's bounding box, outside one of the lines, or from
    which only a sliver would go, is kept whole. Returns the number of new
    pieces, or -1 if the buffers are too small.
    """
    fr = G_FRAME
    nxt = 1 - gen
    cx = 2 * gen
    cy = cx + 1
    nx_ = 2 * nxt
    ny_ = nx_ + 1
    cap = pieces.shape[1]
    capp = poff.shape[1] - 1
    nnext = 0
    poff[nxt, 0] = 0
    for pc in range(ncur):
        p0 = poff[gen, pc]
        pn = poff[gen, pc + 1] - p0
        for i in range(pn):
            work[W_RX, i] = pieces[cx, p0 + i]
            work[W_RY, i] = pieces[cy, p0 + i]
        # the part still to cut alternates between two pairs of rows
        rx = W_RX
        ry = W_RY
        rn = pn
        mark = nnext
        bx, by, hx, hy = bounding_box(work, rx, ry, rn)
        intact = (
            abs(bx - geom[fr, F_BOX]) >= hx + geom[fr, F_BOX + 2]
            or abs(by - geom[fr, F_BOX + 1]) >= hy + geom[fr, F_BOX + 3]
        )
        for li in range(nl):
            if intact:
                break
            gmax = -np.inf
            for i in range(rn):
                gmax = max(
                    gmax, geom[2, li] - geom[0, li] * work[rx, i] - geom[1, li] * work[ry, i]
                )
            intact = gmax <= 0.0
        for li in range(nl):
            if intact:
                break
            la = geom[0, li]
            lb = geom[1, li]
            lc = geom[2, li]
            gmin, gmax = _line_values(work, rx, ry, rn, la, lb, lc)
            if gmin >= 0.0:
                continue
            if gmax <= 0.0:
                intact = True  # the rest is outside: nothing is removed
                break
            tx = W_RX if rx != W_RX else W_IX
            nin, nout = split_polygon(work, rx, ry, rn, W_G, tx, tx + 1, W_OX, W_OY)
            if not is_thin(work, W_OX, W_OY, nout, thin):
                base = poff[nxt, nnext]
                if nnext >= capp or base + nout > cap:
                    return -1
                for i in range(nout):
                    pieces[nx_, base + i] = work[W_OX, i]
                    pieces[ny_, base + i] = work[W_OY, i]
                nnext += 1
                poff[nxt, nnext] = base + nout
            if is_thin(work, tx, tx + 1, nin, thin):
                intact = True  # only a sliver would be removed
                break
            rx = tx
            ry = tx + 1
            rn = nin
        if intact:  # drop the parts split off and keep the piece whole
            nnext = mark
            base = poff[nxt, nnext]
            if nnext >= capp or base + pn > cap:
                return -1
            for i in range(pn):
                pieces[nx_, base + i] = pieces[cx, p0 + i]
                pieces[ny_, base + i] = pieces[cy, p0 + i]
            nnext += 1
            poff[nxt, nnext] = base + pn
    return nnext


@numba.njit(cache=True)
def _face_pieces(
    n: int,
    facets: FloatArray,
    shifts: FloatArray,
    index: IntArray,
    geom: FloatArray,
    work: FloatArray,
    pieces: FloatArray,
    poff: IntArray,
    tau: float,
    thin: float,
    last: IntArray,
) -> tuple[int, int]:
    """Subtract every interferer from the face polygon (rows ``W_FX, W_FY``).

    Returns the number of pieces and their generation (see :func:`_subtract`);
    the number is -1 if the piece buffers are too small. ``last`` lists the
    interferers that last covered a whole face, most recent first
    (:data:`COVER_MEMORY` of them, ``-1``: none): other faces are often
    inside the same ones, so they are tried first (the result is the same,
    an empty face, in whichever order the interferers come).
    """
    if n > pieces.shape[1]:
        return -1, 0
    fr = G_FRAME
    rf = geom[fr, F_RADIUS]
    for slot in range(last.shape[0]):
        q = last[slot]
        if q < 0:
            break
        cx = geom[fr, F_O] - shifts[q, 0]
        cy = geom[fr, F_O + 1] - shifts[q, 1]
        cz = geom[fr, F_O + 2] - shifts[q, 2]
        if math.sqrt(cx * cx + cy * cy + cz * cz) <= rf + shifts[q, 3] + tau:
            if _covered_part(q, n, facets, index, geom, work, tau, thin) == 0:
                _remember(last, slot, q)
                return 0, 0
    for i in range(n):
        pieces[0, i] = work[W_FX, i]
        pieces[1, i] = work[W_FY, i]
    poff[0, 0] = 0
    poff[0, 1] = n
    # not literals, which numba would compile a second specialization of _subtract for
    gen = int(np.int64(0))
    ncur = int(np.int64(1))
    for q in range(index.shape[1] - 1):
        cx = geom[fr, F_O] - shifts[q, 0]
        cy = geom[fr, F_O + 1] - shifts[q, 1]
        cz = geom[fr, F_O + 2] - shifts[q, 2]
        if math.sqrt(cx * cx + cy * cy + cz * cz) > rf + shifts[q, 3] + tau:
            continue
        nl = _covered_part(q, n, facets, index, geom, work, tau, thin)
        if nl < 0:
            continue
        if nl == 0:  # the face lies inside E_q
            _remember(last, last.shape[0] - 1, q)
            return 0, gen
        ncur = _subtract(nl, geom, pieces, poff, gen, ncur, thin, work)
        if ncur < 0:
            return -1, 0
        gen = 1 - gen
        if ncur == 0:
            break
    return ncur, gen


@numba.njit(cache=True)
def _remember(last: IntArray, slot: int, q: int) -> None:
    """Move interferer ``q`` to the front of ``last``, from ``slot`` (or from its own place)."""
    for s in range(slot):
        if last[s] == q:
            slot = s
            break
    for s in range(slot, 0, -1):
        last[s] = last[s - 1]
    last[0] = q


@numba.njit(cache=True)
def free_surface(
    envelope: Polyhedron,
    centre: FloatArray,
    interferers: Interferers,
    lo: FloatArray,
    hi: FloatArray,
    planes: FloatArray,
) -> FreeSurface:
    """Free part of the boundary of the candidate envelope ``E_k`` placed at ``centre``.

    Parameters
    ----------
    envelope
        ``E_k = P_k ⊕ (-Q)`` relative to ``P_k``'s centre.
    centre
        ``(3,)`` the centre ``c_k``.
    interferers
        The interferers' envelopes, see :class:`Interferers`.
    lo, hi
        ``(3,)`` closed box of admissible centres of ``Q``; bounds may be
        infinite.
    planes
        ``(m, 4)`` more admissible half-spaces ``n · x <= b`` (rows ``n, b``;
        a cylinder's wall facets), or none.

    Returns
    -------
    FreeSurface
        Convex pieces of the free surface and their areas (see the module
        docstring for the method and the tolerance policy).
    """
    ev = envelope.vertices
    nf = envelope.normals.shape[0]
    rk = 0.0
    for v in range(ev.shape[0]):
        rk = max(rk, math.sqrt(ev[v, 0] ** 2 + ev[v, 1] ** 2 + ev[v, 2] ** 2))
    tau = FREE_EPS * rk
    thin = THIN_FACTOR * tau
    facets, shifts, index, covered = _cull_interferers(centre, interferers, rk, tau)
    if covered:
        nf = 0
    na = index.shape[1] - 1
    blo = np.empty(3)
    bhi = np.empty(3)
    for a in range(3):  # the box relative to c_k, widened by tau
        blo[a] = lo[a] - centre[a] - tau
        bhi[a] = hi[a] - centre[a] + tau
    walls = np.empty((planes.shape[0], 4))  # the planes relative to c_k, widened by tau
    for w in range(planes.shape[0]):
        walls[w, 0] = planes[w, 0]
        walls[w, 1] = planes[w, 1]
        walls[w, 2] = planes[w, 2]
        walls[w, 3] = (
            planes[w, 3]
            + tau
            - (planes[w, 0] * centre[0] + planes[w, 1] * centre[1] + planes[w, 2] * centre[2])
        )
    # scratch: no polygon has more corners than a face, the box's 6 sides and
    # one side per facet of an interferer
    most_facets = 0
    for q in range(na):
        most_facets = max(most_facets, index[0, q + 1] - index[0, q])
    largest = 0
    for f in range(nf):
        largest = max(largest, envelope.face_offsets[f + 1] - envelope.face_offsets[f])
    width = largest + most_facets + 8 + planes.shape[0]
    work = np.empty((N_WORK, width))
    geom = np.empty((G_FRAME + 1, max(most_facets + 1, N_FRAME)))
    pieces = np.empty((4, 8 * width))
    poff = np.empty((2, 33), dtype=np.int64)

    out_p = np.empty((max(4 * nf, 16), 3))
    out_off = np.zeros(nf + 2, dtype=np.int64)
    out_area = np.empty(nf + 1)
    out_face = np.empty(nf + 1, dtype=np.int64)
    last = np.full(COVER_MEMORY, -1, dtype=np.int64)
    # not literal 0s, which numba would compile second specializations of the callees for
    npieces = int(np.int64(0))
    f = int(np.int64(0))
    while f < nf:
        n = _face_polygon(envelope, f, blo, bhi, walls, geom, work)
        if n < 3 or is_thin(work, W_FX, W_FY, n, thin):
            f += 1
            continue
        ncur, gen = _face_pieces(
            n, facets, shifts, index, geom, work, pieces, poff, tau, thin, last
        )
        if ncur < 0:  # the piece buffers are too small: grow them, do the face again
            pieces = np.empty((4, 2 * pieces.shape[1]))
            poff = np.empty((2, 2 * poff.shape[1] - 1), dtype=np.int64)
            continue
        if npieces + ncur >= out_area.shape[0]:
            grown = 2 * (npieces + ncur) + 1
            out_off = _grow_int(out_off, grown + 1)
            out_face = _grow_int(out_face, grown)
            out_area = _grow_float(out_area, grown)
        need = out_off[npieces] + poff[gen, ncur]
        if need > out_p.shape[0]:
            out_p2 = np.empty((2 * need, 3))
            out_p2[: out_off[npieces]] = out_p[: out_off[npieces]]
            out_p = out_p2
        npieces = _emit(
            f, geom, centre, pieces, poff, gen, ncur, out_p, out_off, out_area, out_face, npieces
        )
        f += 1
    cumulative = np.empty(npieces)
    acc = 0.0
    for i in range(npieces):
        acc += out_area[i]
        cumulative[i] = acc
    return FreeSurface(
        out_p[: out_off[npieces]].copy(),
        out_off[: npieces + 1].copy(),
        cumulative,
        out_face[:npieces].copy(),
        acc,
    )


@numba.njit(cache=True)
def _emit(
    f: int,
    geom: FloatArray,
    centre: FloatArray,
    pieces: FloatArray,
    poff: IntArray,
    gen: int,
    ncur: int,
    out_p: FloatArray,
    out_off: IntArray,
    out_area: FloatArray,
    out_face: IntArray,
    npieces: int,
) -> int:
    """Append the ``ncur`` 2D pieces of face ``f`` to the output in 3D; return the new count."""
    fr = G_FRAME
    for pc in range(ncur):
        p0 = poff[gen, pc]
        pn = poff[gen, pc + 1] - p0
        base = out_off[npieces]
        for i in range(pn):
            s = pieces[2 * gen, p0 + i]
            t = pieces[2 * gen + 1, p0 + i]
            for d in range(3):
                out_p[base + i, d] = centre[d] + (
                    geom[fr, F_O + d] + s * geom[fr, F_E1 + d] + t * geom[fr, F_E2 + d]
                )
        out_area[npieces] = polygon_area(pieces, 2 * gen, 2 * gen + 1, p0, pn)
        out_face[npieces] = f
        npieces += 1
        out_off[npieces] = base + pn
    return npieces


@numba.njit(cache=True)
def _grow_int(a: IntArray, size: int) -> IntArray:
    """Return a copy of ``a`` with ``size`` entries (at least ``a``'s), contents kept."""
    b = np.empty(max(size, a.shape[0]), dtype=np.int64)
    b[: a.shape[0]] = a
    return b


@numba.njit(cache=True)
def _grow_float(a: FloatArray, size: int) -> FloatArray:
    """Return a copy of ``a`` with ``size`` entries (at least ``a``'s), contents kept."""
    b = np.empty(max(size, a.shape[0]))
    b[: a.shape[0]] = a
    return b


@numba.njit(cache=True)
def sample_free_point(surface: FreeSurface, u1: float, u2: float, u3: float) -> FloatArray:
    """Return a point drawn uniformly by area on the free surface.

    Parameters
    ----------
    surface
        The free surface (:func:`free_surface`); its area must be positive.
    u1, u2, u3
        Independent uniform numbers in ``[0, 1)``: ``u1`` picks the piece by
        area and, rescaled within it, a triangle of the piece's fan;
        ``u2, u3`` a point in that triangle.

    Returns
    -------
    numpy.ndarray
        ``(3,)`` the point (absolute coordinates).

    Raises
    ------
    ValueError
        If the free surface has no area.
    """
    npieces = surface.cumulative.shape[0]
    if npieces == 0 or not surface.area > 0.0:
        raise ValueError("the free surface has no area")
    target = u1 * surface.area
    piece = np.searchsorted(surface.cumulative, target, side="right")
    if piece >= npieces:
        piece = npieces - 1
    before = surface.cumulative[piece - 1] if piece > 0 else 0.0
    own = surface.cumulative[piece] - before
    frac = (target - before) / own if own > 0.0 else 0.0
    frac = min(max(frac, 0.0), 1.0)
    pts = surface.points
    p0 = surface.offsets[piece]
    pn = surface.offsets[piece + 1] - p0
    # the fan's triangle areas (twice), then the triangle holding the fraction
    fan = 0.0
    for i in range(1, pn - 1):
        fan += _twice_area(pts, p0, p0 + i, p0 + i + 1)
    goal = frac * fan
    tri = pn - 2
    acc = 0.0
    for i in range(1, pn - 1):
        acc += _twice_area(pts, p0, p0 + i, p0 + i + 1)
        if goal < acc:
            tri = i
            break
    a = u2
    b = u3
    if a + b > 1.0:
        a = 1.0 - a
        b = 1.0 - b
    out = np.empty(3)
    for d in range(3):
        v0 = pts[p0, d]
        out[d] = v0 + a * (pts[p0 + tri, d] - v0) + b * (pts[p0 + tri + 1, d] - v0)
    return out


@numba.njit(cache=True)
def _twice_area(pts: FloatArray, a: int, b: int, c: int) -> float:
    """Twice the area of the triangle ``pts[a], pts[b], pts[c]``."""
    ux = pts[b, 0] - pts[a, 0]
    uy = pts[b, 1] - pts[a, 1]
    uz = pts[b, 2] - pts[a, 2]
    vx = pts[c, 0] - pts[a, 0]
    vy = pts[c, 1] - pts[a, 1]
    vz = pts[c, 2] - pts[a, 2]
    cx = uy * vz - uz * vy
    cy = uz * vx - ux * vz
    cz = ux * vy - uy * vx
    return math.sqrt(cx * cx + cy * cy + cz * cz)
