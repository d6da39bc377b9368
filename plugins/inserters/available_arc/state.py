"""Array state of one available-arc insertion run."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import Domain
from regopack.geometry.population import Population
from regopack.plugins.common.walls import (
    WALL_HALFPLANES,
    check_periodic_size,
    wall_arrays,
)
from regopack.plugins.inserters.available_arc import kernel
from regopack.plugins.inserters.available_arc.bound_queue import new_queue
from regopack.plugins.inserters.available_arc.candidates import tree_size
from regopack.plugins.inserters.available_arc.geometry import prepare_outlines
from regopack.plugins.inserters.available_arc.grid import empty_grid, grid_layout
from regopack.plugins.inserters.available_arc.neighbours import free_stack, list_capacity

if TYPE_CHECKING:
    from regopack.plugins.inserters.available_arc.partner import PartnerThread

FloatArray = NDArray[np.float64]

LIST_CAP_QUANTILE = 0.9
"""New particles up to this quantile of the reach look up interferers in neighbour lists."""
LIST_CAPACITY = 64
"""Entries per neighbour list; a particle with more neighbours uses the grid."""


def list_rows(n: int, pool_rows: int | None) -> int:
    """Rows of a new neighbour-list pool: ``pool_rows`` (at least one), or ``n``."""
    return n if pool_rows is None else max(1, min(n, pool_rows))


def _grown(a: NDArray[Any], rows: int) -> NDArray[Any]:
    """Return ``a`` with zero rows appended up to ``rows`` rows."""
    out = np.zeros((rows, a.shape[1]), dtype=a.dtype)
    out[: a.shape[0]] = a
    return out


class ArcState:
    """Static outlines (canonical form), the growing packing and scratch space.

    Parameters
    ----------
    population
        The particles to insert.
    domain
        The container (any kind of :mod:`regopack.geometry.domain`).
    t
        Screening coefficient.
    tau
        Threshold of the ``tau`` interference test; ``None`` selects the exact test.
    linear
        Use the linear candidate scan instead of the max-tree.
    first_random
        Put the first particle at a random feasible point instead of the centre.
    eta
        Packing control coefficient of the compiled ``eta`` rule.
    neighbour_lists
        Keep per-particle neighbour lists (in a periodic box, of the neighbours'
        images); ``False`` always searches the grid. Both give the same packing.
    pool_rows
        Rows of the neighbour-list pool to start with; ``None``: one per
        particle. An insertion that gives rows back (the sweep) starts small
        and grows the pool with :meth:`reserve_rows`.
    """

    def __init__(
        self,
        population: Population,
        domain: Domain,
        *,
        t: float,
        tau: float | None,
        linear: bool,
        first_random: bool = False,
        eta: float = 0.0,
        neighbour_lists: bool = True,
        pool_rows: int | None = None,
    ) -> None:
        n = len(population)
        offsets = np.ascontiguousarray(population.shapes.offsets, dtype=np.int64)
        verts = np.ascontiguousarray(population.shapes.vertices, dtype=np.float64)
        vx, vy, ex, ey, ang, circum, box = prepare_outlines(verts, offsets)
        req = np.ascontiguousarray(population.radius, dtype=np.float64)
        rho = np.ascontiguousarray(population.shapes.rounding_radius, dtype=np.float64)
        rounded = bool(np.any(rho > 0))
        if rounded:  # the circumradius and the local box of the rounded outlines
            circum = circum + rho
            box = box + rho[:, None] * np.array([-1.0, 1.0, -1.0, 1.0])
        self.outlines = kernel.Outlines(vx, vy, ex, ey, ang, offsets, circum, req, box, rho)

        check_periodic_size(domain, circum)
        mode, walls = wall_arrays(domain)
        reach = np.maximum(circum, req / tau) if tau is not None else circum
        bounds = domain.bounds()
        cell, gnx, gny, capacity = grid_layout(bounds, reach)
        leaves = tree_size(n)
        fpar = np.zeros(kernel.N_FPAR)
        fpar[kernel.F_T] = t
        fpar[kernel.F_TAU] = tau if tau is not None else 1.0
        fpar[kernel.F_XMIN : kernel.F_YMAX + 1] = bounds
        fpar[kernel.F_GX0] = bounds[0]
        fpar[kernel.F_GY0] = bounds[2]
        fpar[kernel.F_GCELL] = cell
        fpar[kernel.F_ETA] = eta
        fpar[kernel.F_CX], fpar[kernel.F_CY] = domain.center
        fpar[kernel.F_REACH] = float(reach.max()) if n else 0.0
        # neighbour lists (see neighbours.py), in every kind of domain
        lists = neighbour_lists and n > 0
        fpar[kernel.F_NBCAP] = float(np.quantile(reach, LIST_CAP_QUANTILE)) if lists else 0.0
        ipar = np.zeros(kernel.N_IPAR, dtype=np.int64)
        ipar[kernel.I_TAUMODE] = 0 if tau is None else 1
        ipar[kernel.I_LINEAR] = 1 if linear else 0
        ipar[kernel.I_LEAVES] = leaves
        ipar[kernel.I_GNX] = gnx
        ipar[kernel.I_GNY] = gny
        ipar[kernel.I_FIRSTRANDOM] = 1 if first_random else 0
        ipar[kernel.I_WALLMODE] = mode
        ipar[kernel.I_ROUNDED] = 1 if rounded else 0
        # disks only: every outline a single vertex at its centre, every rounding > 0
        disks = rounded and n > 0 and bool(np.all(np.diff(offsets) == 1))
        disks = disks and bool(np.all(rho > 0) and np.all(vx == 0.0) and np.all(vy == 0.0))
        ipar[kernel.I_DISKS] = 1 if disks else 0
        # bounds on what a disk candidate can take (disk_bound.py): an analysis they skip
        # must have seen every interferer the bound rests on, and the tau screening's
        # analyses leave some out
        ipar[kernel.I_BOUND] = 1 if disks and tau is None else 0
        ipar[kernel.I_STRIP] = -1  # every candidate is searched (the sweep sets its strip)
        fpar[kernel.F_RMIN] = float(rho.min()) if n else 0.0
        ipar[kernel.I_NBLISTS] = 1 if lists else 0
        rows, cols = list_capacity(list_rows(n, pool_rows), lists, LIST_CAPACITY)
        ipar[kernel.I_NBTOP] = rows if lists else 0
        # the kernels compile their rounded path only for rounded scenes
        self.rounded: bool | None = True if rounded else None
        queue = new_queue(bool(ipar[kernel.I_BOUND]))
        self.packed = kernel.Packed(
            cx=np.full(n, np.nan),
            cy=np.full(n, np.nan),
            order=np.full(n, -1, dtype=np.int64),
            tree=np.full(2 * leaves, -np.inf),
            **empty_grid(n, gnx * gny, capacity),
            fpar=fpar,
            ipar=ipar,
            walls=walls,
            nb_o=np.zeros((rows, cols), dtype=np.int32),
            nb_gap=np.zeros((rows, cols)),
            nb_dx=np.zeros((rows, cols)),
            nb_dy=np.zeros((rows, cols)),
            nb_n=np.full(rows, -1, dtype=np.int64),
            nb_reach=np.ascontiguousarray(reach, dtype=np.float64),
            nb_row=np.full(max(n, 1), -1, dtype=np.int64),
            nb_free=free_stack(rows, lists),
            nb_img=np.zeros((rows, cols), dtype=np.int8),
            shut=np.full(max(n, 1), np.inf),
            bq=queue[0],
            bqf=queue[1],
            home=np.zeros(max(n, 1), dtype=np.int64),
            hnext=np.full(max(n, 1), kernel.NOT_LISTED, dtype=np.int64),
            hhead=np.full(kernel.STRIP_SLOTS, -1, dtype=np.int64),
        )
        mmax = int(np.diff(offsets).max()) if n else 1
        width = 2 * mmax
        slots = kernel.CACHE_SLOTS
        self.work = kernel.Work(
            rx=np.empty(mmax),
            ry=np.empty(mmax),
            rex=np.empty(mmax),
            rey=np.empty(mmax),
            rang=np.empty(mmax),
            wx=np.empty(width),
            wy=np.empty(width),
            wex=np.empty(width),
            wey=np.empty(width),
            va=np.empty(width + 1),
            ckey=np.full(n, -1, dtype=np.int64),
            cslot=np.zeros(n, dtype=np.int64),
            **envelope_cache(slots, width),
            woff=np.zeros(walls.shape[0] if mode == WALL_HALFPLANES else 1),
            found=np.empty(kernel.FOUND_SLOTS, dtype=np.int64),
            found_q=np.empty(kernel.FOUND_SLOTS, dtype=np.int64),
            fs=np.empty((kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH)),
        )

    def reserve_rows(self, need: int) -> None:
        """Grow the neighbour-list pool until at least ``need`` rows are free.

        Every placement takes at most one row, so reserving the rows of ``m``
        placements before packing ``m`` particles keeps every list that the
        full pool would keep: the packing does not depend on the pool's size.
        """
        p = self.packed
        top = int(p.ipar[kernel.I_NBTOP])
        if p.ipar[kernel.I_NBLISTS] == 0 or top >= need:
            return
        rows = p.nb_o.shape[0]
        grown = max(2 * rows, rows + need - top)
        added = grown - rows
        free = np.empty(grown, dtype=np.int64)  # room for every row to be free
        free[:added] = np.arange(grown - 1, rows - 1, -1)
        free[added : added + top] = p.nb_free[:top]
        self.packed = p._replace(
            nb_o=_grown(p.nb_o, grown),
            nb_gap=_grown(p.nb_gap, grown),
            nb_dx=_grown(p.nb_dx, grown),
            nb_dy=_grown(p.nb_dy, grown),
            nb_img=_grown(p.nb_img, grown),
            nb_n=np.concatenate([p.nb_n, np.full(added, -1, dtype=np.int64)]),
            nb_free=free,
        )
        p.ipar[kernel.I_NBTOP] = top + added

    @property
    def count(self) -> int:
        """Number of particles inserted so far."""
        return int(self.packed.ipar[kernel.I_COUNT])

    def counter(self, index: int) -> int:
        """Value of integer counter ``index`` of ``kernel.I_*``."""
        return int(self.packed.ipar[index])

    def pack_range(
        self, begin: int, end: int, rng: np.random.Generator, team: PartnerThread | None = None
    ) -> int:
        """Insert particles ``begin`` to ``end - 1`` with the compiled eta rule.

        ``team``: a partner thread for the searches (the same packing).
        """
        if team is not None:
            from regopack.plugins.inserters.available_arc.partner import pack_range_shared

            shared = team.attach(self.outlines, self.packed, self.rounded)
            return int(
                pack_range_shared(
                    begin, end, self.outlines, self.packed, self.work, rng, self.rounded, shared
                )
            )
        return int(
            kernel.pack_range(begin, end, self.outlines, self.packed, self.work, rng, self.rounded)
        )

    def pack_range_exact(
        self, begin: int, end: int, rng: np.random.Generator, counts: NDArray[np.int64]
    ) -> int:
        """As :meth:`pack_range`, with an exact scan before any refusal (``counts[0]``: rescued)."""
        from regopack.plugins.inserters.available_arc.refusal import pack_range_exact

        return int(
            pack_range_exact(
                begin, end, self.outlines, self.packed, self.work, rng, counts, self.rounded
            )
        )

    def place_first(self, i: int, rng: np.random.Generator) -> bool:
        """Place the first particle; False when it does not fit the domain."""
        return bool(kernel.place_first(i, self.outlines, self.packed, rng))

    def begin_particle(self, i: int) -> int:
        """Prepare for particle ``i``; return its vertex count."""
        return int(kernel.begin_particle(i, self.outlines, self.packed, self.work))

    def find_site(self, i: int, start: int, mq: int) -> tuple[int, FloatArray]:
        """First candidate at or after insertion index ``start`` with arcs for particle ``i``."""
        k, arcs = kernel.find_site(
            i, start, mq, self.outlines, self.packed, self.work, self.rounded
        )
        return int(k), arcs

    def locate(self, k: int, i: int, mq: int, angle: float) -> tuple[float, float]:
        """Centre of particle ``i`` on candidate ``k``'s envelope at polar ``angle``."""
        x, y = kernel.locate(
            int(self.packed.order[k]),
            i,
            mq,
            angle,
            self.outlines,
            self.packed,
            self.work,
            self.rounded,
        )
        return float(x), float(y)

    def insert(self, i: int, x: float, y: float) -> int:
        """Place particle ``i`` at ``(x, y)``; return its insertion index."""
        return int(kernel.insert_particle(i, x, y, self.outlines, self.packed))

    def reject(self, k: int, r: float) -> None:
        """Record that candidate ``k`` cannot take a particle of radius ``r``."""
        kernel.reject(k, r, self.packed)


def envelope_cache(slots: int, width: int) -> dict[str, Any]:
    """Return the ``cache_*`` arrays of a :class:`kernel.Work`: ``slots`` rows of ``width``."""
    return {
        "cache_x": np.empty((slots, width)),
        "cache_y": np.empty((slots, width)),
        "cache_ex": np.empty((slots, width)),
        "cache_ey": np.empty((slots, width)),
        "cache_n": np.zeros(slots, dtype=np.int64),
        "cache_rad": np.zeros(slots),
    }
