"""The placed particles of an available-surface run and the analysis of one candidate.

:class:`SurfaceState` holds what every candidate order needs: the population as
:class:`Polyhedron` tuples, the centres placed so far, the insertion order,
each candidate's screening radius ``rmin_k`` and a grid of cells for the
interferer search. :meth:`SurfaceState.analyse` is the exact analysis of one
candidate for one particle (see :mod:`regopack.plugins.inserters.available_surface.inserter`):
it returns the sampled centre, or ``None`` and records ``rmin_k``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.solids import SolidBatch
from regopack.plugins.common.kernel_random import KernelSource, kernel_source
from regopack.plugins.inserters.available_surface.analysis import (
    FOUND,
    FULL,
    Bounds,
    Placed,
    Screening,
    arcs_for,
    arcs_of,
    cache_for,
    grid_add,
    grid_for,
    grown,
    scan,
    scan_spheres,
    solids_of,
)
from regopack.plugins.inserters.available_surface.envelope import EdgeArcs, edge_arcs
from regopack.plugins.inserters.available_surface.halfspaces import minkowski_halfspaces
from regopack.plugins.inserters.available_surface.partner import (
    PartnerThread,
    SurfacePartner,
    scan_shared,
)
from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron
from regopack.plugins.inserters.available_surface.prism_wall import NO_WALL, inside_prism

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def polyhedra_of(shapes: SolidBatch) -> list[Polyhedron]:
    """Return the solids of a batch as :class:`Polyhedron` tuples (relative to their centres)."""
    polys = []
    for j in range(len(shapes)):
        verts, loops = shapes.solid(j)
        f0, f1 = int(shapes.face_offsets[j]), int(shapes.face_offsets[j + 1])
        fo = np.zeros(len(loops) + 1, dtype=np.int64)
        np.cumsum([len(lp) for lp in loops], out=fo[1:])
        polys.append(
            Polyhedron(
                vertices=np.ascontiguousarray(verts),
                normals=np.ascontiguousarray(shapes.normals[f0:f1]),
                support=np.ascontiguousarray(shapes.support[f0:f1]),
                face_vertices=np.concatenate(loops).astype(np.int64),
                face_offsets=fo,
            )
        )
    return polys


LEVELS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
"""Quantiles of the population's radii at which empty sphere candidates are tried for shutting."""


def shut_levels(radius: FloatArray) -> FloatArray:
    """Distinct radii at the :data:`LEVELS` quantiles of ``radius`` (ascending)."""
    return np.unique(np.quantile(radius, LEVELS, method="inverted_cdf"))


