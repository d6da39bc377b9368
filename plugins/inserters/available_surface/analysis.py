"""Compiled analysis of one candidate: interferers, their envelopes, the free surface, a centre.

:class:`SurfaceState` keeps the placed particles in flat arrays
(:class:`Solids`, :class:`Arcs`, :class:`Grid`) so that the whole analysis of
a candidate runs in one compiled call, :func:`analyse`:

1. the envelope ``E_k = P_k ⊕ (-Q)``;
2. the interferers: the placed particles (and, in a periodic box, their
   images among the 27 shifts) in the grid cells that a ball about ``c_k``
   reaches, kept when ``|c_j - c_k| < R_k + R_j + 2 R_Q`` (plus the packing
   control's margin, when there is one);
3. each interferer's envelope as half-spaces, computed once per particle
   being placed and kept in :class:`HalfspaceCache`;
4. the free surface and, when it has area, a centre drawn uniformly by area
   with three uniform numbers from the run's generator.

The order of the interferers (cells in ascending x, y, z, and in each cell
the order of insertion) is fixed, so the packing does not depend on how the
analysis is run.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.limits import derived_count
from regopack.plugins.common.kernel_random import KernelSource, uniform
from regopack.plugins.inserters.available_arc.candidates import first_candidate, tree_set
from regopack.plugins.inserters.available_surface.cap_cover import (
    COVERED,
    UNSURE,
    cover_by_vertices,
)
from regopack.plugins.inserters.available_surface.envelope import (
    EdgeArcs,
    edge_arcs,
    minkowski_envelope,
)
from regopack.plugins.inserters.available_surface.free_surface import (
    Interferers,
    free_surface,
    sample_free_point,
)
from regopack.plugins.inserters.available_surface.halfspaces import halfspaces_of_arcs
from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron
from regopack.plugins.inserters.available_surface.prism_wall import NO_WALL, wall_planes
from regopack.plugins.inserters.available_surface.spheres import (
    COVER_MARGIN,
    EPS,
    covers,
    drop_contained,
    free_arcs,
    sample_free,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SEPARATION_EPS = 1e-9
"""Relative margin of the face-plane test that drops interferers (see :func:`_separated`)."""
CERTAIN = 1e-9
"""Depth, relative to ``R``, by which a sphere analysis wants every point covered before it
takes the vertices' certificate (:func:`.cap_cover.cover_by_vertices`) for an empty answer:
far beyond the rounding of :func:`.spheres.free_arcs`, which then finds no arc either."""
FOUND, EMPTY, FULL = 1, 0, -1
"""Return codes of :func:`analyse`: a centre, no free area, the cache needs more room."""
NO_VERTICES = np.zeros((0, 3))
"""A sphere's vertices for :func:`.prism_wall.wall_planes` (none: its radius is its support)."""


class Solids(NamedTuple):
    """The population's polyhedra in flat arrays (see :func:`solid`)."""

    vertices: FloatArray
    vertex_offsets: IntArray
    normals: FloatArray
    support: FloatArray
    face_offsets: IntArray
    loops: IntArray
    loop_offsets: IntArray
    loop_starts: IntArray
    loop_start_offsets: IntArray


class Arcs(NamedTuple):
    """Edge arcs of every particle, made on first use (``done``)."""

    left: IntArray
    right: IntArray
    t: FloatArray
    u: FloatArray
    offsets: IntArray
    done: NDArray[np.bool_]


class Grid(NamedTuple):
    """Placed particles in cubic cells: per-cell lists in insertion order.

    Cell ``floor(x / cell) - origin`` per axis (cells aligned on multiples of
    ``cell``); ``dims`` counts them per axis; ``head``/``tail`` per cell and
    ``link`` per particle link the lists.
    """

    origin: IntArray
    cell: FloatArray
    dims: IntArray
    head: IntArray
    tail: IntArray
    link: IntArray


class HalfspaceCache(NamedTuple):
    """Interferer envelopes of the particle being placed, as half-space rows.

    ``stamp[j]`` is the particle whose envelope with ``P_j`` rows
    ``start[j]:start[j] + size[j]`` hold; ``fill[0]`` is the next free row.
    """

    normals: FloatArray
    support: FloatArray
    stamp: IntArray
    start: IntArray
    size: IntArray
    fill: IntArray


class Placed(NamedTuple):
    """The placed particles as an analysis reads them."""

    order: IntArray
    """The particle of each insertion index."""
    centre: FloatArray
    """``(n, 3)`` centres."""
    circum: FloatArray
    """Circumradii (radii, for spheres)."""
    reach_max: float
    """The largest circumradius placed."""


class Bounds(NamedTuple):
    """The box and the admissible centres of the particle being placed."""

    period: FloatArray
    """The box's sides when it is periodic; length 0 for a walled box."""
    lo: FloatArray
    hi: FloatArray
    adm_lo: FloatArray
    adm_hi: FloatArray
    wall: FloatArray = NO_WALL
    """A cylinder's side wall as its inscribed prism (:func:`.prism_wall.prism_wall`);
    empty for a box. ``lo``/``hi`` are then the cylinder's bounding box."""


