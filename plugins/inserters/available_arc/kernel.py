"""Compiled core of the available-arc inserter: candidate analysis and placement.

The state of a run is three named tuples of plain arrays (built by
:class:`regopack.plugins.inserters.available_arc.state.ArcState`):

- :class:`Outlines`, static: outlines in canonical form, radii, local boxes;
- :class:`Packed`, growing: centres, insertion order, the screening max-tree,
  the neighbour grid and scalar parameters ``fpar`` / ``ipar``;
- :class:`Work`, scratch buffers, including a cache of interferer envelopes
  (an envelope ``P_o ⊕ (-Q)`` depends only on ``o`` and the new particle).

``k`` is an insertion index; ``order[k]`` is the particle it refers to.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.atomics import load_acquire
from regopack.plugins.common.borrowed import borrowed
from regopack.plugins.common.halfplane_clip import clip_halfplane
from regopack.plugins.common.walls import (
    WALL_BOX,
    WALL_CIRCLE,
    WALL_HALFPLANES,
    WALL_PERIODIC,
    clip_closed_circle,
    clip_closed_halfplanes,
    particle_offsets,
    point_fits,
    wrap_periodic,
)
from regopack.plugins.inserters.available_arc.bound_queue import post_bound
from regopack.plugins.inserters.available_arc.candidates import first_candidate, tree_set
from regopack.plugins.inserters.available_arc.disk_bound import disk_bound
from regopack.plugins.inserters.available_arc.geometry import (
    angle_slot,
    clip_closed_box,
    clip_open_interior,
    close_arcs,
    inside_open,
    minkowski_envelope,
    reflect_outline,
)
from regopack.plugins.inserters.available_arc.grid import cell_range, grid_insert
from regopack.plugins.inserters.available_arc.neighbours import (
    GAP_SLACK,
    IMAGE_QUERIES,
    GridView,
    ListPool,
    image_query,
    image_shift,
    image_shifts,
    register_neighbours,
)
from regopack.plugins.inserters.available_arc.rounded import (
    RoundedInterferers,
    RoundedWalls,
    disk_arcs,
    rounded_arcs,
    rounded_locate,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# fpar: scalar float parameters
# (F_XMIN..F_YMAX: the domain's bounding box; F_CX, F_CY: its centre;
# F_REACH: the largest registration radius in the grid)
(
    F_T,
    F_TAU,
    F_XMIN,
    F_XMAX,
    F_YMIN,
    F_YMAX,
    F_GX0,
    F_GY0,
    F_GCELL,
    F_ETA,
    F_CX,
    F_CY,
    F_REACH,
    F_NBCAP,
    F_RMIN,
) = range(15)
N_FPAR = 15
# ipar: scalar integer parameters and counters
(
    I_TAUMODE,
    I_LINEAR,
    I_COUNT,
    I_LEAVES,
    I_GNX,
    I_GNY,
    I_GUSED,
    I_STAMP,
    I_ANALYSES,
    I_EMPTY,
    I_GEN,
    I_CUSED,
    I_FIRSTRANDOM,
    I_WALLMODE,
    I_ROUNDED,
    I_NBLISTS,
    I_NBTOP,
    I_DISKS,
    I_BOUND,
    I_STRIP,
) = range(20)
N_IPAR = 20
STRIP_SLOTS = 4096
"""Most strips of the sweep (``Packed.hhead``'s length)."""
NOT_LISTED = -2
"""``Packed.hnext`` of a candidate on no list of hidden candidates."""
BOUND_OFF, BOUND_PROVE, BOUND_POST = 0, 1, 2
"""Values of ``ipar[I_BOUND]``: no disk bounds; proved by the analysis that found no arc;
posted to the partner thread (the calling thread's parameters only; see
:mod:`~regopack.plugins.inserters.available_arc.bound_queue`)."""
FIRST_RANDOM_TRIES = 10_000
"""Random draws in the domain's box for a feasible first centre before giving up."""
CACHE_SLOTS = 512
FOUND_SLOTS = 64
"""Interferers an analysis holds in its scratch before it allocates a larger buffer."""
SCRATCH_ROWS = 10
SCRATCH_WIDTH = 2 * (FOUND_SLOTS + 8)
"""Shape of ``Work.fs``: room for the covers of ``FOUND_SLOTS`` interferers and 8 walls."""
CIRCLE_SLACK = 1.0 + 1e-9
"""Relative slack of the squared-circumcircle pre-test of the covered-edge search."""


class Outlines(NamedTuple):
    """Static particle data; outlines in canonical form (see ``geometry.prepare_outlines``)."""

    vx: FloatArray
    vy: FloatArray
    ex: FloatArray
    ey: FloatArray
    ang: FloatArray
    offsets: IntArray
    circum: FloatArray
    req: FloatArray
    box: FloatArray
    rho: FloatArray


class Packed(NamedTuple):
    """The growing packing: centres, order, screening tree, neighbour grid, parameters."""

    cx: FloatArray
    cy: FloatArray
    order: IntArray
    tree: FloatArray
    head: IntArray
    nxt: IntArray
    item: IntArray
    stamp: IntArray
    fpar: FloatArray
    ipar: IntArray
    walls: FloatArray
    nb_o: NDArray[np.int32]
    nb_gap: FloatArray
    nb_dx: FloatArray
    nb_dy: FloatArray
    nb_n: IntArray
    nb_reach: FloatArray
    nb_row: IntArray
    nb_free: IntArray
    nb_img: NDArray[np.int8]
    """Per list entry in a periodic domain: which image of the neighbour it is
    (:func:`~regopack.plugins.inserters.available_arc.neighbours.image_code`); 0 elsewhere."""
    shut: FloatArray
    """Per particle, in a scene of disks: a radius from which no disk fits against it
    (:mod:`~regopack.plugins.inserters.available_arc.disk_bound`); ``inf`` where none is known."""
    bq: IntArray
    """Counters of the ring of bounds the partner proves
    (:mod:`~regopack.plugins.inserters.available_arc.bound_queue`)."""
    bqf: FloatArray
    """Slots of that ring."""
    home: IntArray
    """Per insertion index, in the sweep: the strip of the candidate (``ipar[I_STRIP]``: the
    strip searched, -1 for every candidate; see :func:`next_candidate`)."""
    hnext: IntArray
    """Per insertion index: the next candidate hidden in the same strip, -1 for none;
    ``NOT_LISTED`` for a candidate on no list."""
    hhead: IntArray
    """Per strip: the last candidate hidden in it, -1 for none."""


class Work(NamedTuple):
    """Scratch buffers and the interferer-envelope cache."""

    rx: FloatArray
    ry: FloatArray
    rex: FloatArray
    rey: FloatArray
    rang: FloatArray
    wx: FloatArray
    wy: FloatArray
    wex: FloatArray
    wey: FloatArray
    va: FloatArray
    ckey: IntArray
    cslot: IntArray
    cache_x: FloatArray
    cache_y: FloatArray
    cache_ex: FloatArray
    cache_ey: FloatArray
    cache_n: IntArray
    cache_rad: FloatArray
    woff: FloatArray
    found: IntArray
    """The interferers of an analysis. When they do not fit, the grid search runs again into
    a buffer twice their number, and a longer neighbour list (none while the lists hold
    ``LIST_CAPACITY = FOUND_SLOTS`` entries) gets a buffer of its length."""
    found_q: IntArray
    """In a periodic domain, the image query that found each interferer; an analysis of
    sharp polygons then overwrites it with the interferers' envelope-cache slots."""
    fs: FloatArray
    """``(SCRATCH_ROWS, SCRATCH_WIDTH)``: rows of scratch for an analysis of disks
    (:func:`~regopack.plugins.inserters.available_arc.rounded.disk_arcs` and
    :func:`~regopack.plugins.inserters.available_arc.disk_bound.disk_bound`) or of sharp polygons
    (the interferers' offsets and an edge's covered intervals); one with more
    interferers allocates its own."""


@numba.njit(cache=True)
def reach_of(p: int, g: Outlines, fpar: FloatArray, ipar: IntArray) -> float:
    """Registration radius of particle ``p`` in the neighbour grid."""
    if ipar[I_TAUMODE] == 1:
        return max(g.circum[p], g.req[p] / fpar[F_TAU])
    return g.circum[p]


@numba.njit(cache=True)
def centre_box(i: int, g: Outlines, fpar: FloatArray) -> tuple[float, float, float, float]:
    """Return the closed box of centres that keep particle ``i`` inside the walls."""
    return (
        fpar[F_XMIN] - g.box[i, 0],
        fpar[F_XMAX] - g.box[i, 1],
        fpar[F_YMIN] - g.box[i, 2],
        fpar[F_YMAX] - g.box[i, 3],
    )


@numba.njit(cache=True)
def insert_particle(i: int, x: float, y: float, g: Outlines, s: Packed) -> int:
    """Place particle ``i`` at ``(x, y)``; return its insertion index."""
    ipar = s.ipar
    k = ipar[I_COUNT]
    if ipar[I_WALLMODE] == WALL_PERIODIC:
        x = wrap_periodic(x, s.fpar[F_XMIN], s.fpar[F_XMAX])
        y = wrap_periodic(y, s.fpar[F_YMIN], s.fpar[F_YMAX])
    s.cx[i] = x
    s.cy[i] = y
    s.order[k] = i
    tree_set(s.tree, ipar[I_LEAVES], k, np.inf)
    ipar[I_COUNT] = k + 1
    gpar = s.fpar[F_GX0 : F_GCELL + 1]
    gdim = ipar[I_GNX : I_GUSED + 1]
    if ipar[I_NBLISTS] == 1:
        token = ipar[I_STAMP] + 1
        ipar[I_STAMP] = token
        periodic = ipar[I_WALLMODE] == WALL_PERIODIC
        grid = GridView(gpar, gdim, s.head, s.nxt, s.item, s.stamp)
        lists = ListPool(s.nb_o, s.nb_gap, s.nb_dx, s.nb_dy, s.nb_n, s.nb_img, s.nb_row, s.nb_free)
        ipar[I_NBTOP] = register_neighbours(
            i, token, ipar[I_NBTOP], s.cx, s.cy, s.nb_reach, grid, lists,
            s.fpar[F_NBCAP], s.fpar[F_REACH], periodic, s.fpar[F_XMIN : F_YMAX + 1],
            s.shut, s.fpar[F_RMIN],
        )  # fmt: skip
        if periodic:  # the image queries took stamps of their own
            ipar[I_STAMP] = token + IMAGE_QUERIES
    grid_insert(i, x, y, reach_of(i, g, s.fpar, ipar), gpar, gdim, s.head, s.nxt, s.item)
    return k


@numba.njit(cache=True)
def _vertex_angles(wx: FloatArray, wy: FloatArray, n: int, out: FloatArray) -> None:
    """Unwrapped polar angle of every envelope vertex (``out[n]`` closes the loop)."""
    out[0] = math.atan2(wy[0], wx[0])
    for j in range(n):
        j2 = j + 1 if j + 1 < n else 0
        cr = wx[j] * wy[j2] - wy[j] * wx[j2]
        dt = wx[j] * wx[j2] + wy[j] * wy[j2]
        out[j + 1] = out[j] + math.atan2(cr, dt)


@numba.njit(cache=True)
def _angle_on_edge(
    wx: FloatArray, wy: FloatArray, n: int, va: FloatArray, j: int, s: float
) -> float:
    """Polar angle of the point at parameter ``s`` of envelope edge ``j``."""
    if s <= 0.0:
        return va[j]
    if s >= 1.0:
        return va[j + 1]
    j2 = j + 1 if j + 1 < n else 0
    px = wx[j] + s * (wx[j2] - wx[j])
    py = wy[j] + s * (wy[j2] - wy[j])
    return va[j] + math.atan2(wx[j] * py - wy[j] * px, wx[j] * px + wy[j] * py)


@numba.njit(cache=True)
def begin_particle(i: int, g: Outlines, s: Packed, w: Work) -> int:
    """Prepare the scratch buffers for new particle ``i``; return its vertex count."""
    mq = reflect_outline(
        i, g.vx, g.vy, g.ex, g.ey, g.ang, g.offsets, w.rx, w.ry, w.rex, w.rey, w.rang
    )
    s.ipar[I_GEN] += 1
    s.ipar[I_CUSED] = 0
    if s.ipar[I_WALLMODE] == WALL_HALFPLANES:
        particle_offsets(g.vx, g.vy, g.offsets[i], g.offsets[i + 1], s.walls, w.woff)
        for e in range(w.woff.shape[0]):
            w.woff[e] -= g.rho[i]
    return mq


@numba.njit(cache=True)
def _clip_walls(
    mode: int,
    ax: float,
    ay: float,
    dx: float,
    dy: float,
    i: int,
    mq: int,
    g: Outlines,
    s: Packed,
    w: Work,
) -> tuple[float, float]:
    """Interval of centres ``a + s d`` (absolute) that keep particle ``i`` inside its walls.

    For polygon and circular walls; a periodic domain admits everything. Kept
    out of :func:`analyze_candidate` so that the walled rectangle's loop stays small.
    """
    if mode == WALL_HALFPLANES:
        return clip_closed_halfplanes(ax, ay, dx, dy, s.walls, w.woff)
    if mode == WALL_CIRCLE:
        return clip_closed_circle(ax, ay, dx, dy, w.rx, w.ry, mq, -1.0, g.circum[i], s.walls)
    return -np.inf, np.inf


@numba.njit(cache=True, inline="always")
def _envelope(
    o: int,
    mq: int,
    g: Outlines,
    w: Work,
    ox: FloatArray,
    oy: FloatArray,
    oex: FloatArray,
    oey: FloatArray,
) -> int:
    """Envelope of particle ``o`` and the new particle (``begin_particle``) into ``ox`` .. ``oey``.

    Returns its vertex count; see ``geometry.minkowski_envelope``.
    """
    return minkowski_envelope(
        o, g.vx, g.vy, g.ex, g.ey, g.ang, g.offsets,
        w.rx, w.ry, w.rex, w.rey, w.rang, mq, ox, oy, oex, oey,
    )  # fmt: skip


@numba.njit(cache=True)
def _interferes(d2: float, rpk: float, ro: float, ri2: float, tau_mode: bool, tau: float) -> bool:
    """Whether a particle at squared distance ``d2`` from ``pk`` can cover part of ``E_k``.

    ``rpk``, ``ro`` and ``ri2`` are the radii of ``pk`` and ``o`` and twice that of
    the new particle: equivalent radii under the τ screening (``tau_mode``),
    circumradii otherwise. Scalars only: a compiled function that receives the
    outline tuple counts up each of its arrays at every call.
    """
    if tau_mode:
        lim = (rpk + ro + ri2) / tau
    else:
        lim = rpk + ro + ri2
    hit = d2 < lim * lim
    if hit and tau_mode:
        hit = tau * math.sqrt(d2) < rpk + ro + ri2
    return hit


@numba.njit(cache=True)
def analyze_candidate(
    pk: int,
    i: int,
    mq: int,
    g: Outlines,
    s: Packed,
    w: Work,
    rounded: object = None,
    cut: tuple[IntArray, int, int] | None = None,
) -> FloatArray:
    """Available arcs of candidate particle ``pk`` for the new particle ``i``.

    ``begin_particle(i, ...)`` must have been called. ``rounded`` is ``None``
    in a scene of sharp polygons (the rounded path is then pruned at compile
    time and never compiled) and ``True`` when some particle is rounded.
    ``cut`` is ``None`` (compiled away), or ``(words, index, id)`` for a
    partner's analysis (:mod:`~regopack.plugins.inserters.available_arc.partner`):
    before each envelope edge it stops, with no arcs, once ``words[index]``
    has reached ``id`` (the caller will not read the result).

    Returns
    -------
    ndarray
        ``(k, 2)`` polar-angle intervals about ``pk``'s centre, unwrapped from the
        angle of the envelope's first vertex; an arc through that vertex is one
        interval that starts below it.
    """
    fpar = s.fpar
    ipar = s.ipar
    cx = s.cx
    cy = s.cy
    pcx = cx[pk]
    pcy = cy[pk]

    # ---- interferers from the grid
    tau_mode = ipar[I_TAUMODE] == 1
    tau = fpar[F_TAU]
    # the radii that decide which particles interfere (see _interferes)
    rad = g.req if tau_mode else g.circum
    rpk = rad[pk]
    ri2 = 2.0 * rad[i]
    qrad = (rpk + ri2) / tau if tau_mode else rpk + ri2
    mode = ipar[I_WALLMODE]
    periodic = mode == WALL_PERIODIC
    # query boxes: the one about pk and, in a periodic domain, its images one
    # period away when an interferer's image could lie across a side (within
    # qrad plus the largest reach). Each image query finds the particles near
    # that image of pk, i.e. the periodic images of particles near pk: one
    # interferer entry per image.
    # shifts of the image queries: index 1 and 2 along each axis (0 is no shift)
    sx1 = sx2 = sy1 = sy2 = 0.0
    nsx = 1
    nsy = 1
    if periodic:
        span = qrad + fpar[F_REACH]
        nsx, sx1, sx2 = image_shifts(pcx, span, fpar[F_XMIN], fpar[F_XMAX])
        nsy, sy1, sy2 = image_shifts(pcy, span, fpar[F_YMIN], fpar[F_YMAX])
    gnx = ipar[I_GNX]
    found = w.found
    found_q = w.found_q
    # int(np.int64(0)) rather than 0 here and wherever a counter starting at a
    # constant (or a constant flag) reaches a compiled call: numba would first type
    # the call with the literal 0 and compile a specialisation of the callee that no
    # run uses; the int() keeps the type checker's view an int
    nf = int(np.int64(0))
    stamp = s.stamp
    # the candidate's neighbour list, nearest first, holds every interferer of a
    # new particle whose reach is at most the lists' cap: read it up to the gap
    # beyond which none can interfere; otherwise (and for a dropped list) search the grid
    row = s.nb_row[pk] if ipar[I_NBLISTS] == 1 else -1
    lists = row >= 0 and s.nb_n[row] >= 0 and s.nb_reach[i] <= fpar[F_NBCAP]
    if lists:
        cnt = s.nb_n[row]
        if cnt > found.shape[0]:
            found = np.empty(cnt, dtype=np.int64)
        lgap = s.nb_reach[pk] + 2.0 * s.nb_reach[i]
        stop = lgap + GAP_SLACK * (lgap + 2.0 * fpar[F_REACH])
        if periodic and cnt > found_q.shape[0]:
            found_q = np.empty(cnt, dtype=np.int64)
        for e in range(cnt):
            if s.nb_gap[row, e] > stop:
                break
            o = s.nb_o[row, e]
            ddx = s.nb_dx[row, e]
            ddy = s.nb_dy[row, e]
            if _interferes(ddx * ddx + ddy * ddy, rpk, rad[o], ri2, tau_mode, tau):
                if periodic:
                    # an entry is an image one period away: the grid search finds it
                    # only in the query about pk's image on that side, if it makes it
                    qs = image_query(s.nb_img[row, e], nsx, sx1, sx2, nsy, sy1, sy2)
                    if qs < 0:
                        continue
                    found_q[nf] = qs
                found[nf] = o
                nf += 1
    # the grid search counts past a full buffer and then runs again into one
    # large enough: a buffer replaced inside the loops would cost a pair of
    # reference counts at every particle visited
    cap = found.shape[0]
    while not lists:
        nf = int(np.int64(0))
        for qs in range(nsx * nsy):
            token = ipar[I_STAMP] + 1
            ipar[I_STAMP] = token
            qcx = pcx
            qcy = pcy
            if qs == 0:
                stamp[pk] = token
            else:
                qx = qs % nsx
                qy = qs // nsx
                qcx += image_shift(qx, sx1, sx2)
                qcy += image_shift(qy, sy1, sy2)
            ia, ib = cell_range(qcx - qrad, qcx + qrad, fpar[F_GX0], fpar[F_GCELL], ipar[I_GNX])
            ja, jb = cell_range(qcy - qrad, qcy + qrad, fpar[F_GY0], fpar[F_GCELL], ipar[I_GNY])
            for gj in range(ja, jb + 1):
                for gi in range(ia, ib + 1):
                    e = s.head[gj * gnx + gi]
                    while e >= 0:
                        o = s.item[e]
                        e = s.nxt[e]
                        if stamp[o] == token:
                            continue
                        stamp[o] = token
                        ddx = cx[o] - qcx
                        ddy = cy[o] - qcy
                        d2 = ddx * ddx + ddy * ddy
                        if _interferes(d2, rpk, rad[o], ri2, tau_mode, tau):
                            if nf < cap:
                                found[nf] = o
                                if periodic:
                                    found_q[nf] = qs
                            nf += 1
        if nf <= cap:
            break
        cap = 2 * nf
        found = np.empty(cap, dtype=np.int64)
        found_q = np.empty(cap if periodic else 0, dtype=np.int64)

    if rounded is not None and ipar[I_DISKS] == 1:
        # disks only: every envelope is a circle about a centre, so none is built.
        # A centre is the offset between the two particles plus the envelope's
        # single vertex, the same arithmetic as through the envelopes below
        # (and rounded_arcs), so the arcs are the same bit for bit
        grho = g.rho
        gvx = g.vx
        gvy = g.vy
        goff = g.offsets
        q0x = w.rx[0]
        q0y = w.ry[0]
        fs = w.fs
        if nf <= fs.shape[1]:
            ocx = fs[0]
            ocy = fs[1]
            orho = fs[2]
            box = fs[3]
        else:
            ocx = np.empty(nf)
            ocy = np.empty(nf)
            orho = np.empty(nf)
            box = np.empty(4)
        for f in range(nf):
            o = found[f]
            odx_ = cx[o] - pcx
            ody_ = cy[o] - pcy
            if periodic and found_q[f] > 0:
                qx = found_q[f] % nsx
                qy = found_q[f] // nsx
                odx_ -= image_shift(qx, sx1, sx2)
                ody_ -= image_shift(qy, sy1, sy2)
            ocx[f] = odx_ + (gvx[goff[o]] + q0x)
            ocy[f] = ody_ + (gvy[goff[o]] + q0y)
            orho[f] = grho[o] + grho[i]
        box[0], box[1], box[2], box[3] = centre_box(i, g, fpar)
        inner = s.walls[0, 2] - grho[i] if mode == WALL_CIRCLE else 0.0
        arcs = disk_arcs(
            grho[pk] + grho[i], pcx, pcy, nf, ocx, ocy, orho,
            mode, s.walls, box, w.woff, w.rx, w.ry, inner, fs,
        )  # fmt: skip
        if arcs.shape[0] == 0 and ipar[I_BOUND] != BOUND_OFF and nf >= 2:
            for f in range(nf):
                orho[f] = grho[found[f]]
            # handed to the partner (BOUND_POST, the calling thread only) unless its
            # ring is full; the bound is the same number either way
            if ipar[I_BOUND] != BOUND_POST or not post_bound(
                s.bq, s.bqf, pk, grho[pk], grho[i], nf, ocx, ocy, orho
            ):
                bound = disk_bound(grho[pk], grho[i], fpar[F_RMIN], nf, ocx, ocy, orho, fs)
                if bound < s.shut[pk]:
                    s.shut[pk] = bound
        return arcs

    wx = w.wx
    wy = w.wy
    n = _envelope(pk, mq, g, w, wx, wy, w.wex, w.wey)

    # ---- interferer envelopes (cached per new particle), relative to their centres
    ncache = w.cache_n.shape[0]
    if nf > ncache:
        width = w.cache_x.shape[1]
        ox = np.empty((nf, width))
        oy = np.empty((nf, width))
        oex = np.empty((nf, width))
        oey = np.empty((nf, width))
        on = np.empty(nf, dtype=np.int64)
        orad = np.empty(nf)
    else:
        ox = w.cache_x
        oy = w.cache_y
        oex = w.cache_ex
        oey = w.cache_ey
        on = w.cache_n
        orad = w.cache_rad
        if ipar[I_CUSED] + nf > ncache:
            ipar[I_GEN] += 1
            ipar[I_CUSED] = 0
    gen = ipar[I_GEN]
    # sharp polygons take their per-interferer arrays from the thread's scratch: the
    # slots overwrite found_q, each entry after it is read; ilo and ihi hold an edge's
    # covered intervals. The rounded path (compiled apart) keeps arrays of its own
    fs = w.fs
    scratch = rounded is None and nf + 2 <= fs.shape[1] and nf <= found_q.shape[0]
    if scratch:
        slot = found_q
        odx = fs[0]
        ody = fs[1]
    else:
        slot = np.empty(nf, dtype=np.int64)
        odx = np.empty(nf)
        ody = np.empty(nf)
    for f in range(nf):
        o = found[f]
        odx[f] = cx[o] - pcx
        ody[f] = cy[o] - pcy
        if periodic and found_q[f] > 0:
            qx = found_q[f] % nsx
            qy = found_q[f] // nsx
            odx[f] -= image_shift(qx, sx1, sx2)
            ody[f] -= image_shift(qy, sy1, sy2)
        if nf <= ncache:
            if w.ckey[o] == gen:
                slot[f] = w.cslot[o]
                continue
            sl = ipar[I_CUSED]
            ipar[I_CUSED] = sl + 1
            w.ckey[o] = gen
            w.cslot[o] = sl
        else:
            sl = f
        slot[f] = sl
        on[sl] = _envelope(o, mq, g, w, ox[sl], oy[sl], oex[sl], oey[sl])
        rr = 0.0
        for j in range(on[sl]):
            d2 = ox[sl, j] * ox[sl, j] + oy[sl, j] * oy[sl, j]
            if d2 > rr:
                rr = d2
        orad[sl] = math.sqrt(rr)

    if rounded is not None:
        orho = np.empty(nf)
        for f in range(nf):
            orho[f] = g.rho[found[f]] + g.rho[i]
        box = np.empty(4)
        box[0], box[1], box[2], box[3] = centre_box(i, g, fpar)
        inner = s.walls[0, 2] - g.rho[i] if mode == WALL_CIRCLE else 0.0
        others = RoundedInterferers(nf, slot, odx, ody, ox, oy, oex, oey, on, orad, orho)
        wl = RoundedWalls(mode, s.walls, box, w.woff, w.rx, w.ry, mq, inner)
        return rounded_arcs(wx, wy, w.wex, w.wey, n, g.rho[pk] + g.rho[i], pcx, pcy, others, wl)

    # ---- walls: closed box of admissible centres, relative to pk
    bx0, bx1, by0, by1 = centre_box(i, g, fpar)
    bx0 -= pcx
    bx1 -= pcx
    by0 -= pcy
    by1 -= pcy

    va = w.va
    have_angles = False
    if scratch:
        ilo = fs[2]
        ihi = fs[3]
    else:
        ilo = np.empty(nf + 2)
        ihi = np.empty(nf + 2)
    arcs = va[:0].reshape((0, 2))  # no arcs yet: an empty view, not an allocation
    na = 0
    joined_vertex = -1  # the last arc ends exactly at this envelope vertex
    first_at_zero = False
    cur = -1  # an interferer whose open envelope contains the start vertex of edge j
    for j in range(n):
        if cut is not None and load_acquire(cut[0], cut[1]) >= cut[2]:
            return arcs[:0]
        j2 = j + 1 if j + 1 < n else 0
        ax = wx[j]
        ay = wy[j]
        bx = wx[j2]
        by = wy[j2]
        dx = bx - ax
        dy = by - ay
        # fast path: both ends strictly inside one interferer's envelope cover the edge
        full = False
        if cur >= 0:
            # unsigned slot numbers: no wraparound test at each access below
            us = np.uint64(slot[cur])
            full = inside_open(
                bx - odx[cur], by - ody[cur], ox[us], oy[us], oex[us], oey[us], on[us]
            )
        mx = ax + 0.5 * dx
        my = ay + 0.5 * dy
        half = 0.5 * math.sqrt(dx * dx + dy * dy)
        if not full:
            cur = -1
            for f in range(nf):
                gx = odx[f] - mx
                gy = ody[f] - my
                us = np.uint64(slot[f])
                # both ends within the circumcircle need |mid - c|^2 <= R^2 - half^2; the
                # slack keeps rounding from rejecting an envelope that holds both ends,
                # so that coverage does not depend on which interferer the fast path kept
                if gx * gx + gy * gy + half * half > orad[us] * orad[us] * CIRCLE_SLACK:
                    continue
                if inside_open(
                    ax - odx[f], ay - ody[f], ox[us], oy[us], oex[us], oey[us], on[us]
                ) and inside_open(
                    bx - odx[f], by - ody[f], ox[us], oy[us], oex[us], oey[us], on[us]
                ):
                    full = True
                    cur = f
                    break
        if full:
            continue
        ni = 0
        if mode == WALL_BOX:
            slo, shi = clip_closed_box(ax, ay, dx, dy, bx0, bx1, by0, by1)
        else:
            slo, shi = _clip_walls(mode, ax + pcx, ay + pcy, dx, dy, i, mq, g, s, w)
        if slo > shi:
            continue
        if slo > 0.0:
            ilo[ni] = -1.0
            ihi[ni] = slo
            ni += 1
        if shi < 1.0:
            ilo[ni] = shi
            ihi[ni] = 2.0
            ni += 1
        for f in range(nf):
            gx = odx[f] - mx
            gy = ody[f] - my
            us = np.uint64(slot[f])
            lim = orad[us] + half
            if gx * gx + gy * gy >= lim * lim:
                continue
            lo, hi = clip_open_interior(
                ax - odx[f], ay - ody[f], dx, dy, ox[us], oy[us], oex[us], oey[us], on[us]
            )
            if lo < hi and hi > 0.0 and lo < 1.0:
                if lo <= 0.0 and hi >= 1.0:
                    full = True
                    break
                ilo[ni] = lo
                ihi[ni] = hi
                ni += 1
        if full:
            continue
        # sort covered intervals by their lower end (insertion sort; few items)
        for a in range(1, ni):
            kl = ilo[a]
            kh = ihi[a]
            b = a - 1
            while b >= 0 and ilo[b] > kl:
                ilo[b + 1] = ilo[b]
                ihi[b + 1] = ihi[b]
                b -= 1
            ilo[b + 1] = kl
            ihi[b + 1] = kh
        pos = 0.0
        for a in range(ni + 1):
            if pos >= 1.0:
                break
            if a < ni:
                lo = ilo[a]
                hi = ihi[a]
                if lo <= pos:
                    if hi > pos:
                        pos = hi
                    continue
                piece_lo = pos
                piece_hi = lo if lo < 1.0 else 1.0
                pos = hi
            else:
                piece_lo = pos
                piece_hi = 1.0
            if piece_hi <= piece_lo:
                continue
            if not have_angles:
                _vertex_angles(wx, wy, n, va)
                have_angles = True
                arcs = np.empty((n * (nf + 3) + 1, 2))
            a0 = _angle_on_edge(wx, wy, n, va, j, piece_lo)
            a1 = _angle_on_edge(wx, wy, n, va, j, piece_hi)
            if piece_lo == 0.0 and joined_vertex == j and na > 0:
                arcs[na - 1, 1] = a1
            else:
                if piece_lo == 0.0 and j == 0:
                    first_at_zero = True
                arcs[na, 0] = a0
                arcs[na, 1] = a1
                na += 1
            joined_vertex = j + 1 if piece_hi == 1.0 else -1
    return close_arcs(arcs, na, first_at_zero and joined_vertex == n, va[n] - va[0])


@numba.njit(cache=True, inline="always")
def shut_for(i: int, pk: int, rho: FloatArray, shut: FloatArray, rounded: object) -> bool:
    """Whether a disk bound shows that candidate ``pk`` has no arc for disk ``i``.

    ``rho`` and ``shut`` are ``Outlines.rho`` and ``Packed.shut``. See
    :mod:`~regopack.plugins.inserters.available_arc.disk_bound`; compiled away in a
    scene of sharp polygons (``rounded`` is ``None``).
    """
    return rounded is not None and rho[i] >= shut[pk]


@numba.njit(cache=True)
def find_site(
    i: int, start: int, mq: int, g: Outlines, s: Packed, w: Work, rounded: object = None
) -> tuple[int, FloatArray]:
    """First candidate (insertion index ``>= start``) with available arcs for particle ``i``.

    Candidates without arcs get ``rmin = r_i``. Returns ``(k, arcs)``, or
    ``(-1, empty)`` when no candidate accepts the particle.
    """
    empty = np.empty((0, 2))
    # a particle that fits nowhere between the walls still goes through the
    # candidates (SPEC §4.7): each is analysed, has no arc, and records rmin
    r = g.req[i]
    t = s.fpar[F_T]
    ipar = s.ipar
    leaves = ipar[I_LEAVES]
    count = ipar[I_COUNT]
    linear = ipar[I_LINEAR] == 1
    c = screen(s)
    k = next_candidate(c, start, count, r, t, linear)
    while k >= 0:
        ipar[I_ANALYSES] += 1
        pk = s.order[k]
        if shut_for(i, pk, g.rho, s.shut, rounded):
            arcs = empty
        else:
            arcs = analyze_candidate(pk, i, mq, g, s, w, rounded)
        if arcs.shape[0] > 0:
            return k, arcs
        ipar[I_EMPTY] += 1
        tree_set(s.tree, leaves, k, r)
        k = next_candidate(c, k + 1, count, r, t, linear)
    return -1, empty


class Screen(NamedTuple):
    """The arrays that the candidate search reads and hides candidates in.

    :func:`next_candidate` and :func:`hide_candidate` take this or the whole
    :class:`Packed` (the same fields). A compiled call counts a reference to
    each array it receives, on entry and again on return, so the searches pass
    these five rather than the packing's twenty-six for every candidate.
    """

    tree: FloatArray
    ipar: IntArray
    home: IntArray
    hnext: IntArray
    hhead: IntArray


@numba.njit(cache=True, inline="always")
def screen(s: Packed) -> Screen:
    """Return the search's arrays of packing ``s``."""
    return Screen(s.tree, s.ipar, s.home, s.hnext, s.hhead)


@numba.njit(cache=True)
def hide_candidate(k: int, value: float, s: Packed | Screen) -> None:
    """Hide candidate ``k`` from the search, among its strip's hidden candidates.

    Its screening radius becomes ``value``, not positive, which no particle passes.
    """
    tree_set(s.tree, s.ipar[I_LEAVES], k, value)
    if s.hnext[k] == NOT_LISTED:  # never twice on a list (a cycle would never end)
        st = s.home[k]
        s.hnext[k] = s.hhead[st]
        s.hhead[st] = k


@numba.njit(cache=True)
def next_candidate(
    s: Packed | Screen, start: int, count: int, r: float, t: float, linear: bool
) -> int:
    """Return the first candidate from ``start`` on that passes screening in the strip searched.

    As :func:`~regopack.plugins.inserters.available_arc.candidates.first_candidate`, within the
    strip ``ipar[I_STRIP]`` (every candidate when it is -1).

    The sweep hides the other strips' candidates when it changes strip, so the search
    should meet none; one met all the same is hidden with its radius negated, to be
    shown again when its strip is searched (the sweep's ``_show``), and the search
    goes on past it.
    """
    leaves = s.ipar[I_LEAVES]
    k = first_candidate(s.tree, leaves, start, count, r, t, linear)
    cur = s.ipar[I_STRIP]
    if cur < 0:
        return k
    while k >= 0 and s.home[k] != cur:
        hide_candidate(k, -s.tree[leaves + k], s)
        k = first_candidate(s.tree, leaves, k + 1, count, r, t, linear)
    return k


@numba.njit(cache=True)
def reject(k: int, r: float, s: Packed) -> None:
    """Record that candidate ``k`` cannot take a particle of radius ``r``."""
    tree_set(s.tree, s.ipar[I_LEAVES], k, r)


@numba.njit(cache=True)
def locate(
    pk: int,
    i: int,
    mq: int,
    angle: float,
    g: Outlines,
    s: Packed,
    w: Work,
    rounded: object = None,
) -> tuple[float, float]:
    """Return where the ray from ``pk``'s centre at polar ``angle`` meets the envelope.

    The envelope is that of candidate ``pk`` and new particle ``i``;
    ``rounded`` as in :func:`analyze_candidate`.
    """
    wx = w.wx
    wy = w.wy
    n = _envelope(pk, mq, g, w, wx, wy, w.wex, w.wey)
    if rounded is not None:
        x, y = rounded_locate(wx, wy, w.wex, w.wey, n, g.rho[pk] + g.rho[i], angle)
        return s.cx[pk] + x, s.cy[pk] + y
    va = w.va
    _vertex_angles(wx, wy, n, va)
    a, j = angle_slot(va, n, angle)
    j2 = j + 1 if j + 1 < n else 0
    dxr = math.cos(a)
    dyr = math.sin(a)
    ex_ = wx[j2] - wx[j]
    ey_ = wy[j2] - wy[j]
    den = dxr * ey_ - dyr * ex_
    t = 0.0
    if den != 0.0:
        t = (wx[j] * dyr - wy[j] * dxr) / den
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    return s.cx[pk] + wx[j] + t * ex_, s.cy[pk] + wy[j] + t * ey_


@numba.njit(cache=True)
def sample_angle(arcs: FloatArray, u01: float) -> float:
    """Angle at fraction ``u01`` of the total length of ``arcs`` (uniform over their union)."""
    total = 0.0
    for a in range(arcs.shape[0]):
        total += arcs[a, 1] - arcs[a, 0]
    u = u01 * total
    before = 0.0
    j = -1
    for a in range(arcs.shape[0]):
        nxt = before + (arcs[a, 1] - arcs[a, 0])
        if nxt > u:
            j = a
            break
        before = nxt
    if j < 0:  # u at the very end (rounding): the end of the last arc
        j = arcs.shape[0] - 1
        before -= arcs[j, 1] - arcs[j, 0]
    ang = arcs[j, 0] + (u - before)
    if ang < arcs[j, 0]:
        ang = arcs[j, 0]
    if ang > arcs[j, 1]:
        ang = arcs[j, 1]
    return ang


@numba.njit(cache=True)
def place_on_arcs(
    k: int,
    arcs: FloatArray,
    i: int,
    mq: int,
    g: Outlines,
    s: Packed,
    w: Work,
    rng: np.random.Generator,
    rounded: object,
) -> int:
    """Place particle ``i`` on the free ``arcs`` of candidate ``k`` (the screened search's step).

    The eta control (``fpar[F_ETA]``) shrinks the arcs first; when it leaves
    none, ``k`` records the rejection (:func:`reject`) and -1 is returned.
    Otherwise the centre lies at an angle drawn uniformly on the arcs; returns
    its insertion index.
    """
    eta = s.fpar[F_ETA]
    if eta != 0.0:
        arcs = eta_shrink(arcs, eta, g.req[i], g.req[s.order[k]], rng)
        if arcs.shape[0] == 0:
            reject(k, g.req[i], s)
            return -1
    angle = sample_angle(arcs, rng.random())
    x, y = locate(s.order[k], i, mq, angle, g, s, w, rounded)
    return insert_particle(i, x, y, g, s)


@numba.njit(cache=True)
def place_screened(
    i: int,
    mq: int,
    g: Outlines,
    s: Packed,
    w: Work,
    rng: np.random.Generator,
    rounded: object,
) -> int:
    """Place particle ``i`` at the first candidate that takes it (the paper's screened search).

    Candidates whose arcs the eta control removes record the rejection and
    the search goes on. Returns the new insertion index, or -1.
    """
    start = int(np.int64(0))
    while True:
        k, arcs = find_site(i, start, mq, g, s, w, rounded)
        if k < 0:
            return -1
        placed = place_on_arcs(k, arcs, i, mq, g, s, w, rng, rounded)
        if placed >= 0:
            return placed
        start = k + 1


@numba.njit(cache=True)
def eta_shrink(
    arcs: FloatArray, eta: float, r_new: float, r_cand: float, rng: np.random.Generator
) -> FloatArray:
    """Compiled twin of the ``EtaController`` of density.eta (same draws, same result)."""
    m = arcs.shape[0]
    out = np.empty((m, 2))
    kept = 0
    scale = 2.0 * r_new / (r_cand + r_new)
    for a in range(m):
        xi = rng.random()
        d = eta + xi - 1.0
        if d < 0.0:
            d = 0.0
        delta = d / 100.0 * scale
        lo = arcs[a, 0] + delta
        hi = arcs[a, 1] - delta
        if hi > lo:
            out[kept, 0] = lo
            out[kept, 1] = hi
            kept += 1
    return out[:kept]


@numba.njit(cache=True)
def _inner_centre(i: int, g: Outlines, s: Packed) -> tuple[bool, float, float]:
    """Find a centre for particle ``i`` when the domain's centre does not fit it.

    In a polygon: the mean of the corners of the polygon of admissible centres
    (the domain's box clipped by every wall moved in by the particle's
    support). In a circle: the centre less the middle of the particle's box,
    which centres the particle's box on the circle's centre.
    """
    fpar = s.fpar
    mode = s.ipar[I_WALLMODE]
    a = g.offsets[i]
    b = g.offsets[i + 1]
    x = fpar[F_CX]
    y = fpar[F_CY]
    if mode == WALL_HALFPLANES:
        k = s.walls.shape[0]
        off = np.empty(k)
        particle_offsets(g.vx, g.vy, a, b, s.walls, off)
        px = np.empty(k + 5)
        py = np.empty(k + 5)
        qx = np.empty(k + 5)
        qy = np.empty(k + 5)
        px[0], py[0] = fpar[F_XMIN], fpar[F_YMIN]
        px[1], py[1] = fpar[F_XMAX], fpar[F_YMIN]
        px[2], py[2] = fpar[F_XMAX], fpar[F_YMAX]
        px[3], py[3] = fpar[F_XMIN], fpar[F_YMAX]
        count = 4
        for e in range(k):
            count = clip_halfplane(
                px, py, count, s.walls[e, 0], s.walls[e, 1], off[e] - g.rho[i], qx, qy
            )
            px, qx = qx, px
            py, qy = qy, py
            if count == 0:
                return False, x, y
        x = 0.0
        y = 0.0
        for j in range(count):
            x += px[j] / count
            y += py[j] / count
    elif mode == WALL_CIRCLE:
        x -= 0.5 * (g.box[i, 0] + g.box[i, 1])
        y -= 0.5 * (g.box[i, 2] + g.box[i, 3])
    return point_fits(x, y, g.vx, g.vy, a, b, mode, s.walls, g.rho[i]), x, y


@numba.njit(cache=True)
def place_first(i: int, g: Outlines, s: Packed, rng: np.random.Generator) -> bool:
    """Place the first particle at the domain centre (or a random feasible point).

    In a walled rectangle a centre that does not fit is moved to the nearest
    feasible one. In a polygon or circle a centre that does not fit is
    replaced by :func:`_inner_centre`; with the random option, the first of
    :data:`FIRST_RANDOM_TRIES` uniform draws in the domain's box that fits is
    taken. Otherwise the particle is not placed.
    """
    fpar = s.fpar
    mode = s.ipar[I_WALLMODE]
    random = s.ipar[I_FIRSTRANDOM] == 1
    if mode == WALL_BOX:
        x0, x1, y0, y1 = centre_box(i, g, fpar)
        if x0 > x1 or y0 > y1:
            return False
        if random:
            x = x0 + rng.random() * (x1 - x0)
            y = y0 + rng.random() * (y1 - y0)
        else:
            x = 0.5 * (fpar[F_XMIN] + fpar[F_XMAX])
            y = 0.5 * (fpar[F_YMIN] + fpar[F_YMAX])
            x = min(max(x, x0), x1)
            y = min(max(y, y0), y1)
        insert_particle(i, x, y, g, s)
        return True
    a = g.offsets[i]
    b = g.offsets[i + 1]
    if not random:
        x = fpar[F_CX]
        y = fpar[F_CY]
        if not point_fits(x, y, g.vx, g.vy, a, b, mode, s.walls, g.rho[i]):
            ok, x, y = _inner_centre(i, g, s)
            if not ok:
                return False
        insert_particle(i, x, y, g, s)
        return True
    for _ in range(FIRST_RANDOM_TRIES):
        x = fpar[F_XMIN] + rng.random() * (fpar[F_XMAX] - fpar[F_XMIN])
        y = fpar[F_YMIN] + rng.random() * (fpar[F_YMAX] - fpar[F_YMIN])
        if point_fits(x, y, g.vx, g.vy, a, b, mode, s.walls, g.rho[i]):
            insert_particle(i, x, y, g, s)
            return True
    return False


@numba.njit(cache=True)
def pack_range(
    begin: int,
    end: int,
    g: Outlines,
    s: Packed,
    w: Work,
    rng: np.random.Generator,
    rounded: object = None,
) -> int:
    """Insert particles ``begin`` to ``end - 1`` with the built-in eta rule.

    Returns how many were placed. ``rounded`` as in :func:`analyze_candidate`.

    ``fpar[F_ETA]`` is the packing control coefficient (0 draws nothing).
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    g, s, w = borrowed(g), borrowed(s), borrowed(w)
    placed = 0
    for i in range(begin, end):
        if s.ipar[I_COUNT] == 0:
            if place_first(i, g, s, rng):
                placed += 1
            continue
        mq = begin_particle(i, g, s, w)
        if place_screened(i, mq, g, s, w, rng, rounded) >= 0:
            placed += 1
    return placed
