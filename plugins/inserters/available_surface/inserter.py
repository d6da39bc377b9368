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
  a cylinder's side wall is taken as its inscribed regular prism
  (:mod:`.prism_wall`), within ``wall_gap`` smallest diameters of the wall;
- the free part of ``∂E_k`` is computed exactly as convex polygons
  (:func:`free_surface.free_surface`), and the centre is drawn uniformly **by
  area** on it (:func:`free_surface.sample_free_point`, three uniform
  numbers from the run's generator).

By area rather than by solid angle about ``c_k``: area is what a uniform
random contact means on a polyhedral envelope, it is exact with planar
pieces, and it does not favour the faces that happen to lie close to the
candidate's centre. A candidate without free area records ``rmin_k = r_Q``;
a particle that no candidate takes is not placed.

Candidates are offered in the paper's order (``order = "paper"``) or in
the sweep order (``order = "sweep"``, :mod:`.sweep`); the box may be walled
or periodic (:class:`.state.SurfaceState`); the ``eta`` controller keeps
the free surface a margin from what covers it
(:func:`.analysis.eta_margin`). Spheres are analysed in closed form
(:mod:`.spheres`); after a sphere candidate's first analysis finds it
empty, and before each later analysis, the
candidate is tried for *shutting* from the next of a few levels of radius
below (quantiles of the population's radii, :func:`.state.shut_levels`):
when the caps of a sphere of that radius cover its sphere of centres with
room to spare, no sphere of that radius or more will ever touch it
(:func:`.analysis.sphere_shut`): a later sphere that large that the
screening lets through is taken as an empty analysis without one — the
same screening, random numbers and packing, with fewer analyses (the 3D
counterpart of the disks' bounds in 2D).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box, Cylinder, Domain
from regopack.geometry.population import Population
from regopack.plugins.inserters.available_surface.prism_wall import NO_WALL, prism_wall
from regopack.plugins.inserters.options import ZONE_PER_RADIUS as ZONE_PER_RADIUS
from regopack.plugins.inserters.options import (
    ScreeningCoefficient,
    SweepLag,
    SweepZone,
    sweep_zone,
)
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
    TileTask,
)
from regopack.registry.plugin_types import InserterSpec

if TYPE_CHECKING:
    from regopack.geometry.solids import SolidBatch
    from regopack.plugins.inserters.available_surface.state import SurfaceState
    from regopack.plugins.inserters.available_surface.sweep import SurfaceSweep

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

PROGRESS_EVERY = 500
"""Particles between progress reports."""

FACET_PER_DIAMETER = 4.0
"""Default side of the faceted front's pyramids, in largest equivalent diameters."""


class AvailableSurfaceConfig(BaseModel):
    """Parameters of the available-surface inserter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    t: ScreeningCoefficient = Field(
        0.999,
        description=(
            "Screening coefficient t in (0, 1]: candidate k is analysed for a particle of "
            "radius r only when r < t * rmin_k, the smallest radius it refused."
        ),
    )
    first: Literal["center"] = Field(
        "center",
        description=(
            "Where the first particle goes in the paper's order: the box's 'center' "
            "(the sweep starts at the bottom of the box below its centre)."
        ),
    )
    order: Literal["paper", "sweep"] = Field(
        "paper",
        description=(
            "Which candidates a particle is offered to: 'paper' (every placed particle, "
            "oldest first: grows from the centre and grades radially) or 'sweep' (only "
            "those of a zone rising from the bottom of the box: homogeneous, and its cost "
            "per particle does not grow with the box; see docs/explanation/method.md)."
        ),
    )
    zone: SweepZone = 0.0
    closing: Literal["paced", "prompt", "tail", "even"] = Field(
        "paced",
        description=(
            "How the sweep ends under the top wall, as in 2D: 'paced', 'prompt' or 'tail' "
            "(see the available-arc inserter); or 'even': paced, but once a column's zone "
            "has reached the top a particle whose sqrt(2) size class is placed in a larger "
            "share of those offered than the least placed class is held back, so that the "
            "particles not placed are spread over the sizes (the placed sizes true to the "
            "drawn ones, the top band looser and coarser). Ignored by order = 'paper'."
        ),
    )
    strip: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Width of the sweep's columns (length units): the box's floor is cut into equal "
            "tiles of about this width (at least two circumradii of the largest particle), "
            "each column with its own rising zone, and each particle is offered to the "
            "column whose zone is lowest, as the 2D strips; 0: one zone over the whole "
            "floor. Ignored by order = 'paper'."
        ),
    )
    # 'none' by default in 3D: with the paced closing the lags leave the top loose
    # (docs/development/2026-12-07-3d-lags.md)
    lag: SweepLag = "none"
    front: Literal["bottom-up", "faceted"] = Field(
        "bottom-up",
        description=(
            "The shape of the sweep's front: 'bottom-up' (flat, rising along z: a deposited "
            "layer whose contact normals lean vertical) or 'faceted' (a field of square "
            "pyramids whose faces slope at a cube's corner angle and move along their "
            "normals: a fabric far less anisotropic, for a representative volume). Only "
            "with order = 'sweep'."
        ),
    )
    facet: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Side of the faceted front's pyramids (length units): the box's floor is cut "
            "into equal squares of about this side; 0: four times the largest equivalent "
            "diameter. Only with front = 'faceted'."
        ),
    )

    facet_slope: float | None = Field(
        None,
        gt=0,
        lt=90,
        allow_inf_nan=False,
        description=(
            "Angle in degrees between the faceted front's face normals and z; default: a "
            "cube's corner, arctan(sqrt(2)) = 54.7 degrees, whose four normals have an "
            "isotropic second moment (spheres pack isotropic there). Polyhedra keep a "
            "vertical lean at that angle; 65-72 degrees halve it (see "
            "docs/how-to/deposited-or-isotropic.md). Only with front = 'faceted'."
        ),
    )
    wall_gap: float = Field(
        1e-3,
        gt=0,
        le=1,
        allow_inf_nan=False,
        description=(
            "Cylinders only: the largest gap, as a fraction of the smallest particle's "
            "equivalent diameter, that a particle touching the side wall may keep from it. "
            "The analyses take the wall as the regular prism inscribed in it whose facets lie "
            "at most this far inside; a smaller gap means more facets near each candidate."
        ),
    )

    @model_validator(mode="after")
    def _facet_with_its_front(self) -> AvailableSurfaceConfig:
        if self.facet > 0.0 and self.front != "faceted":
            raise ValueError(
                f"facet = {self.facet} sizes the faceted front's pyramids: give "
                "front = 'faceted' with it, or leave facet out"
            )
        if self.facet_slope is not None and self.front != "faceted":
            raise ValueError(
                f"facet_slope = {self.facet_slope} tilts the faceted front's faces: give "
                "front = 'faceted' with it, or leave facet_slope out"
            )
        if self.front == "faceted" and self.order != "sweep":
            raise ValueError("front = 'faceted' is a front of the sweep: give order = 'sweep'")
        return self


class AvailableSurface(InsertionStrategy):
    """Sequential insertion by available-surface analysis (see the module docstring)."""

    def __init__(self, config: AvailableSurfaceConfig | None = None) -> None:
        self.config = config or AvailableSurfaceConfig()

    def may_overlap(self) -> bool:
        """Say yes, so that every 3D run is checked by the independent oracle.

        The envelopes are exact up to a tolerance scaled by the particles; a
        run of solids checks its packing with Qhull and HiGHS
        (:mod:`regopack.verification.polyhedra`) unless told not to.
        """
        return True

    def scene_conflict(self, shapes: Sequence[str], density: str) -> tuple[str, str] | None:
        """Refuse a non-``eta`` density controller and spheres mixed with polyhedra."""
        if density != "eta":
            return (
                "density.kind",
                f"{density!r} is not the built-in 'eta' density controller, which "
                "insertion 'available-surface' needs",
            )
        spheres = [kind == "sphere" for kind in shapes]
        if any(spheres) and not all(spheres):
            first = spheres.index(not spheres[0])
            return (
                f"phases.{first}.shape.kind",
                f"{shapes[first]!r} beside {shapes[0]!r} in phase 0: insertion "
                "'available-surface' packs spheres or polyhedra, not both in one scene; "
                "give every phase the same kind of shape",
            )
        return None

    packs_tiles: ClassVar[bool] = True

    def _box(
        self, population: Population, domain: Domain, controller: DensityController
    ) -> tuple[SolidBatch, FloatArray, FloatArray, FloatArray, FloatArray, float]:
        """Check what this inserter packs; return shapes, radii, box corners, wall and eta."""
        from regopack.geometry.solids import SolidBatch

        shapes = population.shapes
        if not isinstance(domain, Box | Cylinder) or not isinstance(shapes, SolidBatch):
            raise ConfigError("insertion 'available-surface' packs solids in a 3D box or cylinder")
        rounding = shapes.rounding_radius
        spheres = shapes.normals.shape[0] == 0 and bool(np.all(rounding > 0))
        if np.any(rounding > 0) and not spheres:
            raise ConfigError(
                "insertion 'available-surface' packs sharp polyhedra or spheres, not both in "
                "one scene nor rounded polyhedra; give every phase the same kind of shape"
            )
        from regopack.plugins.density.eta import EtaController

        if not isinstance(controller, EtaController):
            raise ConfigError(
                "insertion 'available-surface' needs the built-in 'eta' density controller "
                "(density.kind = 'eta')"
            )
        radius = np.asarray(population.radius, dtype=np.float64)
        bounds = domain.bounds()
        lo = np.ascontiguousarray(bounds[0::2])
        hi = np.ascontiguousarray(bounds[1::2])
        wall = NO_WALL
        if isinstance(domain, Cylinder) and len(population):
            d_min = 2.0 * float(np.min(radius))
            wall = prism_wall(domain.cx, domain.cy, domain.radius, d_min, self.config.wall_gap)
        return shapes, radius, lo, hi, wall, float(controller.eta)

    def pack(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Insert the solids one by one; see the module docstring."""
        from regopack.plugins.inserters.available_surface.state import SurfaceState

        started = time.perf_counter()
        shapes, radius, lo, hi, wall, eta = self._box(population, domain, controller)
        n = len(population)
        st = SurfaceState(
            shapes, radius, lo, hi, periodic=bool(domain.periodic), t=self.config.t, eta=eta,
            wall=wall,
        )  # fmt: skip
        stats = self._run(st, shapes, radius, n, 0, rng, progress)
        stats["insert_time_s"] = time.perf_counter() - started
        return InsertionResult(centre=st.centre, insertion_index=st.index, stats=stats)

    def pack_tile(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        tile: TileTask,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Pack one tile in the sweep order: centres in its window, against its obstacles.

        The obstacles are placed first, lowest first, and filed as the sweep's
        candidates; the tile's particles are then offered as in :meth:`pack`,
        with the window bounding every centre (and the sweep's columns cut
        over the window). In a periodic box the box is taken about the
        window (the same box, another image), so that the obstacles' images
        next to the window are the ones analysed.
        """
        from regopack.geometry.solids import join_solids
        from regopack.plugins.inserters.available_surface.state import SurfaceState

        started = time.perf_counter()
        cfg = self.config
        conflict = self.tile_conflict()
        if conflict is not None:
            raise ConfigError(f"{conflict[0]}: {conflict[1]}")
        own, radius, lo, hi, wall, eta = self._box(population, domain, controller)
        obstacles = tile.obstacles
        if not isinstance(obstacles, type(own)):
            raise ConfigError("tiles: the obstacles of a 3D tile must be solids")
        m = len(obstacles)
        n_own = len(population)
        w_lo = np.array(tile.lo, dtype=np.float64)
        w_hi = np.array(tile.hi, dtype=np.float64)
        if domain.periodic:
            # the box about the window: its periodic images sit next to the window
            period = hi - lo
            bounded = np.isfinite(w_lo) & np.isfinite(w_hi)
            mid = np.where(
                bounded, 0.5 * (np.where(bounded, w_lo, 0) + np.where(bounded, w_hi, 0)), 0
            )
            lo = np.where(bounded, mid - 0.5 * period, lo)
            hi = lo + period
        order = np.lexsort((np.arange(m), tile.obstacle_centre[:, 2])) if m else np.zeros(0, int)
        shapes = join_solids([obstacles.take(order), own])
        radius_all = np.concatenate([np.asarray(tile.obstacle_radius, float)[order], radius])
        st = SurfaceState(
            shapes, radius_all, lo, hi, periodic=bool(domain.periodic), t=cfg.t, eta=eta,
            wall=wall, window=(w_lo, w_hi),
        )  # fmt: skip
        centres = np.asarray(tile.obstacle_centre, dtype=np.float64)[order]
        for j in range(m):
            st.insert(j, centres[j])
        stats = self._run(st, shapes, radius_all, st.n, m, rng, progress, floor=(w_lo, w_hi))
        centre = st.centre[m:].copy()
        index = st.index[m:].copy()
        placed = index >= 0
        index[placed] -= m
        stats["insert_time_s"] = time.perf_counter() - started
        stats["obstacles"] = float(m)
        assert centre.shape[0] == n_own
        return InsertionResult(centre=centre, insertion_index=index, stats=stats)

    def tile_conflict(self) -> tuple[str, str] | None:
        """Refuse the paper's order and the pilot's lags in tiles (the sweep packs tiles)."""
        cfg = self.config
        if cfg.order != "sweep":
            return (
                "insertion.order",
                f"{cfg.order!r}: a tiled scene is packed in the sweep order; give 'sweep' "
                "or leave tiles out",
            )
        if cfg.lag == "pilot":
            return (
                "insertion.lag",
                "'pilot' is not available in tiles; give 'none' or leave tiles out",
            )
        return None

    def _run(
        self,
        st: SurfaceState,
        shapes: SolidBatch,
        radius: FloatArray,
        n: int,
        first: int,
        rng: np.random.Generator,
        progress: ProgressCallback | None,
        floor: tuple[FloatArray, FloatArray] | None = None,
    ) -> dict[str, float]:
        """Insert particles ``first..n - 1`` of ``st`` with a partner thread; return the stats."""
        partner = st.start_partner()
        try:
            stats = _insert(st, shapes, radius, self.config, n, rng, progress, first, floor)
        finally:
            failure = st.stop_partner()
        # an error that ended the partner is raised once the insertion is over, unless
        # the insertion itself failed (its own error then went on)
        if failure is not None:
            raise failure
        if progress is not None:
            progress(n - first, st.count - first, n - first)
        return {
            "candidate_analyses": float(st.analyses),
            "empty_analyses": float(st.empty),
            **(
                {
                    "shut_tests": float(st.shut_tests),
                    "shut": float(st.shut),
                    "analyses_saved": float(st.saved),
                }
                if st.spheres
                else {}
            ),
            **stats,
            "partner": float(partner),
        }


def _insert(
    st: SurfaceState,
    shapes: SolidBatch,
    radius: FloatArray,
    cfg: AvailableSurfaceConfig,
    n: int,
    rng: np.random.Generator,
    progress: ProgressCallback | None,
    first: int = 0,
    floor: tuple[FloatArray, FloatArray] | None = None,
) -> dict[str, float]:
    """Insert particles ``first..n - 1`` in the configured order; return the order's statistics.

    The particles before ``first`` are placed already (a tile's obstacles:
    the sweep takes them as candidates); ``floor`` bounds the sweep's
    columns (a tile's window).
    """
    from regopack.plugins.inserters.available_surface.sweep import (
        STATUS_HELD,
        STATUS_REFUSED,
        SurfaceSweep,
    )

    stats: dict[str, float] = {}
    if cfg.order == "sweep":
        zone = sweep_zone(cfg.zone, radius)
        strip = cfg.strip
        if strip > 0.0 and n:
            # columns at least two circumradii of the largest particle wide: a
            # narrower column's own candidates cannot hold up a front
            strip = max(strip, 2.0 * float(np.max(shapes.circumradius)))
        facet = 0.0
        if cfg.front == "faceted":
            facet = cfg.facet or FACET_PER_DIAMETER * 2.0 * float(np.max(radius, initial=0.5))
        sweep = SurfaceSweep(
            st, cfg.t, zone, cfg.closing, strip, cfg.front, facet, cfg.facet_slope, floor
        )
        sweep.seed_with(first)
        if cfg.lag == "pilot":
            piloted = time.perf_counter()
            lags, info = _pilot_lags(st, shapes, radius, cfg, sweep, rng)
            sweep.set_lags(lags)
            stats.update({k: float(v) for k, v in info.items()})
            stats["pilot_time_s"] = time.perf_counter() - piloted
        sweep.run(rng, progress, PROGRESS_EVERY, first)
        refused = int(np.count_nonzero(sweep.status[first:n] == STATUS_REFUSED))
        held = int(np.count_nonzero(sweep.status[first:n] == STATUS_HELD))
        stats = {
            **stats,
            "zone": float(sweep.zone),
            "zone_raises": float(sweep.raises),
            "strips": float(len(sweep.zones)),
            "refused": float(refused),
            **({"held": float(held)} if cfg.closing == "even" else {}),
            "not_offered": float(n - st.count - refused - held),  # obstacles: first = placed
        }
    else:
        _pack_paper(st, rng, progress)
    return stats


def _pilot_lags(
    st: SurfaceState,
    shapes: SolidBatch,
    radius: FloatArray,
    cfg: AvailableSurfaceConfig,
    sweep: SurfaceSweep,
    rng: np.random.Generator,
) -> tuple[IntArray, dict[str, float]]:
    """Return each particle's lag in the run's bins, and what the pilot measured.

    The pilot sweep (:mod:`regopack.plugins.inserters.available_arc.lag`) runs with the
    run's settings in a walled box on the floor and draws from a generator of its own.
    """
    from regopack.plugins.inserters.available_arc.lag import pilot_generator, pilot_lags
    from regopack.plugins.inserters.available_surface.state import SurfaceState
    from regopack.plugins.inserters.available_surface.sweep import SurfaceSweep

    def run_pilot(m: int, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, IntArray, float]:
        pst = SurfaceState(shapes.head(m), radius[:m], lo, hi, t=cfg.t, eta=st.eta)
        psw = SurfaceSweep(pst, cfg.t, sweep.zone, "tail")
        psw.run(pilot_generator(rng))
        return pst.centre[:, 2] - lo[2], psw.top_at[:m], psw.delta

    return pilot_lags(radius, st.lo, st.hi, sweep.zone, sweep.delta, run_pilot)


def _pack_paper(
    st: SurfaceState, rng: np.random.Generator, progress: ProgressCallback | None
) -> None:
    """Insert in the paper's order: every placed particle, oldest first, screened by ``t``."""
    n = st.n
    for i in range(n):
        if progress is not None and i % PROGRESS_EVERY == 0:
            progress(i, st.count, n)
        if not st.begin(i):
            continue  # larger than the box
        if st.count == 0:
            c = 0.5 * (st.lo + st.hi)
            if st.fits_at(c):
                st.insert(i, c)
            continue
        _, x = st.scan(np.arange(st.count), rng)
        if x is not None:
            st.insert(i, x)


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