class Screening(NamedTuple):
    """What a scan screens candidates by and records (see :func:`scan`)."""

    t: float
    radius: FloatArray
    rmin: FloatArray
    tried: IntArray
    counters: IntArray
    levels: FloatArray
    """Spheres: ascending radii at which an empty candidate is tried for shutting
    (:func:`sphere_shut`); ``levels[0]`` the population's smallest (empty: none)."""
    shut: FloatArray
    """Spheres: per candidate, the radius from which no sphere fits any more
    (:func:`sphere_shut`; ``inf``: none known)."""


def solids_of(polys: list[Polyhedron]) -> Solids:
    """Pack :class:`Polyhedron` tuples into :class:`Solids`."""

    def offsets(sizes: list[int]) -> IntArray:
        out = np.zeros(len(sizes) + 1, dtype=np.int64)
        np.cumsum(sizes, out=out[1:])
        return out

    def cat(arrays: list[NDArray[Any]], shape: tuple[int, ...], dtype: type) -> NDArray[Any]:
        return np.ascontiguousarray(np.concatenate(arrays) if arrays else np.zeros(shape, dtype))

    return Solids(
        vertices=cat([p.vertices for p in polys], (0, 3), np.float64),
        vertex_offsets=offsets([len(p.vertices) for p in polys]),
        normals=cat([p.normals for p in polys], (0, 3), np.float64),
        support=cat([p.support for p in polys], (0,), np.float64),
        face_offsets=offsets([len(p.normals) for p in polys]),
        loops=cat([p.face_vertices for p in polys], (0,), np.int64),
        loop_offsets=offsets([len(p.face_vertices) for p in polys]),
        loop_starts=cat([p.face_offsets for p in polys], (0,), np.int64),
        loop_start_offsets=offsets([len(p.face_offsets) for p in polys]),
    )


def arcs_for(solids: Solids) -> Arcs:
    """Room for every particle's edge arcs (``E = loops / 2`` edges each)."""
    n = solids.vertex_offsets.shape[0] - 1
    offsets = solids.loop_offsets // 2
    e = int(offsets[-1])
    return Arcs(
        left=np.zeros(e, dtype=np.int64),
        right=np.zeros(e, dtype=np.int64),
        t=np.zeros((e, 3)),
        u=np.zeros((e, 6)),
        offsets=np.ascontiguousarray(offsets),
        done=np.zeros(n, dtype=np.bool_),
    )


MAX_GRID_CELLS = 1 << 24
"""Cells a neighbour grid may have whatever the particle count (128 MiB of lists)."""
GRID_CELLS_PER_PARTICLE = 8
"""Cells a neighbour grid may have per particle beyond :data:`MAX_GRID_CELLS`."""


def grid_for(lo: FloatArray, hi: FloatArray, cell: float, n: int) -> Grid:
    """Return an empty grid of cells of side ``cell`` over the box ``[lo, hi]``.

    Raises
    ------
    regopack.base.limits.LimitError
        When the box holds more than ``max(MAX_GRID_CELLS,
        GRID_CELLS_PER_PARTICLE * n)`` cells (or no finite number of them).
    """
    lo_cells = np.floor(np.asarray(lo, dtype=np.float64) / cell)
    hi_cells = np.floor(np.asarray(hi, dtype=np.float64) / cell)
    spans = hi_cells - lo_cells + 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.prod(spans))
    if not np.all(np.isfinite(lo_cells) & np.isfinite(hi_cells)):
        total = math.inf
    cells = derived_count(
        total,
        "cells of the neighbour grid (box sides / twice the largest circumradius)",
        max(MAX_GRID_CELLS, GRID_CELLS_PER_PARTICLE * n),
        field="domain",
        hint="give a box nearer the particles' size or more particles",
    )
    first = lo_cells.astype(np.int64)
    dims = spans.astype(np.int64)
    return Grid(
        origin=first,
        cell=np.array([cell]),
        dims=dims,
        head=np.full(cells, -1, dtype=np.int64),
        tail=np.full(cells, -1, dtype=np.int64),
        link=np.full(max(n, 1), -1, dtype=np.int64),
    )


def cache_for(n: int, rows: int) -> HalfspaceCache:
    """Return an empty half-space cache of ``rows`` rows."""
    return HalfspaceCache(
        normals=np.zeros((rows, 3)),
        support=np.zeros(rows),
        stamp=np.full(max(n, 1), -1, dtype=np.int64),
        start=np.zeros(max(n, 1), dtype=np.int64),
        size=np.zeros(max(n, 1), dtype=np.int64),
        fill=np.zeros(1, dtype=np.int64),
    )


@numba.njit(cache=True)
def grown(cache: HalfspaceCache) -> HalfspaceCache:
    """Return a half-space cache of twice the rows, holding ``cache``'s rows and records."""
    rows = cache.support.shape[0]
    normals = np.zeros((2 * rows, 3))
    support = np.zeros(2 * rows)
    normals[:rows] = cache.normals
    support[:rows] = cache.support
    return HalfspaceCache(
        normals, support, cache.stamp.copy(), cache.start.copy(), cache.size.copy(),
        cache.fill.copy(),
    )  # fmt: skip


