"""Random sequential addition (RSA), the classic baseline for comparing packings.

Each particle, in population order, gets up to ``max_attempts`` centres drawn
uniformly in the closed box of centres that keep it inside the domain's
bounding box (in a polygon or circle, a centre whose outline crosses the wall
counts as a rejected attempt; in a periodic rectangle, centres are drawn in the
whole domain and overlaps are tested against the periodic images), with
its outline and orientation as generated (no rotation). The first centre where
its interior meets no placed particle's interior is kept (touching is
allowed); when every attempt fails the particle is not placed and the next one
is tried.

Overlaps are decided exactly for convex polygons by the separating-axis test
over the edge normals of both outlines. Neighbours come from a uniform cell
grid over the domain: every placed particle is registered in the cells that
the bounding square of its circumscribed disk (about its reference point)
overlaps, and a trial position looks in the cells of the new particle's own
square. The whole loop runs compiled and draws its uniforms from the run's
generator: per attempt, ``x`` then ``y``.

The density controller does not apply to RSA (there are no arcs to trim); it
is accepted and ignored.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.errors import ConfigError
from regopack.geometry.domain import Domain, PlaneDomain
from regopack.geometry.population import Population
from regopack.plugins.common.walls import (
    WALL_BOX,
    WALL_PERIODIC,
    check_periodic_size,
    point_fits,
    wall_arrays,
)
from regopack.plugins.inserters.available_arc.grid import cell_range, empty_grid, grid_insert
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
)
from regopack.registry.plugin_types import InserterSpec

__all__ = [
    "PROGRESS_EVERY",
    "RandomSequentialAddition",
    "RsaConfig",
    "convex_polygons_overlap",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

PROGRESS_EVERY = 256
"""Particles inserted between two calls of the progress callback."""

MAX_ATTEMPTS_LIMIT = 10_000_000
"""Largest allowed ``max_attempts``."""

# counters and flags of a run (``Grid.ipar``)
(
    I_GNX,
    I_GNY,
    I_GUSED,
    I_GEN,
    I_ATTEMPTS,
    I_REJECTED,
    I_RUN,
    I_STOPPED,
    I_STOP_AT,
    I_WALLMODE,
) = range(10)
N_IPAR = 10

# ``Grid.fpar`` after the domain's box (xmin, xmax, ymin, ymax): the largest circumradius,
# then the grid's origin and cell size in a row, as ``grid_insert`` reads them
F_REACH, F_GX0, F_GY0, F_GCELL = 4, 5, 6, 7


class RsaConfig(BaseModel):
    """Parameters of the random sequential addition inserter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    max_attempts: int = Field(
        1000,
        ge=1,
        le=MAX_ATTEMPTS_LIMIT,
        description=(
            "Uniform random centres tried per particle (1 to 10^7) before it is "
            "recorded as not placed."
        ),
    )
    stop_after_failures: int | None = Field(
        None,
        ge=1,
        description=(
            "Stop trying further particles after this many consecutive not-placed "
            "particles (the rest are recorded as not placed); unset tries every particle."
        ),
    )


class Outlines(NamedTuple):
    """Static particle data: local outlines, circumradii and local bounding boxes."""

    vx: FloatArray
    vy: FloatArray
    offsets: IntArray
    circum: FloatArray
    box: FloatArray
    rho: FloatArray
    """Rounding radius of every outline (zero for sharp polygons)."""


class Grid(NamedTuple):
    """The growing packing: centres, the neighbour grid and counters."""

    cx: FloatArray
    cy: FloatArray
    placed: IntArray
    head: IntArray
    nxt: IntArray
    item: IntArray
    stamp: IntArray
    fpar: FloatArray
    """``[xmin, xmax, ymin, ymax, reach, x0, y0, cell]``: the domain's box, the largest
    circumradius, and the grid's origin (the box's lower corner) and cell size."""
    ipar: IntArray
    walls: FloatArray
    """Wall array of :func:`regopack.plugins.common.walls.wall_arrays`."""


# ---------------------------------------------------------------------------
# geometry


