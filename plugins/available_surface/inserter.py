"""The ``available-surface`` inserter: the paper's sequential insertion in three dimensions.

Particles are inserted one by one in population order. The first goes to
the centre of the box (or, when it does not fit there, it is not placed).
Each later particle ``Q`` is offered to the placed particles in the order
they were placed (the paper's candidate order); a candidate ``k`` is
analysed only when ``r_Q < t * rmin_k`` (the screening of 2D: ``rmin_k`` is
the smallest radius refused at ``k`` so far). The analysis is exact:

- the envelope ``E_k = P_k ⊕ (-Q)`` (:func:`envelope.minkowski_envelope`) is
  the set of centres at which ``Q`` touches ``P_k``;
- the interferers are the placed particles ``j`` with
  ``|c_j - c_k| < R_k + R_j + 2 R_Q`` (circumradii: the exact test of 2D);
  their envelopes ``E_j``, open, hold the centres at which ``Q`` would
  overlap ``P_j``;
- the walls admit the centres of a box (``Q``'s vertices inside the domain);
- the free part of ``∂E_k`` is computed exactly as convex polygons
  (:func:`free_surface.free_surface`), and the centre is drawn uniformly **by
  area** on it (:func:`free_surface.sample_free_point`, three uniform
  numbers from the run's generator).

By area rather than by solid angle about ``c_k``: area is what a uniform
random contact means on a polyhedral envelope, it is exact with planar
pieces, and it does not favour the faces that happen to lie close to the
candidate's centre. A candidate without free area records ``rmin_k = r_Q``;
a particle that no candidate takes is not placed.

This first version packs sharp polyhedra in a walled box with the
``eta`` controller at ``eta = 0``; spheres, periodic boxes and the packing
control coefficient come next.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.errors import ConfigError
from regopack.hookspecs import hookimpl
from regopack.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
)
from regopack.plugin_types import InserterSpec
from regopack.population import Population

if TYPE_CHECKING:
    from regopack.plugins.available_surface.free_surface import Interferers

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

PROGRESS_EVERY = 500
"""Particles between progress reports."""


class AvailableSurfaceConfig(BaseModel):
    """Parameters of the available-surface inserter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    t: float = Field(
        0.999,
        gt=0,
        le=1,
        allow_inf_nan=False,
        description=(
            "Screening coefficient t in (0, 1]: candidate k is analysed for a particle of "
            "radius r only when r < t * rmin_k, the smallest radius it refused."
        ),
    )
    first: Literal["center"] = Field(
        "center", description="Where the first particle goes: the box's 'center'."
    )


class _Grid:
    """Placed particles binned in cubic cells (a dictionary of cell lists)."""

    def __init__(self, cell: float) -> None:
        self.cell = cell
        self.cells: dict[tuple[int, int, int], list[int]] = {}

    def key(self, x: FloatArray) -> tuple[int, int, int]:
        c = self.cell
        return (math.floor(x[0] / c), math.floor(x[1] / c), math.floor(x[2] / c))

    def add(self, j: int, x: FloatArray) -> None:
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


def _interferers(
    planes: list[tuple[FloatArray, FloatArray]], centres: FloatArray, radii: FloatArray
) -> Interferers:
    """Pack the interferers' half-spaces, centres and circumradius bounds for the kernel."""
    from regopack.plugins.available_surface.free_surface import Interferers

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