@numba.njit(cache=True)
def solid(s: Solids, j: int) -> Polyhedron:
    """Particle ``j`` as a :class:`Polyhedron` (views of the flat arrays)."""
    return Polyhedron(
        s.vertices[s.vertex_offsets[j] : s.vertex_offsets[j + 1]],
        s.normals[s.face_offsets[j] : s.face_offsets[j + 1]],
        s.support[s.face_offsets[j] : s.face_offsets[j + 1]],
        s.loops[s.loop_offsets[j] : s.loop_offsets[j + 1]],
        s.loop_starts[s.loop_start_offsets[j] : s.loop_start_offsets[j + 1]],
    )


@numba.njit(cache=True)
def arcs_of(a: Arcs, s: Solids, j: int) -> EdgeArcs:
    """Edge arcs of particle ``j``, made on first use."""
    e0 = a.offsets[j]
    e1 = a.offsets[j + 1]
    if not a.done[j]:
        made = edge_arcs(solid(s, j), 1.0)
        a.left[e0:e1] = made.left
        a.right[e0:e1] = made.right
        a.t[e0:e1] = made.t
        a.u[e0:e1] = made.u
        a.done[j] = True
    return EdgeArcs(a.left[e0:e1], a.right[e0:e1], a.t[e0:e1], a.u[e0:e1])


@numba.njit(cache=True)
def _cell(g: Grid, x: float, axis: int) -> int:
    return int(math.floor(x / g.cell[0]) - g.origin[axis])


@numba.njit(cache=True)
def grid_add(g: Grid, j: int, x: FloatArray) -> None:
    """File particle ``j`` at ``x`` (inside the box) at the end of its cell's list."""
    ix = min(max(_cell(g, x[0], 0), 0), g.dims[0] - 1)
    iy = min(max(_cell(g, x[1], 1), 0), g.dims[1] - 1)
    iz = min(max(_cell(g, x[2], 2), 0), g.dims[2] - 1)
    c = (ix * g.dims[1] + iy) * g.dims[2] + iz
    g.link[j] = -1
    if g.tail[c] < 0:
        g.head[c] = j
    else:
        g.link[g.tail[c]] = j
    g.tail[c] = j


@numba.njit(cache=True)
def _gather(
    g: Grid,
    p: FloatArray,
    reach: float,
    shift: FloatArray,
    ck: FloatArray,
    pk: int,
    i: int,
    centre: FloatArray,
    circum: FloatArray,
    near: IntArray,
    at: FloatArray,
    count: int,
    margin: float,
) -> int:
    """Append the interferers found in the cells about ``p`` (their images at ``+ shift``).

    Returns the new count; the arrays receive those that fit in them (the
    caller grows them and gathers again when the count is larger). A loop
    that may replace an array it writes reloads it at every step: never
    replacing them here makes the loop four times faster.
    """
    room = near.shape[0]
    lo0 = max(_cell(g, p[0] - reach, 0), 0)
    lo1 = max(_cell(g, p[1] - reach, 1), 0)
    lo2 = max(_cell(g, p[2] - reach, 2), 0)
    hi0 = min(_cell(g, p[0] + reach, 0), g.dims[0] - 1)
    hi1 = min(_cell(g, p[1] + reach, 1), g.dims[1] - 1)
    hi2 = min(_cell(g, p[2] + reach, 2), g.dims[2] - 1)
    for ix in range(lo0, hi0 + 1):
        for iy in range(lo1, hi1 + 1):
            for iz in range(lo2, hi2 + 1):
                j = g.head[(ix * g.dims[1] + iy) * g.dims[2] + iz]
                while j >= 0:
                    dx = centre[j, 0] + shift[0] - ck[0]
                    dy = centre[j, 1] + shift[1] - ck[1]
                    dz = centre[j, 2] + shift[2] - ck[2]
                    d2 = dx * dx + dy * dy + dz * dz
                    lim = circum[pk] + circum[j] + 2.0 * circum[i] + margin
                    if d2 < lim * lim and not (j == pk and d2 == 0.0):
                        if count < room:
                            near[count] = j
                            at[count, 0] = centre[j, 0] + shift[0]
                            at[count, 1] = centre[j, 1] + shift[1]
                            at[count, 2] = centre[j, 2] + shift[2]
                        count += 1
                    j = g.link[j]
    return count


@numba.njit(cache=True)
def _gather_all(
    g: Grid,
    p: FloatArray,
    reach: float,
    shift: FloatArray,
    ck: FloatArray,
    pk: int,
    i: int,
    centre: FloatArray,
    circum: FloatArray,
    near: IntArray,
    at: FloatArray,
    count: int,
    margin: float,
) -> tuple[int, IntArray, FloatArray]:
    """:func:`_gather`, growing the arrays and gathering again until they hold every one."""
    found = _gather(g, p, reach, shift, ck, pk, i, centre, circum, near, at, count, margin)
    if found > near.shape[0]:
        size = max(found, 2 * near.shape[0])
        grown = np.empty(size, dtype=np.int64)
        grown[:count] = near[:count]
        grown_at = np.empty((size, 3))
        grown_at[:count] = at[:count]
        near = grown
        at = grown_at
        found = _gather(g, p, reach, shift, ck, pk, i, centre, circum, near, at, count, margin)
    return found, near, at


