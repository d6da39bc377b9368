"""The placed particles of an available-surface run and the analysis of one candidate.

:class:`SurfaceState` holds what every candidate order needs: the population as
:class:`Polyhedron` tuples, the centres placed so far, the insertion order,
each candidate's screening radius ``rmin_k`` and a grid of cells for the
interferer search. :meth:`SurfaceState.analyse` is the exact analysis of one
candidate for one particle (see :mod:`regopack.plugins.available_surface.inserter`):
it returns the sampled centre, or ``None`` and records ``rmin_k``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.plugins.available_surface.envelope import minkowski_envelope
from regopack.plugins.available_surface.free_surface import (
    Interferers,
    free_surface,
    sample_free_point,
)
from regopack.plugins.available_surface.halfspaces import edge_arcs, halfspaces_of_arcs
from regopack.plugins.available_surface.polyhedron import Polyhedron
from regopack.solids import SolidBatch

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class CellGrid:
    """Placed particles binned in cubic cells (a dictionary of cell lists)."""

    def __init__(self, cell: float) -> None:
        self.cell = cell
        self.cells: dict[tuple[int, int, int], list[int]] = {}

    def key(self, x: FloatArray) -> tuple[int, int, int]:
        """Cell of point ``x``."""
        c = self.cell
        return (math.floor(x[0] / c), math.floor(x[1] / c), math.floor(x[2] / c))

    def add(self, j: int, x: FloatArray) -> None:
        """File particle ``j`` at ``x``."""
        self.cells.setdefault(self.key(x), []).append(j)

    def near(self, x: FloatArray, reach: float) -> list[int]:
        """Particles in the cells that a ball of radius ``reach`` about ``x`` meets."""
        c = self.cell
        lo = [math.floor((x[a] - reach) / c) for a in range(3)]
        hi = [math.floor((x[a] + reach) / c) for a in range(3)]
        out: list[int] = []
        for ix in range(lo[0], hi[0] + 1):
            for iy in range(lo[1], hi[1] + 1):
                for iz in range(lo[2], hi[2] + 1):
                    out.extend(self.cells.get((ix, iy, iz), ()))
        return out


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


def _interferers(
    planes: list[tuple[FloatArray, FloatArray]], centres: FloatArray, radii: FloatArray
) -> Interferers:
    """Pack the interferers' half-spaces, centres and circumradius bounds for the kernel."""
    sizes = [len(h) for _, h in planes]
    offsets = np.zeros(len(planes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    return Interferers(
        normals=np.concatenate([n for n, _ in planes]) if planes else np.zeros((0, 3)),
        support=np.concatenate([h for _, h in planes]) if planes else np.zeros(0),
        offsets=offsets,
        centres=np.ascontiguousarray(centres.reshape(-1, 3)),
        radii=np.ascontiguousarray(radii, dtype=np.float64),
    )


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
    periodic
        Whether the box's opposite faces are identified (no walls): then the
        interferers include the periodic images of the placed particles (and
        of the candidate itself), and a centre is wrapped into the box.
    """

    def __init__(
        self,
        shapes: SolidBatch,
        radius: FloatArray,
        lo: FloatArray,
        hi: FloatArray,
        periodic: bool = False,
    ):
        n = len(shapes)
        self.n = n
        self.period = (hi - lo) if periodic else None
        self.polys = polyhedra_of(shapes)
        self.circum = shapes.circumradius
        self.radius = radius
        self.lo = lo
        self.hi = hi
        self.centre = np.full((n, 3), np.nan)
        self.index = np.full(n, -1, dtype=np.int64)
        self.order = np.full(n, -1, dtype=np.int64)
        self.rmin = np.full(n, np.inf)
        self.count = 0
        self.analyses = 0
        self.empty = 0
        self.reach_max = 0.0
        self.grid = CellGrid(2.0 * float(self.circum.max()) if n else 1.0)
        self._arcs: list[Any] = [None] * n  # edge arcs of each placed particle, on first use
        self._particle = -1
        self._q_arcs: Any = None
        self._halfspaces: dict[int, tuple[FloatArray, FloatArray]] = {}
        self.adm_lo = lo
        self.adm_hi = hi

    def begin(self, i: int) -> bool:
        """Start on particle ``i``; False when it is larger than the box."""
        q = self.polys[i]
        self._particle = i
        self._q_arcs = None
        self._halfspaces = {}
        if self.period is not None:
            self.adm_lo = np.full(3, -np.inf)
            self.adm_hi = np.full(3, np.inf)
            return True
        self.adm_lo = self.lo - q.vertices.min(axis=0)
        self.adm_hi = self.hi - q.vertices.max(axis=0)
        return not bool(np.any(self.adm_lo > self.adm_hi))

    def fits_at(self, x: FloatArray) -> bool:
        """Whether the current particle's centre ``x`` keeps it inside the box."""
        return bool(np.all(x >= self.adm_lo) and np.all(x <= self.adm_hi))

    def analyse(self, k: int, rng: np.random.Generator) -> FloatArray | None:
        """Exact analysis of candidate ``k`` (insertion index) for the current particle.

        Returns a centre drawn uniformly by area on the free surface, or
        ``None`` after recording ``rmin_k`` (the candidate has no free area).
        """
        i = self._particle
        q = self.polys[i]
        if self._q_arcs is None:
            self._q_arcs = edge_arcs(q, -1.0)
        circum = self.circum
        centre = self.centre
        pk = int(self.order[k])
        envelope = minkowski_envelope(self.polys[pk], q)
        reach = circum[pk] + self.reach_max + 2.0 * circum[i]
        if self.period is None:
            found = np.asarray(self.grid.near(centre[pk], reach), dtype=np.int64)
            d = centre[found] - centre[pk]
            lim = circum[pk] + circum[found] + 2.0 * circum[i]
            hit = (np.einsum("ij,ij->i", d, d) < lim * lim) & (found != pk)
            near = found[hit]
            near_centres = centre[near]
        else:
            near, near_centres = self._periodic_neighbours(pk, i, reach)
        halfspaces = self._halfspaces
        arcs = self._arcs
        for j in near.tolist():
            if j not in halfspaces:
                if arcs[j] is None:
                    arcs[j] = edge_arcs(self.polys[j], 1.0)
                halfspaces[j] = halfspaces_of_arcs(self.polys[j], arcs[j], q, self._q_arcs)
        inter = _interferers(
            [halfspaces[j] for j in near.tolist()], near_centres, circum[near] + circum[i]
        )
        self.analyses += 1
        surface = free_surface(envelope, centre[pk], inter, self.adm_lo, self.adm_hi)
        if surface.area > 0.0:
            u = rng.random(3)
            return np.asarray(sample_free_point(surface, u[0], u[1], u[2]))
        self.empty += 1
        self.rmin[k] = self.radius[i]
        return None

    def _periodic_neighbours(self, pk: int, i: int, reach: float) -> tuple[IntArray, FloatArray]:
        """Interferers of candidate ``pk`` among all periodic images, with their centres.

        An image ``c_j + s L`` (``s`` in ``{-1, 0, 1}^3``) lies near ``c_k`` when
        ``c_j`` lies near ``c_k - s L``; shifts whose ball misses the box are skipped.
        The candidate's own images count (a box smaller than a few particles).
        """
        assert self.period is not None
        circum = self.circum
        centre = self.centre
        ck = centre[pk]
        ids: list[int] = []
        shifts: list[FloatArray] = []
        for sx in (-1, 0, 1):
            for sy in (-1, 0, 1):
                for sz in (-1, 0, 1):
                    shift = np.array([sx, sy, sz], dtype=np.float64) * self.period
                    p = ck - shift
                    if np.any(p + reach < self.lo) or np.any(p - reach > self.hi):
                        continue
                    found = self.grid.near(p, reach)
                    ids.extend(found)
                    shifts.extend([shift] * len(found))
        idx = np.asarray(ids, dtype=np.int64)
        at = centre[idx] + np.asarray(shifts, dtype=np.float64).reshape(-1, 3)
        d = at - ck
        lim = circum[pk] + circum[idx] + 2.0 * circum[i]
        own = (idx == pk) & (np.einsum("ij,ij->i", d, d) == 0.0)
        hit = (np.einsum("ij,ij->i", d, d) < lim * lim) & ~own
        return idx[hit], np.ascontiguousarray(at[hit])

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
        self.grid.add(i, self.centre[i])
        self.reach_max = max(self.reach_max, float(self.circum[i]))
        return k
