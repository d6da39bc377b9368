"""Packing one scene in tiles: each tile drawn from its own stream, packed by colour.

The schedule (:mod:`.layout`) packs the tiles of one colour at a time: they
cannot reach one another, so they are independent tasks, and each packs
against the particles of the tiles of earlier colours that its particles
can reach (its *obstacles*). Every tile draws its share of the scene's
particles from its own stream, a child of the scene's seed
(``numpy.random.SeedSequence(seed).spawn``), and then packs with the same
generator, so a tile's particles depend on its index, its window and its
obstacles only: the packing is the same whichever workers pack the tasks
and in whatever order they finish.

A first round draws every tile to learn the largest circumradius (the reach
that decides which obstacles a tile needs, and whether the tiles are wide
enough to be packed side by side); each packing task draws its tile again
from the same stream, which costs a second draw but sends no particles to
the workers.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box, PeriodicBox
from regopack.geometry.population import Population
from regopack.geometry.solids import SolidBatch, join_solids
from regopack.registry.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
    TileTask,
)
from regopack.scenes.model import ResolvedScene
from regopack.tiling.executors import TileExecutor
from regopack.tiling.layout import Tile, TileLayout, tile_layout

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SUMMED_STATS = (
    "candidate_analyses",
    "empty_analyses",
    "shut_tests",
    "shut",
    "analyses_saved",
    "zone_raises",
    "refused",
    "held",
    "not_offered",
    "obstacles",
    "scaffold",
)
"""Statistics of the tiles that the packing's statistics add up."""

REACH_SLACK = 1e-9
"""Relative slack on the reach that selects a tile's obstacles (rounding of the distances)."""

MARGIN_DIAMETERS = 1.0
"""A tile's margin beyond its window, in largest equivalent diameters of the size distribution."""


@dataclass(frozen=True)
class TileJob:
    """What a worker needs to draw and pack one tile (plain, picklable data)."""

    scene: dict[str, Any]
    index: int
    count: int
    seed: np.random.SeedSequence
    layout: TileLayout


@dataclass
class TileOutcome:
    """One packed tile: its particles, where they went, and its statistics."""

    index: int
    population: Population
    centre: FloatArray
    insertion_index: IntArray
    stats: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0


_RESOLVED: dict[str, ResolvedScene] = {}


def _resolve(data: dict[str, Any]) -> ResolvedScene:
    """Resolve the scene ``data`` once per process (with the default plugin registry)."""
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import resolve_scene, scene_from_dict

    key = json.dumps(data, sort_keys=True, default=str)
    resolved = _RESOLVED.get(key)
    if resolved is None:
        resolved = resolve_scene(scene_from_dict(data), default_registry())
        _RESOLVED.clear()  # one scene at a time per process
        _RESOLVED[key] = resolved
    return resolved


def _draw(job: TileJob) -> tuple[ResolvedScene, Population, np.random.Generator]:
    """Draw tile ``job``'s particles from its stream; return the generator, which packs next."""
    from regopack.run.pipeline import draw_population

    resolved = _resolve(job.scene)
    rng = np.random.Generator(np.random.PCG64(job.seed))
    return resolved, draw_population(resolved, rng, job.count), rng


def tile_reach(job: TileJob) -> float:
    """Return the largest circumradius of tile ``job``'s particles (0 for none)."""
    _, population, _ = _draw(job)
    if len(population) == 0:
        return 0.0
    shapes = population.shapes
    if isinstance(shapes, SolidBatch):
        return float(np.max(shapes.circumradius))
    return float(np.max(population.circumradius))