@numba.njit(cache=True)
def _interferers(
    g: Grid, pk: int, i: int, placed: Placed, bounds: Bounds, margin: float
) -> tuple[int, IntArray, FloatArray]:
    """Placed particles (or periodic images) that pass the circumradius test with ``pk``.

    ``|c_j - c_k| < R_k + R_j + 2 R_Q + margin``: with the packing control's
    margin, a particle that the new one could come closer to than the margin
    interferes too. In a periodic box the images are those one period away
    (27), or more in a box thinner than that reach.
    """
    _, centre, circum, reach_max = placed
    period, lo, hi = bounds.period, bounds.lo, bounds.hi
    ck = centre[pk]
    reach = circum[pk] + reach_max + 2.0 * circum[i] + margin
    near = np.empty(64, dtype=np.int64)
    at = np.empty((64, 3))
    # int(np.int64(0)), not 0: a literal 0 would compile a second specialization of _gather
    count = int(np.int64(0))
    if period.shape[0] == 0:
        return _gather_all(
            g, ck, reach, np.zeros(3), ck, pk, i, centre, circum, near, at, count, margin
        )
    # the centres lie in the box, less than a period apart along each axis: images
    # up to ceil(reach / period) periods away (one, unless the box is thinner than
    # the reach) hold every interferer
    mx = max(1, math.ceil(reach / period[0]))
    my = max(1, math.ceil(reach / period[1]))
    mz = max(1, math.ceil(reach / period[2]))
    shift = np.empty(3)
    for sx in range(-mx, mx + 1):
        for sy in range(-my, my + 1):
            for sz in range(-mz, mz + 1):
                shift[0] = sx * period[0]
                shift[1] = sy * period[1]
                shift[2] = sz * period[2]
                skip = False
                for ax in range(3):
                    pa = ck[ax] - shift[ax]
                    if pa + reach < lo[ax] or pa - reach > hi[ax]:
                        skip = True
                if skip:
                    continue
                p = ck - shift
                count, near, at = _gather_all(
                    g, p, reach, shift, ck, pk, i, centre, circum, near, at, count, margin
                )
    return count, near, at


@numba.njit(cache=True)
def _sphere_caps(
    ck: FloatArray,
    big_r: float,
    r: float,
    count: int,
    near: IntArray,
    at: FloatArray,
    circum: FloatArray,
    wall_lo: FloatArray,
    wall_hi: FloatArray,
    planes: FloatArray,
    margin: float,
    tau: float,
    caps: FloatArray,
) -> int:
    """Fill ``caps`` for a sphere of radius ``r`` touching one of ``big_r - r`` at ``ck``.

    Interferers ``near[:count]`` at ``at``; the centre must stay within
    ``wall_lo``/``wall_hi`` (infinite: no wall) and on the inner side of
    ``planes`` (rows ``n, b``: ``n · x <= b``). Returns the number of caps,
    or -1 when one of them holds the whole sphere (but a point).
    """
    nc = int(np.int64(0))  # not a literal 0 (second compilations of free_arcs, sample_free)
    for m in range(count):
        dx = at[m, 0] - ck[0]
        dy = at[m, 1] - ck[1]
        dz = at[m, 2] - ck[2]
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        rho = circum[near[m]] + r + margin
        h = (big_r * big_r + dist * dist - rho * rho) / (2.0 * dist)
        if h >= big_r - tau:
            continue  # the ball misses the sphere, or touches it
        if h <= -big_r + tau:
            return -1  # it holds the whole sphere (but a point)
        caps[nc, 0] = dx / dist
        caps[nc, 1] = dy / dist
        caps[nc, 2] = dz / dist
        caps[nc, 3] = h
        nc += 1
    for ax in range(3):
        for side in (-1.0, 1.0):
            bound = wall_lo[ax] + margin if side < 0 else wall_hi[ax] - margin
            if not math.isfinite(bound):
                continue
            h = side * (bound - ck[ax])
            if h >= big_r - tau:
                continue
            if h <= -big_r + tau:
                return -1
            caps[nc, 0] = 0.0
            caps[nc, 1] = 0.0
            caps[nc, 2] = 0.0
            caps[nc, ax] = side
            caps[nc, 3] = h
            nc += 1
    for w in range(planes.shape[0]):
        h = (
            planes[w, 3]
            - margin
            - (planes[w, 0] * ck[0] + planes[w, 1] * ck[1] + planes[w, 2] * ck[2])
        )
        if h >= big_r - tau:
            continue
        if h <= -big_r + tau:
            return -1
        caps[nc, 0] = planes[w, 0]
        caps[nc, 1] = planes[w, 1]
        caps[nc, 2] = planes[w, 2]
        caps[nc, 3] = h
        nc += 1
    return nc


