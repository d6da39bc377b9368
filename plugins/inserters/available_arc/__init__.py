"""Available-arc sequential insertion (SPEC §4), the paper's packing method.

Each particle, in population order, is offered to the inserted particles in
insertion order that pass the screening ``r_i < t * rmin_k``. For candidate
``k`` the feasible centres lie on the envelope ``E_k = P_k ⊕ (-Q)``; the parts
covered by interferers' envelopes or by the walls are removed, the density
controller trims the remaining arcs, and the centre is drawn uniformly in
polar angle over what is left.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError
from regopack.base.threads import kernel_threads
from regopack.geometry.domain import Domain, Rectangle
from regopack.geometry.population import Population
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
)
from regopack.registry.plugin_types import InserterSpec

if TYPE_CHECKING:
    from regopack.plugins.inserters.available_arc.batches import Helpers
    from regopack.plugins.inserters.available_arc.partner import PartnerThread
    from regopack.plugins.inserters.available_arc.state import ArcState
    from regopack.plugins.inserters.available_arc.sweep import Sweep

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

PROGRESS_EVERY = 256
SWEEP_POOL_ROWS = 4096
"""Neighbour-list rows the sweep starts with (the pool grows when a batch could exhaust it)."""


class AvailableArcConfig(BaseModel):
    """Parameters of the available-arc inserter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    t: ScreeningCoefficient = Field(
        0.999,
        description=(
            "Screening coefficient t in (0, 1]: candidate k is analysed when r_new < t * rmin_k."
        ),
    )
    interference: Literal["exact", "tau"] = Field(
        "exact",
        description=(
            "Interferer test: 'exact' (circumradii; never misses an interferer) or 'tau' "
            "(the paper's rule on equivalent radii; may miss interferers and leave overlaps)."
        ),
    )
    tau: float = Field(
        0.65,
        gt=0,
        le=1,
        allow_inf_nan=False,
        description="Threshold tau in (0, 1] of the 'tau' interference test (ignored by 'exact').",
    )
    first: Literal["center", "random"] = Field(
        "center",
        description=(
            "Where the first particle goes: the domain's 'center' or a 'random' feasible point."
        ),
    )
    neighbour_lists: bool = Field(
        True,
        description=(
            "Keep a neighbour list per particle (in a periodic box with the images): the "
            "same packing, faster in large domains, about 1.8 kB per particle; false uses "
            "the grid only."
        ),
    )
    order: Literal["paper", "sweep"] = Field(
        "paper",
        description=(
            "Which candidates a particle is offered to: 'paper' (every inserted particle, "
            "oldest first: the reference, grows from the centre and grades radially) or "
            "'sweep' (only those of a zone rising from the bottom of the domain: "
            "homogeneous, the same size mix everywhere; see docs/explanation/method.md)."
        ),
    )
    screening: Literal["paper", "exact"] = Field(
        "paper",
        description=(
            "What a refusal means: 'paper' (not placed when every candidate that passes the "
            "screening lacks arcs) or 'exact' (then also analysed, unscreened, at every "
            "candidate: not placed only when none has an arc; slower, places more). "
            "The sweep order always refuses exactly."
        ),
    )
    zone: SweepZone = 0.0
    closing: Literal["paced", "prompt", "tail"] = Field(
        "paced",
        description=(
            "How the sweep ends under the top wall: 'paced' (the last zone is offered as "
            "many particles as every zone before: denser and homogeneous to the top, but the "
            "coarse particles it cannot take are refused), 'prompt' (each refusal retires "
            "a bin: the particles left out are a random tail, the top band is looser) or "
            "'tail' (the first refusal under the top ends the run, that of the particle "
            "that lifted the zone there aside: every particle offered "
            "before it is placed, so the placed sizes are a sample of those drawn, and the "
            "rest of the population is a random tail left out; the top band is loose). "
            "Ignored by order = 'paper'."
        ),
    )
    strip: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Width of the sweep's strips (length units): the domain's width is cut into "
            "equal vertical strips of about this width, each with its own rising zone, and "
            "each particle is offered to the strip whose zone is lowest (or within a tenth "
            "of a zone of it, the strip offered the particles before), so that the work "
            "per particle no longer grows with the domain's width. 0: one zone across the "
            "whole width. Ignored by order = 'paper'."
        ),
    )
    lag: SweepLag = "pilot"
    search: Literal["indexed", "linear"] = Field(
        "indexed",
        description=(
            "Candidate search: 'indexed' (max-tree, fast) or 'linear' (the paper's "
            "scan; same packing)."
        ),
    )