def tile_pack(job: TileJob, task: TileTask) -> TileOutcome:
    """Draw tile ``job``, pack it against ``task``'s obstacles, keep what it owns.

    The tile packs in its window grown by a margin (``task``'s window); its
    particles whose centres fall in the window of a tile packed after it are
    the scaffold that gave the particles next to them the surroundings of the
    bulk: they are dropped (from the population too). Those in its own window
    or in the window of a tile packed before it are kept.
    """
    from regopack.run.pipeline import _build

    start = time.perf_counter()
    resolved, population, rng = _draw(job)
    inserter: InsertionStrategy = _build(resolved.insertion, InsertionStrategy, "insertion")
    controller: DensityController = _build(resolved.density, DensityController, "density")
    result = inserter.pack_tile(population, resolved.domain, controller, rng, task)
    centre = np.array(result.centre, dtype=np.float64)
    domain = resolved.domain
    if domain.periodic:  # back from the image about the window into the domain's box
        bounds = domain.bounds()
        lo, hi = bounds[0::2], bounds[1::2]
        with np.errstate(invalid="ignore"):
            centre = lo + np.mod(centre - lo, hi - lo)
            centre = np.where(centre >= hi, lo, centre)
    index = np.asarray(result.insertion_index, dtype=np.int64)
    layout = job.layout
    colour = layout.tiles[job.index].colour
    placed = np.flatnonzero(index >= 0)
    owner = layout.owner(centre[placed])
    owner_colour = np.array([layout.tiles[int(o)].colour for o in owner], dtype=np.int64)
    scaffold = placed[(owner != job.index) & (owner_colour >= colour)]
    keep = np.setdiff1d(np.arange(len(population)), scaffold)
    index = index[keep]
    kept = index >= 0
    # the kept particles' insertion order, renumbered without the scaffold
    ranks = np.empty(int(kept.sum()), dtype=np.int64)
    ranks[np.argsort(index[kept], kind="stable")] = np.arange(ranks.shape[0])
    index[kept] = ranks
    stats = dict(result.stats)
    stats["scaffold"] = float(scaffold.shape[0])
    return TileOutcome(
        index=job.index,
        population=_take(population, keep),
        centre=centre[keep],
        insertion_index=index,
        stats=stats,
        seconds=time.perf_counter() - start,
    )


def _take(population: Population, idx: IntArray) -> Population:
    """Return the particles ``idx`` of a population of solids."""
    shapes = population.shapes
    assert isinstance(shapes, SolidBatch)
    return Population(
        radius=np.asarray(population.radius)[idx],
        mineral=np.asarray(population.mineral)[idx],
        mineral_names=population.mineral_names,
        shapes=shapes.take(idx),  # type: ignore[arg-type]
    )


def _tile_pack_args(args: tuple[TileJob, TileTask]) -> TileOutcome:
    return tile_pack(*args)


def split_count(n: int, shares: Sequence[float]) -> list[int]:
    """Split ``n`` particles over tiles by their shares (largest remainders, ties by index).

    Examples
    --------
    >>> split_count(10, [0.25, 0.25, 0.25, 0.25])
    [3, 3, 2, 2]
    """
    exact = np.asarray(shares, dtype=np.float64) * n
    base = np.floor(exact).astype(np.int64)
    left = n - int(base.sum())
    order = np.lexsort((np.arange(len(base)), -(exact - base)))
    base[order[:left]] += 1
    return [int(v) for v in base]


def check_tiled(resolved: ResolvedScene) -> None:
    """Refuse, in one line, a tiled scene whose domain or inserter cannot be tiled."""
    tiles = resolved.scene.tiles
    if tiles is None:
        return
    domain = resolved.domain
    if type(domain) not in (Box, PeriodicBox):
        raise ConfigError(
            f"{tiles.label()}: domain kind {domain.kind!r} is not tiled; "
            "tiles cover a 3D 'box' or 'periodic-box'"
        )
    inserter = resolved.insertion.build()
    if not getattr(inserter, "packs_tiles", False):
        raise ConfigError(
            f"{tiles.label()}: insertion {resolved.insertion.kind!r} does not "
            "pack tiles; leave tiles out"
        )
    conflict = inserter.tile_conflict()
    if conflict is not None:
        field, reason = conflict
        raise ConfigError(f"{tiles.label()}: {field} = {reason}")


def layout_of(resolved: ResolvedScene) -> TileLayout:
    """Return the tiles of ``resolved`` (a tiled scene)."""
    tiles = resolved.scene.tiles
    assert tiles is not None
    domain = resolved.domain
    bounds = domain.bounds()
    floor = domain.dimension - 1
    if isinstance(tiles.side, list) and len(tiles.side) != floor:
        raise ConfigError(
            f"{tiles.label()}: a {domain.dimension}D domain has {floor} floor "
            f"ax{'is' if floor == 1 else 'es'}; give one side or {floor}"
        )
    try:
        return tile_layout(
            bounds[0::2], bounds[1::2], domain.dimension, bool(domain.periodic),
            tiles.sides(floor),
        )  # fmt: skip
    except ValueError as err:
        raise ConfigError(f"{tiles.label()}: {err}") from None