@numba.njit(cache=True)
def analyse_sphere(
    k: int,
    i: int,
    count: int,
    near: IntArray,
    at: FloatArray,
    placed: Placed,
    bounds: Bounds,
    margin: float,
    rng: KernelSource,
    out: FloatArray,
) -> int:
    """:func:`analyse` for spheres (``circum`` holds their radii); see :mod:`.spheres`.

    ``near[:count]``, at ``at``, are candidate ``k``'s interferers for
    particle ``i`` with this ``margin`` (:func:`_interferers`).
    """
    order, centre, circum, _ = placed
    pk = order[k]
    ck = centre[pk]
    r = circum[i]
    big_r = circum[pk] + r
    tau = EPS * big_r
    # a facet within the margin beyond the sphere of centres comes onto it once moved in
    planes = wall_planes(bounds.wall, ck, big_r + margin, NO_VERTICES, r)
    caps = np.empty((count + 6 + planes.shape[0], 4))
    nc = _sphere_caps(
        ck, big_r, r, count, near, at, circum, bounds.adm_lo, bounds.adm_hi, planes, margin,
        tau, caps,
    )  # fmt: skip
    if nc < 0:
        return EMPTY
    nc = drop_contained(caps, nc, big_r, tau)
    if nc > 0 and cover_by_vertices(caps, nc, big_r, tau, CERTAIN * big_r) == COVERED:
        return EMPTY  # covered deeper than CERTAIN: free_arcs would find no arc
    arcs = free_arcs(caps, nc, big_r, tau)
    if nc > 0 and arcs.shape[0] == 0:
        return EMPTY
    ux, uy, uz = sample_free(caps, nc, arcs, big_r, tau, rng)
    out[0] = ck[0] + ux
    out[1] = ck[1] + uy
    out[2] = ck[2] + uz
    return FOUND


@numba.njit(cache=True)
def sphere_shut(
    k: int,
    i: int,
    count: int,
    near: IntArray,
    at: FloatArray,
    placed: Placed,
    bounds: Bounds,
    level: float,
) -> bool:
    """Whether no sphere of radius ``level`` or more can touch candidate ``k`` any more.

    Asked after an analysis of ``k`` for particle ``i`` (radius above
    ``level``, no packing control) found no free area: the caps that
    ``i``'s interferers (a superset of a smaller sphere's) and the walls
    a sphere of radius ``level`` keeps to cut from its sphere of centres
    must cover it with room to spare (:func:`.spheres.covers`). A smaller
    sphere fits wherever a larger one does (shrink it towards the contact
    point) and particles are only added, so every later analysis of ``k``
    for a sphere of radius ``level`` or more would find nothing. ``near[:count]``,
    at ``at``, are ``k``'s interferers for ``i`` without a margin.
    """
    order, centre, circum, _ = placed
    pk = order[k]
    ck = centre[pk]
    shift = circum[i] - level  # the admissible box of a sphere of radius level
    big_r = circum[pk] + level
    depth = COVER_MARGIN * big_r
    planes = wall_planes(bounds.wall, ck, big_r + depth, NO_VERTICES, level)
    caps = np.empty((count + 6 + planes.shape[0], 4))
    nc = _sphere_caps(
        ck, big_r, level, count, near, at, circum,
        bounds.adm_lo - shift, bounds.adm_hi + shift, planes, 0.0, -depth, caps,
    )  # fmt: skip
    # -1: a ball holds the whole sphere, deeper than depth (the tolerance given is -depth)
    if nc < 0:
        return True
    # a cap inside another shrunk by depth stays inside it when both are shrunk
    nc = drop_contained(caps, nc, big_r, depth)
    answer = cover_by_vertices(caps, nc, big_r, depth, 0.0)
    if answer == UNSURE:
        return covers(caps, nc, big_r, depth)
    return answer == COVERED


@numba.njit(cache=True)
def _face_gap(
    s: Solids, a: int, ca: FloatArray, b: int, cb: FloatArray, q: int, margin: float
) -> bool:
    """Whether a face plane of ``a`` leaves ``b`` farther than ``Q``'s width (plus ``margin``).

    Along a face normal ``n`` of ``a``, ``b`` lies beyond ``a`` by a gap; ``Q``
    can touch ``a`` and overlap ``b`` only if its own width along ``n`` (and
    the margin) spans that gap.
    """
    va = s.vertex_offsets
    for f in range(s.face_offsets[a], s.face_offsets[a + 1]):
        nx = s.normals[f, 0]
        ny = s.normals[f, 1]
        nz = s.normals[f, 2]
        far = nx * ca[0] + ny * ca[1] + nz * ca[2] + s.support[f]
        near_b = np.inf
        for v in range(va[b], va[b + 1]):
            near_b = min(
                near_b, nx * s.vertices[v, 0] + ny * s.vertices[v, 1] + nz * s.vertices[v, 2]
            )
        gap = nx * cb[0] + ny * cb[1] + nz * cb[2] + near_b - far
        if gap <= margin:
            continue
        qmin = np.inf
        qmax = -np.inf
        for v in range(va[q], va[q + 1]):
            d = nx * s.vertices[v, 0] + ny * s.vertices[v, 1] + nz * s.vertices[v, 2]
            qmin = min(qmin, d)
            qmax = max(qmax, d)
        if gap > (qmax - qmin) + margin + SEPARATION_EPS * (abs(far) + abs(gap) + qmax - qmin):
            return True
    return False