@numba.njit(cache=True)
def _separated_along_edges(
    ax: FloatArray,
    ay: FloatArray,
    bx: FloatArray,
    by: FloatArray,
    dx: float,
    dy: float,
) -> bool:
    """Return whether a normal of one of ``a``'s edges separates ``a`` from ``b + (dx, dy)``.

    Projections that only meet at one value (touching) count as separated.
    Edges of zero length have no normal and are skipped.
    """
    m = ax.shape[0]
    k = bx.shape[0]
    for j in range(m):
        j2 = j + 1 if j + 1 < m else 0
        ex = ax[j2] - ax[j]
        ey = ay[j2] - ay[j]
        if ex == 0.0 and ey == 0.0:
            continue
        # normal (ey, -ex); the sign does not matter for the test
        lo_a = math.inf
        hi_a = -math.inf
        for q in range(m):
            p = ax[q] * ey - ay[q] * ex
            lo_a = min(lo_a, p)
            hi_a = max(hi_a, p)
        lo_b = math.inf
        hi_b = -math.inf
        for q in range(k):
            p = (bx[q] + dx) * ey - (by[q] + dy) * ex
            lo_b = min(lo_b, p)
            hi_b = max(hi_b, p)
        if hi_a <= lo_b or hi_b <= lo_a:
            return True
    return False


@numba.njit(cache=True)
def _overlap(
    ax: FloatArray,
    ay: FloatArray,
    bx: FloatArray,
    by: FloatArray,
    dx: float,
    dy: float,
) -> bool:
    """Return whether the interiors of convex polygons ``a`` and ``b + (dx, dy)`` intersect."""
    if _separated_along_edges(ax, ay, bx, by, dx, dy):
        return False
    # the test along b's normals, in b's frame: a is shifted by (-dx, -dy)
    return not _separated_along_edges(bx, by, ax, ay, -dx, -dy)


def convex_polygons_overlap(
    a: ArrayLike, b: ArrayLike, shift: tuple[float, float] = (0.0, 0.0)
) -> bool:
    """Whether the interiors of two convex polygons intersect (touching is no overlap).

    This is the exact test the ``rsa`` inserter uses: the separating-axis test
    over the edge normals of both outlines.

    Parameters
    ----------
    a, b
        ``(k, 2)`` vertices of convex polygons, in either orientation.
    shift
        Translation applied to ``b`` first.

    Examples
    --------
    >>> square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    >>> convex_polygons_overlap(square, square, shift=(1.0, 0.0))
    False
    >>> convex_polygons_overlap(square, square, shift=(0.5, 0.5))
    True
    """
    pa = np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1, 2).T)
    pb = np.ascontiguousarray(np.asarray(b, dtype=np.float64).reshape(-1, 2).T)
    return bool(_overlap(pa[0], pa[1], pb[0], pb[1], float(shift[0]), float(shift[1])))


# ---------------------------------------------------------------------------
# neighbour grid


def _grid_layout(domain: PlaneDomain, circum: FloatArray) -> tuple[float, int, int, int]:
    """Cell size, cells along x and y, and an upper bound on the registrations."""
    width, height = domain.width, domain.height
    n = max(int(circum.shape[0]), 1)
    typical = float(np.median(circum)) if circum.shape[0] else max(width, height)
    cell = max(2.0 * typical, math.sqrt(width * height / (4.0 * n)))
    longest = max(width, height)
    cell = min(cell, longest) if longest > 0 else 1.0
    cell = max(cell, 1e-300)
    gnx = max(1, math.ceil(width / cell))
    gny = max(1, math.ceil(height / cell))
    span = np.floor(2.0 * circum / cell) + 2.0
    capacity = int(np.sum(np.minimum(span, gnx) * np.minimum(span, gny))) + 1
    return cell, gnx, gny, capacity


@numba.njit(cache=True)
def _register(p: int, g: Outlines, s: Grid) -> None:
    """Enter placed particle ``p`` in every cell of its circumscribed square."""
    grid_insert(
        p, s.cx[p], s.cy[p], g.circum[p], s.fpar[F_GX0 : F_GCELL + 1],
        s.ipar[I_GNX : I_GUSED + 1], s.head, s.nxt, s.item,
    )  # fmt: skip