@dataclass
class _Done:
    """The particles of the tiles packed so far, for choosing obstacles."""

    centre: list[FloatArray] = field(default_factory=list)
    circum: list[FloatArray] = field(default_factory=list)
    radius: list[FloatArray] = field(default_factory=list)
    shapes: list[SolidBatch] = field(default_factory=list)
    order: list[IntArray] = field(default_factory=list)

    def add(self, outcome: TileOutcome) -> None:
        placed = outcome.insertion_index >= 0
        idx = np.flatnonzero(placed)
        idx = idx[np.argsort(outcome.insertion_index[idx], kind="stable")]
        shapes = outcome.population.shapes
        assert isinstance(shapes, SolidBatch)
        self.centre.append(outcome.centre[idx])
        self.circum.append(shapes.circumradius[idx])
        self.radius.append(np.asarray(outcome.population.radius)[idx])
        self.shapes.append(shapes.take(idx))
        self.order.append(idx)

    def near(self, layout: TileLayout, tile: Tile, reach: float) -> TileTask:
        """Return ``tile``'s obstacles: done particles within ``reach`` plus their circumradius."""
        parts: list[SolidBatch] = []
        centres: list[FloatArray] = []
        radii: list[FloatArray] = []
        for centre, circum, radius, shapes in zip(
            self.centre, self.circum, self.radius, self.shapes, strict=True
        ):
            if centre.shape[0] == 0:
                continue
            gap = layout.floor_gap(tile, centre)
            pick = np.flatnonzero(gap < (circum + reach) * (1.0 + REACH_SLACK))
            if pick.shape[0] == 0:
                continue
            parts.append(shapes.take(pick))
            centres.append(centre[pick])
            radii.append(radius[pick])
        dim = tile.lo.shape[0]
        return TileTask(
            lo=_window(layout, tile, 0),
            hi=_window(layout, tile, 1),
            obstacles=join_solids(parts) if parts else SolidBatch.of_spheres(np.zeros(0)),
            obstacle_centre=np.concatenate(centres) if centres else np.zeros((0, dim)),
            obstacle_radius=np.concatenate(radii) if radii else np.zeros(0),
        )


def _area(tile: Tile, layout: TileLayout) -> float:
    """Return the floor area (a length in the plane) of a tile's window."""
    return float(np.prod(tile.hi[: layout.floor_axes] - tile.lo[: layout.floor_axes]))


def _window(layout: TileLayout, tile: Tile, side: int) -> FloatArray:
    """Return the tile's centre window along the floor, unbounded along the vertical."""
    out = np.array(tile.lo if side == 0 else tile.hi, dtype=np.float64)
    out[layout.floor_axes :] = -np.inf if side == 0 else np.inf
    return out


@dataclass(frozen=True)
class TiledPacking:
    """A tiled packing: where its particles went, the particles, and the tile of each."""

    result: InsertionResult
    population: Population
    tile: IntArray
    """``(n,)`` index of the tile that drew and packed each particle."""


def pack_tiled(
    resolved: ResolvedScene,
    controller: DensityController,
    executor: TileExecutor,
    progress: ProgressCallback | None = None,
) -> TiledPacking:
    """Pack ``resolved`` (a tiled scene) tile by tile.

    The population lists the tiles' particles tile by tile (in the tiles'
    index order); the insertion order runs through the colours, and within a
    colour through the tiles in index order.

    Raises
    ------
    ConfigError
        When the tiles are narrower than two margins and two largest
        circumradii (tiles of one colour could then meet), or the scene
        cannot be tiled.
    """
    from regopack.registry.interfaces import SizeDistribution
    from regopack.run.pipeline import _build, check_scene

    start = time.perf_counter()
    check_tiled(resolved)
    tiles_cfg = resolved.scene.tiles
    assert tiles_cfg is not None
    n = check_scene(resolved)
    layout = layout_of(resolved)
    shares = [layout.share(t) for t in layout.tiles]
    counts = split_count(n, shares)
    seeds = np.random.SeedSequence(resolved.seed).spawn(len(layout.tiles))
    data = resolved.to_dict()
    # the scene a tile resolves: its own draws, no outputs of its own
    data["outputs"] = {"packing": "packing.npz", "summary": "summary.json", "fabric": False}
    # the margin: one largest equivalent diameter of the size distribution, known before any
    # particle is drawn, so that each tile's count (its share and its margin's) is fixed first
    size_dist: SizeDistribution = _build(resolved.size, SizeDistribution, "size")
    margin = MARGIN_DIAMETERS * 2.0 * float(size_dist.r_max) if len(layout.tiles) > 1 else 0.0
    grown = [layout.grown(t, margin) if len(layout.tiles) > 1 else t for t in layout.tiles]
    # each tile draws for its grown window too: the particles it drops there are extra
    jobs = [
        TileJob(
            data,
            t.index,
            counts[t.index] + round(counts[t.index] * (_area(g, layout) / _area(t, layout) - 1)),
            seeds[t.index],
            layout,
        )
        for t, g in zip(layout.tiles, grown, strict=True)
    ]
    # the reach: the largest circumradius of the particles the tiles will pack (the same
    # draws as the packing tasks make)
    reach = max(executor.map(tile_reach, jobs), default=0.0)
    eta = float(getattr(controller, "eta", 0.0) or 0.0)
    # the packing control keeps particles up to eta/100 of a diameter apart: so much more reach
    reach *= 1.0 + max(eta, 0.0) / 50.0
    # only axes cut into several tiles need the width (a strip spans its other axis)
    cut = [a for a, n in enumerate(layout.counts) if n > 1]
    narrowest = min((float(t.hi[a] - t.lo[a]) for t in layout.tiles for a in cut), default=math.inf)
    least = 2.0 * margin + 2.0 * reach
    if len(layout.tiles) > 1 and narrowest < least:
        raise ConfigError(
            f"{tiles_cfg.label()}: tiles {narrowest:g} wide are narrower than two margins "
            f"and two largest circumradii ({least:g}); give tiles.side >= {least:g}"
        )
    outcomes: dict[int, TileOutcome] = {}
    done = _Done()
    total = sum(job.count for job in jobs)
    for colour in range(layout.colours):
        phase = layout.phase(colour)
        if not phase:
            continue
        tasks = [(jobs[t.index], done.near(layout, grown[t.index], reach)) for t in phase]

        def report(_: int, outcome: TileOutcome) -> None:
            outcomes[outcome.index] = outcome
            if progress is not None:
                drawn = sum(jobs[i].count for i in outcomes)
                placed = sum(
                    int(np.count_nonzero(o.insertion_index >= 0)) for o in outcomes.values()
                )
                progress(drawn, placed, total)

        for outcome in executor.map(_tile_pack_args, tasks, report):
            outcomes[outcome.index] = outcome
        for t in phase:
            done.add(outcomes[t.index])
    tiled = _merge(layout, outcomes, time.perf_counter() - start)
    tiled.result.stats["tile_reach"] = reach
    tiled.result.stats["tile_margin"] = margin
    return tiled