@numba.njit(cache=True)
def _separated(
    s: Solids, pk: int, j: int, i: int, ck: FloatArray, cj: FloatArray, margin: float
) -> bool:
    """Whether the envelopes ``E_k``, ``E_j`` of particle ``i`` cannot meet (:func:`_face_gap`)."""
    return _face_gap(s, pk, ck, j, cj, i, margin) or _face_gap(s, j, cj, pk, ck, i, margin)


@numba.njit(cache=True)
def analyse(
    k: int,
    i: int,
    q_arcs: EdgeArcs,
    s: Solids,
    a: Arcs,
    g: Grid,
    cache: HalfspaceCache,
    placed: Placed,
    bounds: Bounds,
    margin: float,
    rng: KernelSource,
    out: FloatArray,
) -> int:
    """Analyse candidate ``k`` (insertion index) for particle ``i``; see the module docstring.

    ``margin`` (the packing
    control) moves every interferer's facets out and the walls in by that
    length, so the free surface keeps that distance from what covers it.
    Returns :data:`FOUND` (the
    centre in ``out``), :data:`EMPTY`, or :data:`FULL` when the half-space
    cache has no room for an interferer (nothing was drawn; grow it and call
    again). With an empty ``out`` a free surface gives :data:`FOUND` with
    nothing drawn (``rng`` untouched): the answer alone. (A flag would do, but
    numba compiles a function once for each constant passed to it: every caller
    would compile the analysis again.)
    """
    order, centre, circum, _ = placed
    adm_lo, adm_hi = bounds.adm_lo, bounds.adm_hi
    pk = order[k]
    q = solid(s, i)
    ck = centre[pk]
    count, near, at = _interferers(g, pk, i, placed, bounds, margin)
    kept = 0
    for m in range(count):  # drop the interferers that a face plane keeps off E_k
        # (exact without a margin only: facets moved out by it reach farther at vertices)
        if margin > 0.0 or not _separated(s, pk, near[m], i, ck, at[m], margin):
            near[kept] = near[m]
            at[kept] = at[m]
            kept += 1
    count = kept
    rows = 0
    for m in range(count):
        j = near[m]
        if cache.stamp[j] != i:
            hn, hh = halfspaces_of_arcs(solid(s, j), arcs_of(a, s, j), q, q_arcs)
            f = cache.fill[0]
            if f + hh.shape[0] > cache.support.shape[0]:
                return FULL
            cache.normals[f : f + hh.shape[0]] = hn
            cache.support[f : f + hh.shape[0]] = hh
            cache.stamp[j] = i
            cache.start[j] = f
            cache.size[j] = hh.shape[0]
            cache.fill[0] = f + hh.shape[0]
        rows += cache.size[j]
    normals = np.empty((rows, 3))
    support = np.empty(rows)
    offsets = np.zeros(count + 1, dtype=np.int64)
    radii = np.empty(count)
    r = 0
    for m in range(count):
        j = near[m]
        c0 = cache.start[j]
        for h in range(cache.size[j]):
            normals[r, 0] = cache.normals[c0 + h, 0]
            normals[r, 1] = cache.normals[c0 + h, 1]
            normals[r, 2] = cache.normals[c0 + h, 2]
            support[r] = cache.support[c0 + h] + margin
            r += 1
        offsets[m + 1] = r
        radii[m] = circum[j] + circum[i] + margin
    inter = Interferers(normals, support, offsets, at[:count].copy(), radii)
    envelope = minkowski_envelope(solid(s, pk), q)
    # a facet within the margin beyond the envelope comes onto it once moved in
    planes = wall_planes(bounds.wall, ck, circum[pk] + circum[i] + margin, q.vertices, 0.0)
    if margin > 0.0:
        adm_lo = adm_lo + margin
        adm_hi = adm_hi - margin
        for w in range(planes.shape[0]):
            planes[w, 3] -= margin
    surface = free_surface(envelope, ck.copy(), inter, adm_lo, adm_hi, planes)
    if surface.area > 0.0:
        if out.shape[0] == 0:
            return FOUND
        u1 = uniform(rng)  # three uniforms in the order of rng.random(3)
        u2 = uniform(rng)
        u3 = uniform(rng)
        x = sample_free_point(surface, u1, u2, u3)
        out[0] = x[0]
        out[1] = x[1]
        out[2] = x[2]
        return FOUND
    return EMPTY


@numba.njit(cache=True)
def eta_margin(eta: float, xi: float, r: float) -> float:
    """Margin of the packing control: ``max(0, eta + xi - 1) / 100`` of the diameter ``2 r``.

    The 2D control trims each free arc by ``delta = max(0, eta + xi - 1) / 100 *
    2 r / (r_k + r)`` radians at both ends; on an envelope of equivalent
    radius ``r_k + r`` that is this length.
    """
    return max(0.0, eta + xi - 1.0) / 100.0 * 2.0 * r