class AvailableSurface(InsertionStrategy):
    """Sequential insertion by available-surface analysis (see the module docstring)."""

    def __init__(self, config: AvailableSurfaceConfig | None = None) -> None:
        self.config = config or AvailableSurfaceConfig()

    def pack(
        self,
        population: Population,
        domain: object,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Insert the solids one by one; see the module docstring."""
        from regopack.domain3d import Box
        from regopack.plugins.available_surface.envelope import minkowski_envelope
        from regopack.plugins.available_surface.free_surface import (
            free_surface,
            sample_free_point,
        )
        from regopack.plugins.available_surface.halfspaces import edge_arcs, halfspaces_of_arcs
        from regopack.plugins.available_surface.polyhedron import Polyhedron
        from regopack.solids import SolidBatch

        started = time.perf_counter()
        shapes = population.shapes
        if not isinstance(domain, Box) or not isinstance(shapes, SolidBatch):
            raise ConfigError("insertion 'available-surface' packs solids in a 3D box")
        if domain.periodic:
            raise ConfigError(
                "insertion 'available-surface' packs walled boxes only so far; "
                "use domain.kind = 'box'"
            )
        if shapes.rounding is not None and np.any(shapes.rounding > 0):
            raise ConfigError(
                "insertion 'available-surface' packs sharp polyhedra only so far; "
                "spheres and rounded solids are not supported yet"
            )
        eta = getattr(controller, "eta", 0.0)
        if eta != 0.0 and not getattr(controller, "identity", False):
            raise ConfigError("insertion 'available-surface' supports density.eta = 0 only so far")
        n = len(population)
        t = self.config.t
        radius = np.asarray(population.radius, dtype=np.float64)
        polys = []
        for j in range(n):
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
        circum = shapes.circumradius
        arcs: list[Any] = [None] * n  # edge arcs of each placed particle, made on first use
        lo = np.array([domain.xmin, domain.ymin, domain.zmin])
        hi = np.array([domain.xmax, domain.ymax, domain.zmax])
        centre = np.full((n, 3), np.nan)
        index = np.full(n, -1, dtype=np.int64)
        order = np.full(n, -1, dtype=np.int64)
        rmin = np.full(n, np.inf)
        grid = _Grid(2.0 * float(circum.max()) if n else 1.0)
        count = 0
        analyses = empty = 0
        reach_max = 0.0
        for i in range(n):
            if progress is not None and i % PROGRESS_EVERY == 0:
                progress(i, count, n)
            q = polys[i]
            adm_lo = lo - q.vertices.min(axis=0)
            adm_hi = hi - q.vertices.max(axis=0)
            if np.any(adm_lo > adm_hi):
                continue  # larger than the box
            if count == 0:
                c = 0.5 * (lo + hi)
                if np.all(c >= adm_lo) and np.all(c <= adm_hi):
                    x = c
                else:
                    continue
            else:
                x = None
                halfspaces: dict[int, tuple[FloatArray, FloatArray]] = {}
                q_arcs = edge_arcs(q, -1.0)
                for k in np.flatnonzero(radius[i] < t * rmin[:count]):
                    pk = int(order[k])
                    envelope = minkowski_envelope(polys[pk], q)
                    reach = circum[pk] + reach_max + 2.0 * circum[i]
                    found = np.asarray(grid.near(centre[pk], reach), dtype=np.int64)
                    d = centre[found] - centre[pk]
                    lim = circum[pk] + circum[found] + 2.0 * circum[i]
                    hit = (np.einsum("ij,ij->i", d, d) < lim * lim) & (found != pk)
                    near = found[hit]
                    for j in near.tolist():
                        if j not in halfspaces:
                            if arcs[j] is None:
                                arcs[j] = edge_arcs(polys[j], 1.0)
                            halfspaces[j] = halfspaces_of_arcs(polys[j], arcs[j], q, q_arcs)
                    inter = _interferers(
                        [halfspaces[j] for j in near.tolist()],
                        centre[near],
                        circum[near] + circum[i],
                    )
                    analyses += 1
                    surface = free_surface(envelope, centre[pk], inter, adm_lo, adm_hi)
                    if surface.area > 0.0:
                        u = rng.random(3)
                        x = sample_free_point(surface, u[0], u[1], u[2])
                        break
                    empty += 1
                    rmin[k] = radius[i]
                if x is None:
                    continue
            centre[i] = x
            index[i] = count
            order[count] = i
            count += 1
            grid.add(i, centre[i])
            reach_max = max(reach_max, float(circum[i]))
        if progress is not None:
            progress(n, count, n)
        stats = {
            "candidate_analyses": float(analyses),
            "empty_analyses": float(empty),
            "insert_time_s": time.perf_counter() - started,
        }
        return InsertionResult(centre=centre, insertion_index=index, stats=stats)


@hookimpl
def regopack_inserters() -> Iterable[InserterSpec]:
    """Register the ``available-surface`` inserter."""
    return [
        InserterSpec(
            name="available-surface",
            config_model=AvailableSurfaceConfig,
            factory=AvailableSurface,
            description="Sequential insertion by available-surface analysis (3D polyhedra).",
            dimensions=(3,),
        )
    ]