class AvailableArc(InsertionStrategy):
    """Sequential insertion by available-arc analysis."""

    def __init__(self, config: AvailableArcConfig) -> None:
        self.config = config

    def scene_conflict(self, shapes: Sequence[str], density: str) -> tuple[str, str] | None:
        """Refuse a density controller other than ``eta`` for the sweep and exact screening."""
        cfg = self.config
        if density != "eta" and (cfg.order == "sweep" or cfg.screening == "exact"):
            option = (
                "insertion.order = 'sweep'"
                if cfg.order == "sweep"
                else "insertion.screening = 'exact'"
            )
            return (
                "density.kind",
                f"{density!r} is not the built-in 'eta' density controller, which {option} needs",
            )
        return None

    def may_overlap(self) -> bool:
        """Return True for the approximate ``tau`` interference test, which can overlap."""
        return self.config.interference == "tau"

    def pack(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Insert the particles one by one; see the module docstring.

        The built-in ``eta`` controller runs inside the compiled loop; any other
        controller is called from Python for every candidate with arcs. Both
        paths draw the same random numbers in the same order.
        """
        from regopack.plugins.density.eta import EtaController
        from regopack.plugins.inserters.available_arc import kernel
        from regopack.plugins.inserters.available_arc.state import ArcState

        cfg = self.config
        n = len(population)
        started = time.perf_counter()
        compiled = type(controller) is EtaController or controller.identity
        eta = controller.eta if type(controller) is EtaController else 0.0

        def new_state(population: Population, domain: Domain) -> ArcState:
            return ArcState(
                population,
                domain,
                t=cfg.t,
                tau=cfg.tau if cfg.interference == "tau" else None,
                linear=cfg.search == "linear",
                first_random=cfg.first == "random",
                eta=eta,
                neighbour_lists=cfg.neighbour_lists,
                # the sweep gives back the lists it leaves behind: start small, grow on demand
                pool_rows=SWEEP_POOL_ROWS if cfg.order == "sweep" else None,
            )

        st = new_state(population, domain)
        prepared = time.perf_counter()
        if cfg.order == "sweep":
            if not compiled:
                raise ConfigError(
                    "insertion.order = 'sweep' needs the built-in 'eta' density controller "
                    f"(got {type(controller).__name__})"
                )
            return _pack_sweep(
                st, new_state, population, domain, cfg, rng, progress, started, prepared
            )
        exact = cfg.screening == "exact"
        if exact and not compiled:
            raise ConfigError(
                "insertion.screening = 'exact' needs the built-in 'eta' density controller "
                f"(got {type(controller).__name__})"
            )
        counts = np.zeros(1, dtype=np.int64)
        placed = 0
        team = _partner_for(st) if compiled and not exact else None
        try:
            for begin in range(0, n, PROGRESS_EVERY):
                if progress is not None:
                    progress(begin, placed, n)
                end = min(begin + PROGRESS_EVERY, n)
                if exact:
                    placed += st.pack_range_exact(begin, end, rng, counts)
                elif compiled:
                    placed += st.pack_range(begin, end, rng, team)
                else:
                    placed += _pack_python(st, begin, end, controller, rng)
        finally:
            failure = team.stop() if team is not None else None
        if failure is not None:
            raise failure
        if progress is not None:
            progress(n, placed, n)
        index = np.full(n, -1, dtype=np.int64)
        order = st.packed.order[: st.count]
        index[order] = np.arange(order.shape[0])
        centre = np.column_stack([st.packed.cx, st.packed.cy])
        stats = {
            "candidate_analyses": st.counter(kernel.I_ANALYSES),
            "empty_analyses": st.counter(kernel.I_EMPTY),
            **({"rescued": int(counts[0])} if exact else {}),
            "prepare_time_s": prepared - started,
            "insert_time_s": time.perf_counter() - prepared,
        }
        return InsertionResult(centre=centre, insertion_index=index, stats=stats)


def _pack_sweep(
    st: ArcState,
    new_state: Callable[[Population, Domain], ArcState],
    population: Population,
    domain: Domain,
    cfg: AvailableArcConfig,
    rng: np.random.Generator,
    progress: ProgressCallback | None,
    started: float,
    prepared: float,
) -> InsertionResult:
    """Insert in the sweep order (see :mod:`regopack.plugins.inserters.available_arc.sweep`)."""
    from regopack.plugins.inserters.available_arc import batches, kernel, sweep
    from regopack.plugins.inserters.available_arc.lag import head, pilot_generator, pilot_lags

    n = len(population)
    bounds = domain.bounds()
    height = float(bounds[3] - bounds[2])
    zone = sweep_zone(cfg.zone, population.radius)
    width = float(bounds[1] - bounds[0])
    strip = cfg.strip
    if strip > 0.0 and n:
        # strips at least two circumradii of the largest particle wide: a narrower
        # strip's own candidates cannot hold up a front
        strip = max(strip, 2.0 * float(st.outlines.circum.max()))
        if sweep.strip_count(width, strip) > 1:
            # and a zone at least as high: a strip's next candidate is then always
            # within one zone of its top
            zone = max(zone, 2.0 * float(st.outlines.circum.max()))
    sw = sweep.Sweep(n, height, zone, closing=cfg.closing, width=width, strip=strip)
    lag_info: dict[str, Any] = {}
    if cfg.lag == "pilot":

        def run_pilot(m: int, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, IntArray, float]:
            pilot = Rectangle(float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
            pst = new_state(head(population, m), pilot)
            psw = sweep.Sweep(m, pilot.height, zone, closing="tail", width=pilot.width)
            _run_sweep(pst, psw, m, pilot_generator(rng), None, None)
            y = pst.packed.cy[:m] - pilot.ymin
            return y, psw.lags.top_at[:m], psw.delta

        lags, lag_info = pilot_lags(
            population.radius, bounds[0::2], bounds[1::2], zone, sw.delta, run_pilot
        )
        sw.set_lags(lags)
    threads = min(kernel_threads(), batches.MAX_THREADS) if n else 1
    helpers = batches.new_helpers(st.work, st.packed, threads if threads > 1 else 0)
    team = _partner_for(st)
    piloted = time.perf_counter()
    try:
        placed = _run_sweep(st, sw, n, rng, helpers, progress, team)
    finally:
        # an error that ended the partner is raised once the insertion is over, unless
        # the insertion itself failed (its own error then goes on)
        failure = team.stop() if team is not None else None
    if failure is not None:
        raise failure
    index = np.full(n, -1, dtype=np.int64)
    order = st.packed.order[: st.count]
    index[order] = np.arange(order.shape[0])
    centre = np.column_stack([st.packed.cx, st.packed.cy])
    refused = sw.refused
    stats = {
        "candidate_analyses": st.counter(kernel.I_ANALYSES),
        "empty_analyses": st.counter(kernel.I_EMPTY),
        "zone": float(zone),
        "zone_raises": sw.raises,
        "strips": sw.nstrip,
        "threads": threads,
        "partner": int(team is not None),
        "refused": refused,
        "not_offered": n - placed - refused,
        **lag_info,
        "prepare_time_s": prepared - started,
        **({"pilot_time_s": piloted - prepared} if cfg.lag == "pilot" else {}),
        "insert_time_s": time.perf_counter() - prepared,
    }
    return InsertionResult(centre=centre, insertion_index=index, stats=stats)


def _partner_for(st: ArcState) -> PartnerThread | None:
    """Return a partner thread for the screened searches of ``st``, or None.

    With two threads or more (numba's count) where threads can sleep (POSIX).
    In a scene of disks alone, whose analyses are too quick to hand over, the
    partner proves the disk bounds instead (see
    :mod:`~regopack.plugins.inserters.available_arc.bound_queue`). The packing is the
    same with it or without it.
    """
    from regopack.plugins.inserters.available_arc import kernel, partner

    if kernel_threads() < 2 or not partner.available():
        return None
    if st.packed.ipar[kernel.I_DISKS] == 1:
        if st.packed.ipar[kernel.I_BOUND] == kernel.BOUND_OFF:
            return None
        return partner.PartnerThread(st.work, st.packed, bounds=True)
    return partner.PartnerThread(st.work, st.packed)


def _run_sweep(
    st: ArcState,
    sw: Sweep,
    n: int,
    rng: np.random.Generator,
    helpers: Helpers | None,
    progress: ProgressCallback | None,
    team: PartnerThread | None = None,
) -> int:
    """Offer particles ``0 .. n - 1`` to ``sw`` in chunks; return how many were placed."""
    placed = 0
    for begin in range(0, n, PROGRESS_EVERY):
        if progress is not None:
            progress(begin, placed, n)
        end = min(begin + PROGRESS_EVERY, n)
        # every placement takes at most one list row: this chunk's particles, and
        # at the end those still waiting for their lag
        st.reserve_rows(end - begin + sw.waiting)
        placed += sw.run(
            begin, end, st.outlines, st.packed, st.work, rng, st.rounded, helpers, team
        )
    if progress is not None:
        progress(n, placed, n)
    return placed


def _pack_python(
    st: ArcState, begin: int, end: int, controller: DensityController, rng: np.random.Generator
) -> int:
    """Insert particles ``begin`` to ``end - 1`` calling ``controller`` from Python."""
    from regopack.plugins.inserters.available_arc import kernel

    radius = st.outlines.req
    placed = 0
    for i in range(begin, end):
        if st.count == 0:
            placed += st.place_first(i, rng)
            continue
        mq = st.begin_particle(i)
        start = 0
        while True:
            k, arcs = st.find_site(i, start, mq)
            if k < 0:
                break
            arcs = controller.shrink(arcs, float(radius[i]), float(radius[st.packed.order[k]]), rng)
            if arcs.shape[0] == 0:
                st.reject(k, float(radius[i]))
                start = k + 1
                continue
            angle = float(
                kernel.sample_angle(np.ascontiguousarray(arcs, dtype=np.float64), rng.random())
            )
            x, y = st.locate(k, i, mq, angle)
            st.insert(i, x, y)
            placed += 1
            break
    return placed


@hookimpl
def regopack_inserters() -> Iterable[InserterSpec]:
    """Register the ``available-arc`` inserter."""
    return [
        InserterSpec(
            name="available-arc",
            config_model=AvailableArcConfig,
            factory=AvailableArc,
            description="Sequential insertion by available-arc analysis (the paper's method).",
        )
    ]