@numba.njit(cache=True)
def _shut_below(
    k: int,
    i: int,
    g: Grid,
    count: int,
    near: IntArray,
    at: FloatArray,
    placed: Placed,
    bounds: Bounds,
    levels: FloatArray,
    t: float,
    r: float,
    shut: FloatArray,
    counters: IntArray,
) -> None:
    """After an empty analysis at ``r``: try to shut ``k`` from the next level below.

    The largest level under ``t * r`` (and not above particle ``i``'s radius,
    whose interferers :func:`sphere_shut` reads) is tried when it lies below
    ``shut[k]``; when ``k`` is shut from it, ``shut[k]`` becomes that level.
    ``near[:count]`` are the interferers the analysis gathered (``count < 0``:
    none, they are gathered when a level is tried).
    """
    lv = -1
    for m in range(levels.shape[0]):
        if levels[m] < t * r and levels[m] <= placed.circum[i]:
            lv = m
    if lv < 0:
        return
    level = levels[lv]
    if not level < shut[k]:
        return
    counters[2] += 1
    if count < 0:
        count, near, at = _interferers(g, placed.order[k], i, placed, bounds, 0.0)
    if sphere_shut(k, i, count, near, at, placed, bounds, level):
        counters[3] += 1
        shut[k] = level


@numba.njit(cache=True)
def next_screened(
    candidates: IntArray,
    m: int,
    r: float,
    t: float,
    rmin: FloatArray,
    tree: FloatArray,
    leaves: int,
) -> int:
    """Return the first position from ``m`` whose candidate passes the screening, or -1."""
    while True:
        if leaves > 0:
            m = first_candidate(tree, leaves, m, candidates.shape[0], r, t, False)
            if m < 0:
                return -1
        elif m >= candidates.shape[0]:
            return -1
        if r < t * rmin[candidates[m]]:
            return m
        m += 1


@numba.njit(cache=True)
def sphere_turn(
    k: int,
    i: int,
    first: bool,
    shutting: bool,
    t: float,
    r: float,
    g: Grid,
    placed: Placed,
    bounds: Bounds,
    levels: FloatArray,
    shut: FloatArray,
    counters: IntArray,
    rng: KernelSource,
    out: FloatArray,
) -> int:
    """Candidate ``k``'s turn for sphere ``i`` in a scan without a margin (see :func:`scan`).

    The shut tests before and after the analysis and the analysis itself:
    ``shut[k]`` is ``k``'s shutting radius (read and written), ``counters``
    those of :func:`scan` (added to). ``first``: ``k`` has not been found
    empty before (its shut test follows an empty analysis); ``shutting``:
    the scan shuts candidates. Returns :data:`FOUND` (the centre in ``out``)
    or :data:`EMPTY`.
    """
    count = -1  # interferers not gathered
    near = np.empty(0, dtype=np.int64)
    at = np.empty((0, 3))
    if not first and placed.circum[i] < shut[k]:
        count, near, at = _interferers(g, placed.order[k], i, placed, bounds, 0.0)
        if shutting:
            # a candidate found empty before: try to shut it first, and when it
            # shuts below this sphere the analysis would find nothing (certified)
            _shut_below(
                k, i, g, count, near, at, placed, bounds, levels, t, r, shut, counters
            )  # fmt: skip
    if placed.circum[i] >= shut[k]:
        counters[4] += 1  # certified: no sphere this large fits (sphere_shut)
        return EMPTY
    if count < 0:
        count, near, at = _interferers(g, placed.order[k], i, placed, bounds, 0.0)
    code = analyse_sphere(k, i, count, near, at, placed, bounds, 0.0, rng, out)
    counters[0] += 1
    if code == EMPTY:
        counters[1] += 1
        if first:
            _shut_below(
                k, i, g, count, near, at, placed, bounds, levels, t, r, shut, counters
            )  # fmt: skip
    return code