def packer_for(
    executor: TileExecutor,
) -> Callable[
    [ResolvedScene, DensityController, ProgressCallback | None],
    tuple[InsertionResult, Population],
]:
    """Return the packer that :func:`~regopack.run.pipeline.run_scene` takes, on ``executor``."""

    def pack(
        resolved: ResolvedScene, controller: DensityController, progress: ProgressCallback | None
    ) -> tuple[InsertionResult, Population]:
        tiled = pack_tiled(resolved, controller, executor, progress)
        return tiled.result, tiled.population

    return pack


def _merge(layout: TileLayout, outcomes: dict[int, TileOutcome], seconds: float) -> TiledPacking:
    """Join the tiles' particles in tile order, their insertion orders in schedule order."""
    order = sorted(outcomes, key=lambda i: (layout.tiles[i].colour, i))
    offset: dict[int, int] = {}
    running = 0
    for i in order:
        offset[i] = running
        running += int(np.count_nonzero(outcomes[i].insertion_index >= 0))
    parts = [outcomes[i] for i in sorted(outcomes)]
    index = np.concatenate(
        [np.where(o.insertion_index >= 0, o.insertion_index + offset[o.index], -1) for o in parts]
    ).astype(np.int64)
    centre = np.concatenate([o.centre for o in parts])
    first = parts[0].population
    shapes = [o.population.shapes for o in parts]
    population = Population(
        radius=np.concatenate([np.asarray(o.population.radius) for o in parts]),
        mineral=np.concatenate([np.asarray(o.population.mineral) for o in parts]).astype(np.int64),
        mineral_names=first.mineral_names,
        shapes=join_solids([s for s in shapes if isinstance(s, SolidBatch)]),  # type: ignore[arg-type]
    )
    stats: dict[str, float] = {}
    for key in SUMMED_STATS:
        values = [o.stats[key] for o in parts if key in o.stats]
        if values:
            stats[key] = float(math.fsum(values))
    stats["tiles"] = float(len(parts))
    stats["tile_time_s_max"] = max(o.seconds for o in parts)
    stats["tile_time_s_sum"] = math.fsum(o.seconds for o in parts)
    stats["insert_time_s"] = seconds
    tile = np.concatenate([np.full(len(o.population), o.index, dtype=np.int64) for o in parts])
    return TiledPacking(
        InsertionResult(centre=centre, insertion_index=index, stats=stats), population, tile
    )


__all__ = [
    "TileJob",
    "TileOutcome",
    "TiledPacking",
    "check_tiled",
    "layout_of",
    "pack_tiled",
    "packer_for",
    "split_count",
    "tile_pack",
    "tile_reach",
]