@numba.njit(cache=True)
def _hits(i: int, x: float, y: float, g: Outlines, s: Grid) -> bool:
    """Return whether particle ``i`` centred at ``(x, y)`` overlaps a placed particle."""
    ai, aj = g.offsets[i], g.offsets[i + 1]
    ax, ay = g.vx[ai:aj], g.vy[ai:aj]
    if s.ipar[I_WALLMODE] != WALL_PERIODIC:
        return _hits_near(i, x, y, ax, ay, g, s)
    # the images one period away of the particles near (x, y)
    lx = s.fpar[1] - s.fpar[0]
    ly = s.fpar[3] - s.fpar[2]
    span = g.circum[i] + s.fpar[F_REACH]
    for sx in (0.0, lx, -lx):
        if (sx > 0.0 and x - span >= s.fpar[0]) or (sx < 0.0 and x + span <= s.fpar[1]):
            continue
        for sy in (0.0, ly, -ly):
            if (sy > 0.0 and y - span >= s.fpar[2]) or (sy < 0.0 and y + span <= s.fpar[3]):
                continue
            if _hits_near(i, x + sx, y + sy, ax, ay, g, s):
                return True
    return False


@numba.njit(cache=True)
def _hits_near(
    i: int, x: float, y: float, ax: FloatArray, ay: FloatArray, g: Outlines, s: Grid
) -> bool:
    """Return whether outline ``a`` of particle ``i`` at ``(x, y)`` overlaps a registered one."""
    reach = g.circum[i]
    nx, ny = s.ipar[I_GNX], s.ipar[I_GNY]
    ia, ib = cell_range(x - reach, x + reach, s.fpar[F_GX0], s.fpar[F_GCELL], nx)
    ja, jb = cell_range(y - reach, y + reach, s.fpar[F_GY0], s.fpar[F_GCELL], ny)
    gen = s.ipar[I_GEN] + 1
    s.ipar[I_GEN] = gen
    for j in range(ja, jb + 1):
        for ic in range(ia, ib + 1):
            e = s.head[j * nx + ic]
            while e >= 0:
                p = s.item[e]
                e = s.nxt[e]
                if s.stamp[p] == gen:
                    continue
                s.stamp[p] = gen
                dx = s.cx[p] - x
                dy = s.cy[p] - y
                both = reach + g.circum[p]
                if dx * dx + dy * dy >= both * both:
                    continue
                # bounding boxes, in the new particle's frame
                if (
                    g.box[i, 1] <= g.box[p, 0] + dx
                    or g.box[p, 1] + dx <= g.box[i, 0]
                    or g.box[i, 3] <= g.box[p, 2] + dy
                    or g.box[p, 3] + dy <= g.box[i, 2]
                ):
                    continue
                bi, bj = g.offsets[p], g.offsets[p + 1]
                bx, by = g.vx[bi:bj], g.vy[bi:bj]
                rr = g.rho[i] + g.rho[p]
                if rr == 0.0:
                    if _overlap(ax, ay, bx, by, dx, dy):
                        return True
                elif _core_distance(ax, ay, bx, by, dx, dy) < rr:
                    return True
    return False