@numba.njit(cache=True)
def scan(
    candidates: IntArray,
    begin: int,
    i: int,
    screen: Screening,
    q_arcs: EdgeArcs,
    s: Solids,
    a: Arcs,
    g: Grid,
    cache: HalfspaceCache,
    placed: Placed,
    bounds: Bounds,
    eta: float,
    xi: FloatArray,
    spheres: bool,
    rng: KernelSource,
    out: FloatArray,
    tree: FloatArray,
) -> tuple[int, int]:
    """Offer particle ``i`` to ``candidates[begin:]`` in turn; stop at the first with free area.

    A candidate is analysed when ``radius[i] < t * rmin[k]`` (the fields of
    ``screen``; ``t = inf``: every one); an empty one records ``rmin[k] =
    radius[i]``; each analysed one records ``tried[k] = i`` (when ``tried`` is
    not empty). With ``eta > 0``
    each analysis first draws ``xi ~ U(0, 1)`` and keeps the free surface
    ``max(0, eta + xi - 1) / 100`` of the particle's equivalent diameter away
    from the interferers and walls (:func:`eta_margin`). With ``spheres`` the
    population is spheres (:func:`analyse_sphere`). ``counters``
    counts analyses, empty ones, shut tests, shut candidates and analyses saved;
    ``xi[0]`` holds a drawn ``xi`` across a
    :data:`FULL` return (negative: none). Returns ``(code, position)``: :data:`FOUND`
    and the candidate's position (the centre in ``out``), :data:`EMPTY` and
    ``len(candidates)``, or :data:`FULL` and the position to resume from
    after growing the cache.

    With a ``tree`` (not empty), the screening reads it instead of ``rmin``:
    a max-tree over the positions of ``candidates``
    (:func:`~regopack.plugins.inserters.available_arc.candidates.tree_set`)
    whose leaf is ``rmin_k`` for a candidate open to the search and ``-inf``
    for one hidden from it; the scan descends it to the next candidate that
    passes, so a search costs the candidates analysed, not the candidates
    listed. An empty analysis sets the leaf to ``radius[i]`` as it sets
    ``rmin``.

    For spheres without a margin, a candidate is tried for shutting from a
    level of radius below (:func:`_shut_below`, ``shut[k]``): after its
    first analysis when that finds it empty, and before every later one
    (its ``rmin`` is finite), where a shut below the sphere stands for the
    analysis. A sphere at least ``shut[k]`` large that passes the screening
    is not analysed but taken as empty, with all that an empty analysis
    does (its ``xi`` drawn, ``tried``, ``rmin`` and the leaf set).
    The screening, the random numbers and so the packing stay those of the
    analyses themselves; ``counters[4]`` counts the analyses saved.
    """
    t, radius, rmin, tried, counters, levels, shut = screen
    r = radius[i]
    leaves = tree.shape[0] // 2
    m = begin - 1
    while True:
        m = next_screened(candidates, m + 1, r, t, rmin, tree, leaves)
        if m < 0:
            break
        k = candidates[m]
        margin = 0.0
        if eta > 0.0:
            if xi[0] < 0.0:  # drawn once per analysis, kept when the cache grows
                xi[0] = uniform(rng)
            margin = eta_margin(eta, xi[0], r)
        if spheres and margin == 0.0:
            shutting = levels.shape[0] > 0 and math.isfinite(t)
            first = shutting and not math.isfinite(rmin[k])  # shut tried after the analysis
            code = sphere_turn(
                k, i, first, shutting, t, r, g, placed, bounds, levels, shut, counters, rng,
                out,
            )  # fmt: skip
        elif spheres and placed.circum[i] >= shut[k]:
            code = EMPTY  # certified by an earlier shut test (a margin only takes more away)
            counters[4] += 1
        else:
            if spheres:
                count, near, at = _interferers(g, placed.order[k], i, placed, bounds, margin)
                code = analyse_sphere(k, i, count, near, at, placed, bounds, margin, rng, out)
            else:
                code = analyse(k, i, q_arcs, s, a, g, cache, placed, bounds, margin, rng, out)
            if code == FULL:
                return FULL, m
            counters[0] += 1
            if code == EMPTY:
                counters[1] += 1
        xi[0] = -1.0
        if tried.shape[0] > 0:
            tried[k] = i
        if code == FOUND:
            return FOUND, m
        rmin[k] = r
        if leaves > 0:
            tree_set(tree, leaves, m, r)
    return EMPTY, candidates.shape[0]


@numba.njit(cache=True)
def _no_solids() -> tuple[EdgeArcs, Solids, Arcs, HalfspaceCache]:
    """Empty polyhedron arrays of the types :func:`scan` takes (spheres need none)."""
    i0 = np.zeros(0, dtype=np.int64)
    i1 = np.zeros(1, dtype=np.int64)
    f1 = np.zeros(0)
    f3 = np.zeros((0, 3))
    q_arcs = EdgeArcs(i0, i0, f3, np.zeros((0, 6)))
    s = Solids(f3, i1, f3, f1, i1, i0, i1, i0, i1)
    a = Arcs(i0, i0, f3, np.zeros((0, 6)), i1, np.zeros(0, dtype=np.bool_))
    cache = HalfspaceCache(f3, f1, i0, i0, i0, i1)
    return q_arcs, s, a, cache


@numba.njit(cache=True)
def scan_spheres(
    candidates: IntArray,
    begin: int,
    i: int,
    screen: Screening,
    g: Grid,
    placed: Placed,
    bounds: Bounds,
    eta: float,
    xi: FloatArray,
    rng: KernelSource,
    out: FloatArray,
    tree: FloatArray,
) -> tuple[int, int]:
    """:func:`scan` for spheres, with only the arrays spheres read.

    A compiled call unpacks every array it is given (about a microsecond
    each): this entry takes half of :func:`scan`'s and makes the polyhedron
    arrays, empty, inside.
    """
    q_arcs, s, a, cache = _no_solids()
    # no polyhedra (one offset): True, but known only when it runs, not a constant (numba
    # compiles a function once for each constant passed to it; Python passes a flag)
    spheres = s.face_offsets.shape[0] == 1
    return scan(
        candidates, begin, i, screen, q_arcs, s, a, g, cache, placed, bounds, eta, xi, spheres,
        rng, out, tree,
    )  # fmt: skip