class SurfaceState:
    """Placed particles of one run and the exact analysis of a candidate.

    Parameters
    ----------
    shapes
        The population's solids (sharp polyhedra).
    radius
        ``(n,)`` equivalent radii (the screening compares them).
    lo, hi
        Corners of the box.
    t
        Screening coefficient.
    eta
        Packing control coefficient (see :func:`.analysis.eta_margin`).
    periodic
        Whether the box's opposite faces are identified (no walls): then the
        interferers include the periodic images of the placed particles (and
        of the candidate itself), and a centre is wrapped into the box.
    wall
        A cylinder's side wall as its inscribed prism
        (:func:`.prism_wall.prism_wall`); ``lo``/``hi`` are then the
        cylinder's bounding box. Empty: the box's walls alone.
    window
        Bounds ``(lo, hi)`` that every centre must keep besides the walls
        (a tile's centre window; infinite values bound nothing). ``None``:
        none.
    """

    def __init__(
        self,
        shapes: SolidBatch,
        radius: FloatArray,
        lo: FloatArray,
        hi: FloatArray,
        periodic: bool = False,
        t: float = 0.999,
        eta: float = 0.0,
        wall: FloatArray = NO_WALL,
        window: tuple[FloatArray, FloatArray] | None = None,
    ):
        n = len(shapes)
        self.wall = wall
        self.window = window
        self.n = n
        self.period = (hi - lo) if periodic else None
        self.t = t
        self.eta = eta
        self._xi = np.full(1, -1.0)
        rounding = shapes.rounding_radius
        self.spheres = bool(n > 0 and shapes.normals.shape[0] == 0 and np.all(rounding > 0))
        self.rounding = rounding
        self.polys = [] if self.spheres else polyhedra_of(shapes)
        self.circum = shapes.circumradius
        self.levels = shut_levels(self.circum) if self.spheres else np.zeros(0)
        """Spheres: radii at which an empty candidate is tried for shutting."""
        self.radius = radius
        self.lo = lo
        self.hi = hi
        self.centre = np.full((n, 3), np.nan)
        self.index = np.full(n, -1, dtype=np.int64)
        self.order = np.full(n, -1, dtype=np.int64)
        self.rmin = np.full(n, np.inf)
        self.shut_from = np.full(n, np.inf)
        """Spheres: per candidate, the radius from which no sphere fits any more."""
        self.count = 0
        self.counters = np.zeros(5, dtype=np.int64)
        self._no_tried = np.zeros(0, dtype=np.int64)
        self._no_tree = np.zeros(0)
        self._no_arcs = EdgeArcs(
            np.zeros(0, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
            np.zeros((0, 3)),
            np.zeros((0, 6)),
        )
        self.reach_max = 0.0
        self.solids = solids_of(self.polys)
        self.arcs = arcs_for(self.solids)
        self.grid = grid_for(lo, hi, 2.0 * float(self.circum.max()) if n else 1.0, n)
        self.cache = cache_for(n, 4096)
        self._period = self.period if self.period is not None else np.zeros(0)
        self._out = np.zeros(3)
        self._particle = -1
        self._q_arcs: Any = None
        self.adm_lo = lo
        self.adm_hi = hi
        self._partner: PartnerThread | None = None
        self._shared: SurfacePartner | None = None
        self._rng: np.random.Generator | None = None
        self._source: KernelSource = np.zeros(4, dtype=np.uint64)
        self._placed = Placed(self.order, self.centre, self.circum, self.reach_max)
        self._bounds = Bounds(self._period, lo, hi, lo, hi, wall)
        self._unbounded = (np.full(3, -np.inf), np.full(3, np.inf))

    def start_partner(self) -> bool:
        """Have a partner thread analyse candidates ahead of the scans; False when none serves.

        A partner serves polyhedra scanned without a packing control margin
        (:mod:`.partner`), where numba has two threads or more and threads can
        sleep (POSIX). The packing is the same with it or without it.
        """
        from regopack.base.threads import kernel_threads
        from regopack.plugins.inserters.available_arc.partner import available

        if self.spheres or self.eta > 0.0 or self.n == 0:
            return False
        if self._partner is None:
            if kernel_threads() < 2 or not available():
                return False
            self._partner = PartnerThread(
                self.solids, self.arcs, self.grid, cache_for(self.n, 4096), self.order,
                self.centre, self.circum, self._period, self.lo, self.hi, self.wall,
            )  # fmt: skip
        self._shared = self._partner.start()
        return True

    def stop_partner(self) -> BaseException | None:
        """Stop the partner thread, if one runs; return the error that ended it, if any."""
        partner, self._partner, self._shared = self._partner, None, None
        return None if partner is None else partner.stop()

    @property
    def partner_analyses(self) -> int:
        """Analyses the running partner thread has made (those the scans dropped included)."""
        return 0 if self._partner is None else self._partner.served

    def begin(self, i: int) -> bool:
        """Start on particle ``i``; False when it is larger than the box.

        In a periodic box: False when it overlaps its own images.
        """
        self._particle = i
        self._q_arcs = None
        self.cache.fill[0] = 0
        if self.period is not None:
            self.adm_lo, self.adm_hi = self._unbounded
            if self.window is not None:
                self.adm_lo = np.maximum(self.adm_lo, self.window[0])
                self.adm_hi = np.minimum(self.adm_hi, self.window[1])
            self._bounds = Bounds(
                self._period, self.lo, self.hi, self.adm_lo, self.adm_hi, self.wall
            )
            return not self._meets_own_images(i)
        if self.spheres:
            r = self.rounding[i]
            self.adm_lo = self.lo + r
            self.adm_hi = self.hi - r
        else:
            q = self.polys[i]
            self.adm_lo = self.lo - q.vertices.min(axis=0)
            self.adm_hi = self.hi - q.vertices.max(axis=0)
        if self.window is not None:
            self.adm_lo = np.maximum(self.adm_lo, self.window[0])
            self.adm_hi = np.minimum(self.adm_hi, self.window[1])
        self._bounds = Bounds(self._period, self.lo, self.hi, self.adm_lo, self.adm_hi, self.wall)
        lo, hi = self.adm_lo, self.adm_hi
        return not (lo[0] > hi[0] or lo[1] > hi[1] or lo[2] > hi[2])

    def _meets_own_images(self, i: int) -> bool:
        """Whether particle ``i`` overlaps its own periodic images (it then fits nowhere).

        A sphere does when its diameter exceeds the shortest period; a
        polyhedron ``Q`` when a period shift lies inside the open difference
        body ``Q ⊕ (-Q)`` (touching images are allowed).
        """
        period = self.period
        assert period is not None
        if self.spheres:
            return bool(2.0 * self.rounding[i] > period.min())
        q = self.polys[i]
        normals, support = minkowski_halfspaces(q, q)
        tol = 1e-12 * float(support.max())
        reach = np.ceil(2.0 * float(self.circum[i]) / period).astype(np.int64)
        axes = [np.arange(-m, m + 1) for m in reach]
        shifts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        shifts = shifts[np.any(shifts != 0, axis=1)] * period
        inside = (shifts @ normals.T - support).max(axis=1) < -tol
        return bool(np.any(inside))

    def fits_at(self, x: FloatArray) -> bool:
        """Whether the current particle's centre ``x`` keeps it inside the box (and the prism)."""
        if not (np.all(x >= self.adm_lo) and np.all(x <= self.adm_hi)):
            return False
        if self.wall.shape[0] == 0:
            return True
        i = self._particle
        if self.spheres:
            return inside_prism(self.wall, x, np.zeros((0, 3)), float(self.rounding[i]))
        return inside_prism(self.wall, x, self.polys[i].vertices, 0.0)

    def scan(
        self,
        candidates: IntArray,
        rng: np.random.Generator,
        screened: bool = True,
        tried: IntArray | None = None,
        tree: FloatArray | None = None,
    ) -> tuple[int, FloatArray | None]:
        """Offer the current particle to ``candidates`` (insertion indices) in turn.

        A candidate is analysed when the particle passes its screening (every
        one when ``screened`` is False); the first with free area takes it.
        Each analysed candidate gets ``tried[k] = i`` when ``tried`` is given.
        With a screening ``tree`` over the positions of ``candidates`` (see
        :func:`.analysis.scan`) only the candidates open in it are searched.

        Returns
        -------
        k, x
            The candidate and a centre drawn uniformly by area on its free
            surface, or ``(-1, None)``.
        """
        i = self._particle
        if self._q_arcs is None:
            self._q_arcs = self._no_arcs if self.spheres else edge_arcs(self.polys[i], -1.0)
        cands = np.ascontiguousarray(candidates, dtype=np.int64)
        t = self.t if screened else np.inf
        screen = Screening(
            t,
            self.radius,
            self.rmin,
            self._no_tried if tried is None else tried,
            self.counters,
            self.levels,
            self.shut_from,
        )
        placed, bounds = self._placed, self._bounds
        if rng is not self._rng:  # the kernels draw from its PCG64 state (.kernel_random)
            self._rng, self._source = rng, kernel_source(rng)
        src = self._source
        begin = 0
        if self.spheres:
            code, at = scan_spheres(
                cands, begin, i, screen, self.grid, placed, bounds, self.eta, self._xi, src,
                self._out, self._no_tree if tree is None else tree,
            )  # fmt: skip
            if code == FOUND:
                return int(cands[at]), self._out.copy()
            return -1, None
        shared = self._shared
        while True:
            if shared is not None:
                code, at = scan_shared(
                    cands, begin, i, screen, self._q_arcs, self.solids, self.arcs, self.grid,
                    self.cache, placed, bounds, src, self._out,
                    self._no_tree if tree is None else tree, shared,
                )  # fmt: skip
                if code != FULL:
                    break
                self._grow_cache()
                begin = at
                continue
            code, at = scan(
                cands, begin, i, screen, self._q_arcs, self.solids, self.arcs, self.grid,
                self.cache, placed, bounds, self.eta, self._xi, self.spheres, src, self._out,
                self._no_tree if tree is None else tree,
            )  # fmt: skip
            if code != FULL:
                break
            self._grow_cache()
            begin = at
        if code == FOUND:
            return int(cands[at]), self._out.copy()
        return -1, None

    @property
    def analyses(self) -> int:
        """Candidates analysed so far."""
        return int(self.counters[0])

    @property
    def empty(self) -> int:
        """Analyses that found no free area."""
        return int(self.counters[1])

    @property
    def shut_tests(self) -> int:
        """Tries to shut a candidate (spheres): after an empty first analysis, before later ones."""
        return int(self.counters[2])

    @property
    def shut(self) -> int:
        """Tries that shut their candidate from a level down (spheres)."""
        return int(self.counters[3])

    @property
    def saved(self) -> int:
        """Analyses not run because their candidate was shut (spheres): each an empty one."""
        return int(self.counters[4])

    def _grow_cache(self) -> None:
        """Double the half-space cache, keeping its rows."""
        self.cache = grown(self.cache)

    def insert(self, i: int, x: FloatArray) -> int:
        """Place particle ``i`` at ``x`` (wrapped into a periodic box); return its index."""
        if self.period is not None:
            x = self.lo + np.mod(x - self.lo, self.period)
            x = np.where(x >= self.hi, self.lo, x)
        k = self.count
        self.centre[i] = x
        self.index[i] = k
        self.order[k] = i
        self.count += 1
        if not self.spheres:
            # the edge arcs of a placed particle, made here once: a partner's analyses
            # read them and write nothing the scans read (.partner)
            arcs_of(self.arcs, self.solids, i)
        grid_add(self.grid, i, self.centre[i])
        if self.circum[i] > self.reach_max:
            self.reach_max = float(self.circum[i])
            self._placed = Placed(self.order, self.centre, self.circum, self.reach_max)
        return k