@numba.njit(cache=True)
def _point_segment2(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Squared distance from ``p`` to the segment ``a b``."""
    dx = bx - ax
    dy = by - ay
    ll = dx * dx + dy * dy
    t = 0.0
    if ll > 0.0:
        t = min(max(((px - ax) * dx + (py - ay) * dy) / ll, 0.0), 1.0)
    ex = ax + t * dx - px
    ey = ay + t * dy - py
    return ex * ex + ey * ey


@numba.njit(cache=True)
def _core_distance(
    ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray, dx: float, dy: float
) -> float:
    """Distance between the convex cores ``a`` and ``b + (dx, dy)`` (0 when they overlap).

    A core is a single point or a convex polygon; a point inside the other
    core, or two polygons whose interiors meet, are at distance 0.
    """
    m = ax.shape[0]
    k = bx.shape[0]
    if m + k > 2 and not _separated_along_edges(ax, ay, bx, by, dx, dy):
        if not _separated_along_edges(bx, by, ax, ay, -dx, -dy):
            return 0.0
    best = np.inf
    for j in range(m):
        for q in range(k):
            q2 = q + 1 if q + 1 < k else 0
            d2 = _point_segment2(ax[j], ay[j], bx[q] + dx, by[q] + dy, bx[q2] + dx, by[q2] + dy)
            best = min(best, d2)
    for q in range(k):
        for j in range(m):
            j2 = j + 1 if j + 1 < m else 0
            d2 = _point_segment2(bx[q] + dx, by[q] + dy, ax[j], ay[j], ax[j2], ay[j2])
            best = min(best, d2)
    return math.sqrt(best)


# ---------------------------------------------------------------------------
# insertion loop


@numba.njit(cache=True)
def _pack_range(
    begin: int,
    end: int,
    max_attempts: int,
    stop_after: int,
    g: Outlines,
    s: Grid,
    rng: np.random.Generator,
) -> int:
    """Try particles ``begin`` to ``end - 1``; return how many were placed.

    ``stop_after`` > 0 stops the run after that many consecutive failures
    (``ipar[I_STOPPED]`` is set and ``ipar[I_STOP_AT]`` is the first particle not tried).
    """
    ipar = s.ipar
    mode = ipar[I_WALLMODE]
    placed = 0
    for i in range(begin, end):
        if mode == WALL_PERIODIC:
            x0, x1, y0, y1 = s.fpar[0], s.fpar[1], s.fpar[2], s.fpar[3]
        else:
            x0 = s.fpar[0] - g.box[i, 0]
            x1 = s.fpar[1] - g.box[i, 1]
            y0 = s.fpar[2] - g.box[i, 2]
            y1 = s.fpar[3] - g.box[i, 3]
        ok = False
        if x0 <= x1 and y0 <= y1:
            for _ in range(max_attempts):
                x = min(x0 + rng.random() * (x1 - x0), x1)
                y = min(y0 + rng.random() * (y1 - y0), y1)
                ipar[I_ATTEMPTS] += 1
                if mode == WALL_PERIODIC and (x >= x1 or y >= y1):
                    ipar[I_REJECTED] += 1  # the upper sides are the lower ones
                    continue
                a, b = g.offsets[i], g.offsets[i + 1]
                if mode != WALL_BOX and not point_fits(
                    x, y, g.vx, g.vy, a, b, mode, s.walls, g.rho[i]
                ):
                    ipar[I_REJECTED] += 1
                    continue
                if _hits(i, x, y, g, s):
                    ipar[I_REJECTED] += 1
                    continue
                s.cx[i] = x
                s.cy[i] = y
                s.placed[i] = 1
                _register(i, g, s)
                ok = True
                break
        if ok:
            placed += 1
            ipar[I_RUN] = 0
        else:
            ipar[I_RUN] += 1
            if stop_after > 0 and ipar[I_RUN] >= stop_after:
                ipar[I_STOPPED] = 1
                ipar[I_STOP_AT] = i + 1
                break
    return placed


def _prepare(population: Population, domain: PlaneDomain) -> tuple[Outlines, Grid]:
    """Build the static outlines and an empty grid."""
    n = len(population)
    offsets = np.ascontiguousarray(population.shapes.offsets, dtype=np.int64)
    verts = np.asarray(population.shapes.vertices, dtype=np.float64).reshape(-1, 2)
    vx = np.ascontiguousarray(verts[:, 0])
    vy = np.ascontiguousarray(verts[:, 1])
    circum = np.ascontiguousarray(population.circumradius, dtype=np.float64)
    rho = np.ascontiguousarray(population.shapes.rounding_radius, dtype=np.float64)
    box = np.zeros((n, 4), dtype=np.float64)
    counts = np.diff(offsets)
    full = counts > 0
    if full.any():
        starts = offsets[:-1][full]
        box[full, 0] = np.minimum.reduceat(vx, starts)
        box[full, 1] = np.maximum.reduceat(vx, starts)
        box[full, 2] = np.minimum.reduceat(vy, starts)
        box[full, 3] = np.maximum.reduceat(vy, starts)
    box += rho[:, None] * np.array([-1.0, 1.0, -1.0, 1.0])
    check_periodic_size(domain, circum)
    mode, walls = wall_arrays(domain)
    cell, gnx, gny, capacity = _grid_layout(domain, circum)
    reach = float(circum.max()) if n else 0.0
    bounds = domain.bounds()
    fpar = np.array([*bounds, reach, bounds[0], bounds[2], cell], dtype=np.float64)
    ipar = np.zeros(N_IPAR, dtype=np.int64)
    ipar[I_WALLMODE] = mode
    ipar[I_GNX] = gnx
    ipar[I_GNY] = gny
    outlines = Outlines(vx=vx, vy=vy, offsets=offsets, circum=circum, box=box, rho=rho)
    grid = Grid(
        cx=np.full(n, np.nan),
        cy=np.full(n, np.nan),
        placed=np.zeros(n, dtype=np.int64),
        **empty_grid(n, gnx * gny, capacity),
        fpar=fpar,
        ipar=ipar,
        walls=walls,
    )
    return outlines, grid


class RandomSequentialAddition(InsertionStrategy):
    """Random sequential addition with rejection; see the module docstring.

    It places particles without the density controller
    (:attr:`steered_by_density` is False).

    Examples
    --------
    >>> import numpy as np
    >>> from regopack.geometry.domain import Rectangle
    >>> from regopack.plugins.density.eta import EtaConfig, EtaController
    >>> from regopack.geometry.population import Population, ShapeBatch
    >>> square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    >>> shapes = ShapeBatch(np.tile(square, (3, 1)), np.arange(0, 13, 4), np.zeros(3))
    >>> pop = Population(np.full(3, 2 / np.sqrt(np.pi)), np.zeros(3, int), ("m",), shapes)
    >>> rsa = RandomSequentialAddition(RsaConfig(max_attempts=100))
    >>> ctl = EtaController(EtaConfig())
    >>> out = rsa.pack(pop, Rectangle(0, 10, 0, 10), ctl, np.random.default_rng(1))
    >>> int(out.placed.sum())
    3
    """

    steered_by_density = False

    def __init__(self, config: RsaConfig) -> None:
        self.config = config

    def pack(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Try the particles in population order; ``controller`` is ignored.

        ``stats`` holds ``attempts`` (centres drawn), ``rejected_attempts``
        (centres that overlapped), ``not_tried`` (particles skipped after
        ``stop_after_failures``), ``prepare_time_s`` and ``insert_time_s``, and
        ``controller_ignored = 1`` when the controller is not the identity.
        """
        if not isinstance(domain, PlaneDomain):
            raise ConfigError("insertion 'rsa' packs polygons in a 2D domain")
        cfg = self.config
        n = len(population)
        started = time.perf_counter()
        outlines, grid = _prepare(population, domain)
        stop_after = cfg.stop_after_failures or 0
        prepared = time.perf_counter()
        placed = 0
        for begin in range(0, n, PROGRESS_EVERY):
            if progress is not None:
                progress(begin, placed, n)
            end = min(begin + PROGRESS_EVERY, n)
            placed += int(
                _pack_range(begin, end, cfg.max_attempts, stop_after, outlines, grid, rng)
            )
            if grid.ipar[I_STOPPED]:
                break
        if progress is not None:
            progress(n, placed, n)
        mask = grid.placed.astype(bool)
        index = np.full(n, -1, dtype=np.int64)
        index[mask] = np.arange(int(mask.sum()), dtype=np.int64)
        centre = np.column_stack([grid.cx, grid.cy])
        not_tried = n - int(grid.ipar[I_STOP_AT]) if grid.ipar[I_STOPPED] else 0
        stats = {
            "attempts": int(grid.ipar[I_ATTEMPTS]),
            "rejected_attempts": int(grid.ipar[I_REJECTED]),
            "not_tried": int(not_tried),
            "prepare_time_s": prepared - started,
            "insert_time_s": time.perf_counter() - prepared,
        }
        if not controller.identity:
            stats["controller_ignored"] = 1
        return InsertionResult(centre=centre, insertion_index=index, stats=stats)


@hookimpl
def regopack_inserters() -> Iterable[InserterSpec]:
    """Register the ``rsa`` inserter."""
    return [
        InserterSpec(
            name="rsa",
            config_model=RsaConfig,
            factory=RandomSequentialAddition,
            description=(
                "Random sequential addition: uniform random centres with rejection "
                "(the classic baseline)."
            ),
        )
    ]
