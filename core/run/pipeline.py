"""Running a scene: draw the population, insert it, summarise, write the files.

One pipeline for both dimensions: the scene's domain says which. What differs
by dimension is small and named where it happens: the particles' measure
(area or volume) in the checks, the shape generators' batches (outlines or
solids), the solid fractions and the exporters' interface.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from regopack._compat import renamed_names
from regopack.analysis.pipeline import AnalysisFiles, write_analysis_files
from regopack.base import toml as _toml
from regopack.base.errors import (
    ConfigError,
    DensityTargetWarning,
    GeometryError,
    PluginError,
)
from regopack.base.field_error import FieldValueError
from regopack.base.limits import (
    MAX_EXTENT_RATIO,
    LimitError,
    check_memory,
    format_bytes,
)
from regopack.base.limits import memory_limit as memory_limit
from regopack.base.outdir import (
    MARKER,
    NAME_RULE,
    check_replaceable,
    checkpoint,
    name_key,
    name_problem,
    rebase,
    replace_folder,
)
from regopack.exports.pipeline import run_exports
from regopack.geometry.domain import Cylinder
from regopack.geometry.population import FloatArray, IntArray, Population, concat_shapes
from regopack.geometry.solids import SolidBatch, concat_solids
from regopack.packing.core import Packing, save, write_json_atomic
from regopack.packing.phi_references import references_3d, references_row
from regopack.packing.sieve import unplaced_per_class
from regopack.packing.solid_fraction import phi_in_box, phi_in_cylinder
from regopack.packing.solid_fraction import phi_in_window as phi_in_window
from regopack.registry.interfaces import (
    Analyzer,
    DensityController,
    DensitySearch,
    DensityTarget,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
    ShapeGenerator,
    SizeDistribution,
    SolidGenerator,
)
from regopack.run import __all__ as __all__  # public names, listed in the package
from regopack.run.compilation import CompileTime, compile_timer
from regopack.run.fabric import fabric_rows, fabric_summary
from regopack.scenes.analysis_plan import plan_analyses, run_analyses
from regopack.scenes.model import ANALYSIS_FOLDER, ResolvedPlugin, ResolvedScene, output_files
from regopack.verification.summary import verify_summary

TiledPacker = Callable[
    [ResolvedScene, DensityController, ProgressCallback | None],
    tuple[InsertionResult, Population],
]
"""Packs a scene with tiles: the insertion's result and the particles drawn (tile by tile)."""

RUN_FOLDER = "run"
"""Kind of the folder a run writes (in its :data:`regopack.base.outdir.MARKER` file)."""

BYTES_PER_PARTICLE = 3_200
"""Memory a 2D run needs per particle drawn, in bytes (paper order; measured, with a margin).

Peak resident memory grows by about 2.6 kB a particle in the paper order
(``small`` scaled to 5,000-52,000 particles; see ``docs/benchmarks.md``):
the particle's radius, mineral, orientation and vertices, the inserter's
arrays and outlines and the shapely polygons that measure the covered
area. A scene whose particle count times this exceeds :func:`memory_limit`
is refused before anything is allocated. :data:`PARTICLE_BYTES` holds the
figure of each kind of run.
"""

MIN_AREA = 1e-300
"""Smallest area (2D) or volume (3D) of a particle of a scene.

Below it, squared lengths leave 64-bit floats' normal range: they lose their
precision, then become zero (a scene written with ``d_min = 2e-200`` once
sized its neighbour grid by a cell of zero and overflowed). Like the largest
area's overflow, this is where floats end, not a length chosen for particles.
"""

PARTICLE_BYTES: dict[str, int] = {
    "2D paper order": BYTES_PER_PARTICLE,
    "2D sweep": 1_200,
    "3D polyhedra": 32_000,
    "3D spheres": 8_000,
}
"""Memory a run needs per particle drawn, in bytes, by kind of run (see :func:`particle_bytes`).

The growth of the peak resident memory per particle between runs of
increasing size (``docs/benchmarks.md``, "Memory per particle"), rounded up
by a quarter or more: 2.6 kB in the paper order, 0.81 kB in the sweep
(`dem` from 16 579 to 1 061 033 particles drawn: 232 MB to 1 077 MB), 14-25
kB at the peak of generating polyhedra.
Spheres grew by 0.3 kB a particle up to 9,638 (the kernels' fixed memory is
the peak there); their 8 kB is a cautious bound until a larger run measures
them.
"""


@dataclass(frozen=True)
class RunOutcome:
    """Result of :func:`run_scene`.

    Attributes
    ----------
    packing
        The packing.
    summary
        Scalar results of the run (what ``summary.json`` holds).
    packing_path, summary_path
        Files written, or ``None`` when nothing was written.
    analysis
        The analysis files (under ``<out_dir>/analysis``), when the scene lists
        analyses and files were written.
    exports
        Files written by the exporters of ``outputs.exports``, in scene order.
    """

    packing: Packing
    summary: dict[str, Any]
    packing_path: Path | None = None
    summary_path: Path | None = None
    analysis: AnalysisFiles | None = None
    exports: tuple[Path, ...] = ()


def _build(plugin: ResolvedPlugin[Any], interface: type[Any], what: str) -> Any:
    obj = plugin.build()
    if not isinstance(obj, interface):
        raise PluginError(
            f"{what} plugin {plugin.kind!r} ({plugin.origin}) built a {type(obj).__name__}, "
            f"not a {interface.__name__}"
        )
    return obj


def particle_count(scene: ResolvedScene, size_dist: SizeDistribution) -> int:
    """Return the number of particles to draw.

    This is the scene's ``count``, or ``round(domain area / size_dist.mean_area)``
    for ``count = "auto"`` (volumes in 3D: ``size_dist.mean_volume``).

    Raises
    ------
    ConfigError
        When ``count = "auto"`` gives no finite number of particles.
    """
    count = scene.scene.count
    if count == "auto":
        word = _MEASURE[scene.scene.domain.dimension]
        measure = scene.domain.measure
        mean = float(getattr(size_dist, f"mean_{word}"))
        if not (math.isfinite(mean) and mean > 0):
            raise ConfigError(
                _located(
                    scene,
                    "count",
                    f"count = 'auto' needs the mean particle {word}, which the "
                    f"{scene.size.kind!r} size distribution does not give; give a count",
                )
            )
        auto = measure / mean
        if not math.isfinite(auto):
            raise ConfigError(
                _located(
                    scene,
                    "count",
                    f"domain {word} / mean particle {word} = {measure:g} / {mean:g} is not a "
                    "finite number of particles; give a count or larger particles",
                )
            )
        return round(auto)
    return int(count)


_MEASURE = {2: "area", 3: "volume"}
"""What a particle's and a domain's measure is called, by dimension."""


def _measure(r: float, dimension: int) -> float:
    """Area of the disk or volume of the ball of radius ``r``."""
    return math.pi * r * r if dimension == 2 else 4.0 / 3.0 * math.pi * r * r * r


def _bytes(n: float) -> str:
    """``n`` bytes in binary units, e.g. ``7.3 TiB`` (as ``format_bytes``)."""
    return format_bytes(n)


def _located(scene: ResolvedScene, loc: str, text: str, value: Any = None) -> str:
    """``<source>: <loc> = <value>: <text>``, the style of the scene's validation errors."""
    where = scene.scene.origin(loc)
    if value is None and loc == "count":
        value = scene.scene.count
    shown = f"{loc} = {_toml._value(value)}" if value is not None else loc
    return f"{where}: {shown}: {text}" if where else f"{shown}: {text}"


def located_limit(scene: ResolvedScene, err: FieldValueError) -> ConfigError:
    """``err`` prefixed with the source of its field (the scene file or ``--set``)."""
    return ConfigError(err.located(scene.scene.origin(err.field)))


def particle_bytes(scene: ResolvedScene) -> tuple[int, str]:
    """Memory per particle of a run of ``scene`` (:data:`PARTICLE_BYTES`) and its kind."""
    if scene.scene.domain.dimension == 3:
        spheres = all(phase.shape.kind == "sphere" for phase in scene.phases)
        kind = "3D spheres" if spheres else "3D polyhedra"
    else:
        sweep = getattr(scene.insertion.config, "order", "paper") == "sweep"
        kind = "2D sweep" if sweep else "2D paper order"
    return PARTICLE_BYTES[kind], kind


def check_particle_memory(scene: ResolvedScene, n: int, auto: str = "") -> None:
    """Refuse ``n`` particles whose memory (:func:`particle_bytes`) exceeds :func:`memory_limit`.

    ``auto`` tells how ``count = "auto"`` gave ``n`` (shown in the message).
    """
    each, kind = particle_bytes(scene)
    given = f"gives {_count(n)} particles ({auto}), which" if auto else f"{_count(n)} particles"
    try:
        check_memory(
            float(n) * each,
            f"{given} ({kind} runs: about {each:,} bytes a particle)",
            field="count",
            given=scene.scene.count,
            limit=memory_limit(),
        )
    except LimitError as err:
        raise located_limit(scene, err) from None


def check_extents(scene: ResolvedScene, extents: Mapping[str, float], d_min: float) -> None:
    """Refuse a domain more than ``MAX_EXTENT_RATIO`` smallest diameters long.

    The ratio is :data:`~regopack.base.limits.MAX_EXTENT_RATIO`.

    ``extents`` maps the domain field that sets each extent (``domain.width``)
    to the extent's length.
    """
    for field, length in extents.items():
        ratio = length / d_min
        if ratio <= MAX_EXTENT_RATIO:
            continue
        size_set = scene.scene.origin("size") != scene.scene.source
        domain_set = scene.scene.origin(field) != scene.scene.source
        blame, value = (
            ("size", None) if size_set and not domain_set else (field, _field_value(scene, field))
        )
        raise ConfigError(
            _located(
                scene,
                blame,
                f"the domain's extent ({length:g}) is {ratio:.3g} times the smallest particle "
                f"diameter ({d_min:g}); at most {MAX_EXTENT_RATIO:g} times, or 64-bit "
                "coordinates do not resolve the particles and the neighbour grids grow "
                "without bound; give a smaller domain or larger particles",
                value,
            )
        )


def _field_value(scene: ResolvedScene, field: str) -> Any:
    """Return the scalar value of a dotted ``domain.<name>`` field, or ``None``."""
    value = getattr(scene.scene.domain, field.removeprefix("domain."), None)
    return value if isinstance(value, int | float) else None


def domain_extents(scene: ResolvedScene) -> dict[str, float]:
    """Each extent of the domain by the scene field that sets it (for :func:`check_extents`)."""
    d = scene.scene.domain
    if d.kind == "cylinder":
        return {"domain.radius": 2.0 * float(d.radius or 0.0), "domain.height": float(d.height)}
    if d.dimension == 3:
        width, depth, height = d.to_box().size
        return {"domain.width": width, "domain.depth": depth, "domain.height": height}
    if d.kind == "circle":
        return {"domain.radius": 2.0 * float(d.radius or 0.0)}
    bounds = scene.domain.bounds()
    width, height = float(bounds[1] - bounds[0]), float(bounds[3] - bounds[2])
    if d.kind == "polygon":
        return {"domain.vertices": max(width, height)}
    return {"domain.width": width, "domain.height": height}


def check_shapes(scene: ResolvedScene, r_min: float) -> None:
    """Draw one smallest particle of each phase (on a generator of its own), to refuse early.

    A shape generator's mistake (a template file that is missing or
    malformed, an outline that overflows) then ends ``regopack config`` and
    ``regopack run`` alike, naming the phase's shape field.
    """
    for p, phase in enumerate(scene.phases):
        try:
            generator = phase.shape.build()
            with np.errstate(over="ignore", invalid="ignore"):
                generator.generate(np.array([r_min]), np.random.default_rng(0))
        except ConfigError as err:
            raise ConfigError(_located(scene, f"phases.{p}.shape", str(err))) from err


def check_runnable(scene: ResolvedScene) -> int:
    """Every check of a scene before a run (2D or 3D); return the particle count.

    ``regopack run`` and ``regopack config`` both call it, so a scene that
    one accepts the other accepts too.

    Raises
    ------
    ConfigError
        One line naming the source (scene file or ``--set``), the field, the
        value and what is allowed.
    """
    count = check_scene(scene)
    check_analyses(scene)
    return count


def _count(n: int) -> str:
    return f"{n:,}" if n < 10**15 else f"{n:.3g}"


def check_inserter(scene: ResolvedScene) -> None:
    """Refuse, before anything is drawn, a scene that its inserter says it cannot pack.

    Raises
    ------
    ConfigError
        One line naming the scene file (or ``--set``), the field and the reason
        (see :meth:`~regopack.registry.interfaces.InsertionStrategy.scene_conflict`).
    """
    inserter: InsertionStrategy = _build(scene.insertion, InsertionStrategy, "insertion")
    density = scene.density.kind
    controller: DensityController = _build(scene.density, DensityController, "density")
    if isinstance(controller, DensityTarget):  # the inserter packs with the one it chooses
        if not inserter.steered_by_density:
            raise ConfigError(
                _located(
                    scene,
                    "density.kind",
                    f"a density target chooses a controller by packing, and insertion "
                    f"{scene.insertion.kind!r} places particles without one",
                    scene.density.kind,
                )
            )
        density = controller.controls
    conflict = inserter.scene_conflict(tuple(phase.shape.kind for phase in scene.phases), density)
    if conflict is not None:
        field, reason = conflict
        raise ConfigError(_located(scene, field, reason))


def check_scene(scene: ResolvedScene) -> int:
    """Check that ``scene`` can be drawn and packed at all; return its particle count.

    Refused, before anything is drawn: particles whose area overflows 64-bit
    floats, or whose smallest area is below :data:`MIN_AREA`; particles larger
    than the domain (the smallest particle's area exceeds the domain's, so none
    can be placed); and a particle count (given, or from ``count = "auto"``)
    whose memory (:func:`particle_bytes` per particle) exceeds
    :func:`memory_limit`; a domain more than
    :data:`~regopack.base.limits.MAX_EXTENT_RATIO` smallest diameters long; a shape
    generator that cannot draw a particle (:func:`check_shapes`); and
    what the inserter says it cannot pack (:func:`check_inserter`).

    Raises
    ------
    ConfigError
        One line naming the scene file (or ``--set``), the field and the limit.
    """
    check_inserter(scene)
    dimension = scene.scene.domain.dimension
    word = _MEASURE[dimension]
    size_dist: SizeDistribution = _build(scene.size, SizeDistribution, "size")
    r_min, r_max = float(size_dist.r_min), float(size_dist.r_max)
    largest, smallest = _measure(r_max, dimension), _measure(r_min, dimension)
    if not math.isfinite(largest):
        raise ConfigError(
            _located(
                scene,
                "size",
                f"the largest particle (diameter {2 * r_max:g}) has {_a(word)} {word} of "
                f"{largest:g}: its size overflows 64-bit floats; give smaller sizes",
            )
        )
    if not smallest >= MIN_AREA:
        raise ConfigError(
            _located(
                scene,
                "size",
                f"the smallest particle (diameter {2 * r_min:g}) has {_a(word)} {word} of "
                f"{smallest:g}: its size underflows 64-bit floats; give larger sizes",
            )
        )
    domain_measure = scene.domain.measure
    if smallest > domain_measure:
        domain_set = scene.scene.origin("domain") != scene.scene.source
        raise ConfigError(
            _located(
                scene,
                "domain"
                if domain_set and scene.scene.origin("size") == scene.scene.source
                else "size",
                f"the smallest particle (diameter {2 * r_min:g}, {word} {smallest:g}) is "
                f"larger than the domain ({word} {domain_measure:g}), so no particle can be "
                "placed; give smaller sizes or a larger domain",
            )
        )
    check_extents(scene, domain_extents(scene), 2.0 * r_min)
    check_shapes(scene, r_min)
    n = particle_count(scene, size_dist)
    auto = (
        f"domain {word} {domain_measure:g} / mean particle {word} "
        f"{float(getattr(size_dist, f'mean_{word}')):g}"
        if scene.scene.count == "auto"
        else ""
    )
    check_particle_memory(scene, n, auto)
    return n


def _a(word: str) -> str:
    return "an" if word[0] in "aeiou" else "a"


def draw_sizes_and_minerals(
    scene: ResolvedScene, rng: np.random.Generator, n: int
) -> tuple[FloatArray, IntArray]:
    """Draw the ``n`` radii, then the minerals (2D and 3D scenes draw them alike).

    Raises
    ------
    PluginError
        When the size plugin returns other than ``n`` finite positive radii.
    """
    size_dist: SizeDistribution = _build(scene.size, SizeDistribution, "size")
    radii = np.asarray(size_dist.sample(n, rng), dtype=np.float64)
    if radii.shape != (n,) or not np.all(np.isfinite(radii) & (radii > 0)):
        raise PluginError(
            f"size plugin {scene.size.kind!r} returned radii of shape {radii.shape} "
            f"(expected ({n},), all finite and positive)"
        )
    minerals = rng.choice(len(scene.phases), size=n, p=scene.fractions).astype(np.int64)
    return radii, minerals


def draw_population(
    scene: ResolvedScene, rng: np.random.Generator, count: int | None = None
) -> Population:
    """Draw every particle of ``scene`` up front, in insertion order.

    The random draws happen in exactly this order, in both dimensions: the
    radii (``size.sample(N, rng)``); the minerals (``rng.choice`` over the
    phases with the normalised fractions); then, for each phase in scene
    order, the shapes of that phase's particles
    (``shape.generate(radii[idx], rng)``): outlines in 2D, solids in 3D.
    ``count`` draws that many instead of the scene's count (a tile's share;
    the scene is checked all the same).
    """
    n = check_scene(scene)
    if count is not None:
        n = count
    radii, minerals = draw_sizes_and_minerals(scene, rng, n)
    solid = scene.scene.domain.dimension == 3
    interface = SolidGenerator if solid else ShapeGenerator
    parts: list[tuple[IntArray, Any]] = []
    for p, phase in enumerate(scene.phases):
        generator = _build(phase.shape, interface, "shape")
        idx = np.flatnonzero(minerals == p).astype(np.int64)
        with np.errstate(over="ignore", invalid="ignore"):  # refused just below
            batch = generator.generate(radii[idx], rng)
        if solid and not isinstance(batch, SolidBatch):
            raise PluginError(
                f"shape plugin {phase.shape.kind!r} returned {type(batch).__name__} for "
                f"{len(idx)} radii (phase {phase.name!r}); expected a SolidBatch of one solid "
                "per radius"
            )
        if len(batch) != len(idx):
            raise PluginError(
                f"shape plugin {phase.shape.kind!r} returned {len(batch)} "
                f"{'solids' if solid else 'outlines'} for {len(idx)} radii (phase {phase.name!r})"
            )
        finite = np.isfinite(batch.vertices).all(axis=1)
        if not finite.all():
            j = int(np.searchsorted(batch.offsets, np.flatnonzero(~finite)[0], side="right")) - 1
            raise GeometryError(
                _located(
                    scene,
                    f"phases.{p}.shape",
                    f"the {phase.shape.kind!r} {'solid' if solid else 'outline'} of a particle "
                    f"of diameter {2 * radii[idx][j]:g} (phase {phase.name!r}) has non-finite "
                    "vertices (64-bit float overflow); give smaller sizes",
                )
            )
        parts.append((idx, batch))
    shapes = concat_solids(parts, n) if solid else concat_shapes(parts, n)
    return Population(
        radius=radii,
        mineral=minerals,
        mineral_names=scene.phase_names,
        shapes=shapes,  # type: ignore[arg-type]
    )


def default_out_dir(scene: ResolvedScene) -> Path:
    """``runs/<scene name>-seed<seed>`` (relative to the working directory)."""
    return Path("runs") / f"{scene.name}-seed{scene.seed}"


def run_scene(
    resolved: ResolvedScene,
    out_dir: str | Path | None = None,
    progress: ProgressCallback | None = None,
    *,
    figures: bool = True,
    summary_extras: Callable[[Any], Mapping[str, Any]] | None = None,
    verify: bool | None = None,
    extra_files: Mapping[str, str] | None = None,
    tiled: TiledPacker | None = None,
) -> RunOutcome:
    """Draw, insert and summarise ``resolved``; write the files into ``out_dir``.

    Parameters
    ----------
    resolved
        The scene, with validated plugin parameters.
    out_dir
        The run folder (see :func:`default_out_dir`), written as a whole:
        it ends up holding this run's files and nothing else. ``None``
        writes nothing.
    progress
        Called as ``progress(done, placed, total)`` during insertion.
    figures
        Draw the analysis figures when the scene lists analyses and
        ``out_dir`` is given.
    summary_extras
        Called with the packing once it is analysed; the items it returns are
        added to the summary before anything is written.
    verify
        Check the packing for overlaps and wall violations
        (:func:`regopack.verification.summary.verify_packing`) and add the ``verify`` entry to the
        summary. ``None`` (the default) verifies when the insertion strategy
        says its settings may overlap (:meth:`InsertionStrategy.may_overlap`).
    extra_files
        More text files for the run folder, by plain file name (a sweep's
        ``scene.json``); a name that is also one of the run's outputs is
        refused.
    tiled
        Packs a scene with ``tiles`` (:func:`regopack.tiling.run.packer_for`,
        which chooses where the tiles are packed); a tiled scene without it
        is refused.

    Returns
    -------
    RunOutcome
        The packing, the summary and the paths written.

    Raises
    ------
    ConfigError
        When ``out_dir`` may not be replaced (it exists, is not empty and
        does not hold a previous regopack run; or it is the current
        directory) or cannot be written, checked before the packing starts.

    Notes
    -----
    The summary's ``fabric`` block (:func:`regopack.run.fabric.fabric_summary`:
    contacts, Z, Z_m, rattlers and the fabric anisotropy with its error) is
    measured after packing unless ``outputs.fabric`` is false, reusing the
    scene's analyses where they hold its analyzers.
    The analyzers in ``outputs.analyses`` (and those they require) run after
    packing; the summary holds the results of the listed ones, and
    :func:`regopack.analysis.pipeline.write_analysis` writes all of them into
    ``<out_dir>/analysis``. The exporters in ``outputs.exports`` then write
    the packing beside the packing file, as ``<packing stem><suffix>``, with
    the computed analyzers passed on.

    Everything is written into a fresh temporary folder beside ``out_dir``
    (``<out_dir>.tmp-<random>``), which replaces ``out_dir`` as a whole once
    every file is complete (see :func:`regopack.base.outdir.replace_folder`): an
    interrupted or killed run leaves the previous run untouched, and a rerun
    leaves nothing of the previous one (no stale analysis or exports).
    """
    check_analyses(resolved)
    if out_dir is not None:
        check_replaceable(out_dir, RUN_FOLDER)
        _check_extra_files(resolved, extra_files or {})
    if resolved.scene.tiles is not None and tiled is None:
        raise ConfigError(
            f"scene {resolved.name!r} has tiles: pack it with regopack.pack or 'regopack run'"
        )
    with compile_timer() as compiling:
        return _run(
            resolved, out_dir, progress, figures, summary_extras, verify, extra_files, compiling,
            tiled,
        )  # fmt: skip


def _run(
    resolved: ResolvedScene,
    out_dir: str | Path | None,
    progress: ProgressCallback | None,
    figures: bool,
    summary_extras: Callable[[Any], Mapping[str, Any]] | None,
    verify: bool | None,
    extra_files: Mapping[str, str] | None,
    compiling: CompileTime,
    tiled: TiledPacker | None = None,
) -> RunOutcome:
    start = time.perf_counter()
    inserter: InsertionStrategy = _build(resolved.insertion, InsertionStrategy, "insertion")
    controller: DensityController = _build(resolved.density, DensityController, "density")
    size_dist: SizeDistribution = _build(resolved.size, SizeDistribution, "size")
    margin = 2.0 * float(size_dist.r_max)
    domain = resolved.domain
    scene_dict = resolved.to_dict()

    def pack_with(ctl: DensityController) -> tuple[InsertionResult, Packing]:
        try:
            if resolved.scene.tiles is not None:
                assert tiled is not None
                result, population = tiled(resolved, ctl, progress)
            else:
                rng = np.random.default_rng(resolved.seed)
                population = draw_population(resolved, rng)
                result = inserter.pack(population, domain, ctl, rng, progress)
        except LimitError as err:  # a size the inserter derived from the scene, refused
            raise located_limit(resolved, err) from None
        packing = Packing.from_parts(
            population, result, domain, scene_dict, resolved.seed, result.stats
        )
        return result, packing

    search: DensitySearch | None = None
    interior: tuple[float, str] | None = None
    if isinstance(controller, DensityTarget):
        result, packing, search, interior = _search_density(resolved, controller, pack_with, margin)
    else:
        result, packing = pack_with(controller)
    times = compiling.run_times(time.perf_counter() - start)  # now, before any later compiling

    n_placed = packing.n_placed
    phi_interior, note = interior if interior is not None else _phi_interior(packing, margin)
    summary: dict[str, Any] = {
        "scene": resolved.name,
        "seed": resolved.seed,
        **({"dimension": 3} if packing.dimension == 3 else {}),
        "tried": packing.n_particles,
        "placed": n_placed,
        "not_placed": packing.n_particles - n_placed,
        "phi_domain": packing.phi,
        "phi_interior": phi_interior,
        "interior_margin": margin,
        **times,
    }
    if note:
        summary["phi_interior_note"] = note
    if packing.dimension == 3:
        summary["phi_references"] = references_3d()
    if n_placed < packing.n_particles:
        summary["not_placed_by_class"] = [
            row for row in unplaced_per_class(packing) if row["not_placed"] > 0
        ]
    eta = getattr(resolved.density.config, "eta", None)
    if eta is not None:
        summary["eta"] = eta
    if search is not None:
        assert isinstance(controller, DensityTarget)
        summary["eta"] = search.tries[search.chosen]["eta"]
        summary["density_target"] = _target_summary(controller, search)
    for key, value in result.stats.items():
        summary.setdefault(key, value)
    if verify if verify is not None else inserter.may_overlap():
        summary["verify"] = verify_summary(packing)
    analyzers: dict[str, Analyzer] = {}
    if resolved.analyses:
        requests = [(p.kind, _params(p)) for p in resolved.analyses]
        analyzers = run_analyses(packing, resolved.registry, requests, source=_analyses(resolved))
        summary["analyses"] = {p.kind: analyzers[p.kind].results() for p in resolved.analyses}
    if resolved.scene.outputs.fabric:
        begin = time.perf_counter()
        summary["fabric"] = fabric_summary(packing, resolved.registry, analyzers)
        summary["fabric_time_s"] = time.perf_counter() - begin
    summary["compile_time_s"] = compiling.seconds
    if summary_extras is not None:
        summary.update(summary_extras(packing))

    if out_dir is None:
        return RunOutcome(packing, summary)
    return _write_run(
        resolved, Path(out_dir), packing, summary, analyzers, figures, extra_files or {}
    )


def _search_density(
    resolved: ResolvedScene,
    target: DensityTarget,
    pack_with: Callable[[DensityController], tuple[InsertionResult, Packing]],
    margin: float,
) -> tuple[InsertionResult, Packing, DensitySearch, tuple[float, str] | None]:
    """Pack ``resolved`` as often as ``target``'s search asks; return the packing it keeps.

    The last item is the kept packing's interior fraction and note when the
    search measured them (``None`` when it measured the domain's).

    The search keeps the packing closest to ``target.phi`` (the first one
    within the tolerance ends it); only the closest so far is held.
    """
    best: list[Any] = []  # [distance, index, result, packing, interior fraction and note]
    count = 0

    def probe(ctl: DensityController) -> float:
        nonlocal count
        result, packing = pack_with(ctl)
        interior = None if target.measure == "domain" else _phi_interior(packing, margin)
        phi = packing.phi if interior is None else interior[0]
        if not math.isnan(phi) and (not best or abs(phi - target.phi) < best[0]):
            best[:] = [abs(phi - target.phi), count, result, packing, interior]
        count += 1
        return phi

    try:
        search = target.search(probe)
    except FieldValueError as err:  # out of the scene's reach, or not measurable
        raise located_limit(resolved, err) from None
    if not best or best[1] != search.chosen or len(search.tries) != count:
        raise PluginError(
            f"density {resolved.density.kind!r}: its search chose packing {search.chosen} of "
            f"{len(search.tries)}, not the closest to its target of the {count} it made"
        )
    if not search.met:
        warnings.warn(
            DensityTargetWarning(
                f"density {resolved.density.kind!r}: phi {target.measure} {target.phi:.4g} not "
                f"reached within the tolerance in {count} packings; the closest, kept, has "
                f"{search.tries[search.chosen]['phi']:.4f} (raise density.packings or "
                "density.tolerance)"
            ),
            stacklevel=1,
        )
    packing: Packing = best[3]
    # the chosen controller's parameters (eta) travel with the packing, for its analyses
    chosen = {k: v for k, v in search.tries[search.chosen].items() if k != "phi"}
    packing.stats.update(chosen)
    return best[2], packing, search, best[4]


def _target_summary(target: DensityTarget, search: DensitySearch) -> dict[str, Any]:
    """Return the summary's ``density_target`` block: the goal, what was reached, the tries."""
    return {
        **{k: v for k, v in search.tries[search.chosen].items() if k != "phi"},
        "phi": target.phi,
        "of": target.measure,
        "tolerance": target.tolerance,
        "reached": search.tries[search.chosen]["phi"],
        "met": search.met,
        "packings": len(search.tries),
        "tries": search.tries,
    }


def _phi_interior(packing: Packing, margin: float) -> tuple[float, str]:
    """Return the solid fraction inside the walls by ``margin``, and a note when there is none.

    A periodic box has no walls: its whole cell is interior. A solid that
    crosses the faces of the interior window of a box of polyhedra is not
    cut yet (``NaN``, as :func:`regopack.packing.solid_fraction.phi_in_box` says).
    A cylinder's interior is the coaxial cylinder ``margin`` inside its side
    wall, floor and lid (:func:`regopack.packing.solid_fraction.phi_in_cylinder`).
    """
    empty = f"the interior window is empty: the domain is not wider than 2 x {margin:g}"
    if packing.dimension == 2:
        phi = phi_in_window(packing, packing.domain.interior(margin))
        return phi, empty if math.isnan(phi) else ""
    box = packing.domain
    if box.periodic:
        return packing.phi, ""
    try:
        if isinstance(box, Cylinder):  # a coaxial cylinder inside the walls
            phi = phi_in_cylinder(packing, box.interior(margin))
            return phi, empty if math.isnan(phi) else ""
        return phi_in_box(packing, box.interior(margin)), ""
    except NotImplementedError:
        return math.nan, ""


def _analyses(resolved: ResolvedScene) -> str:
    """Where the scene's ``outputs.analyses`` come from and the field, for messages."""
    where = resolved.scene.origin("outputs.analyses")
    return f"{where}: outputs.analyses" if where else "outputs.analyses"


def check_analyses(resolved: ResolvedScene) -> None:
    """Refuse, before anything is packed, what the scene's analyses would refuse after it.

    An analyzer or a parameter that the scene's dimension lacks, one analyzer
    asked for by two names, a requirement that is not registered: the plan of
    the analyses is made (the analyzers built, none computed).
    """
    if resolved.analyses:
        requests = [(p.kind, _params(p)) for p in resolved.analyses]
        dimension = resolved.scene.domain.dimension
        plan_analyses(resolved.registry, requests, {}, dimension, _analyses(resolved), warn=False)


def _check_extra_files(resolved: ResolvedScene, extra_files: Mapping[str, str]) -> None:
    taken = {name_key(name): loc for loc, names in output_files(resolved).items() for name in names}
    taken[name_key(MARKER)] = "regopack's marker file"
    for name in extra_files:
        problem = name_problem(name)
        if problem is not None:
            raise ConfigError(f"extra run file {name!r}: {problem} ({NAME_RULE})")
        if name_key(name) in taken:
            raise ConfigError(f"extra run file {name!r}: the same file as {taken[name_key(name)]}")


def _write_run(
    resolved: ResolvedScene,
    out: Path,
    packing: Packing,
    summary: dict[str, Any],
    analyzers: Mapping[str, Analyzer],
    figures: bool,
    extra_files: Mapping[str, str],
) -> RunOutcome:
    """Write the run into a fresh folder and swap it in place of ``out``."""
    outputs = resolved.scene.outputs
    packing_path = out / outputs.packing
    summary_path = out / outputs.summary
    analysis = None
    exports: tuple[Path, ...] = ()
    with replace_folder(out, RUN_FOLDER) as tmp:
        try:
            checkpoint("packing")
            save(packing, tmp / outputs.packing)
            checkpoint("summary")
            write_json_atomic(tmp / outputs.summary, summary)
            for name, text in extra_files.items():
                (tmp / name).write_text(text, encoding="utf-8")
        except (PermissionError, IsADirectoryError, NotADirectoryError) as err:
            raise ConfigError(f"cannot write the run's output: {err}") from err
        if analyzers:
            checkpoint("analysis")
            analysis = write_analysis_files(
                tmp / ANALYSIS_FOLDER,
                packing,
                analyzers,
                figures=figures,
                packing_path=packing_path,
                registry=resolved.registry,
            )
        if resolved.exports:
            checkpoint("exports")
        exports = run_exports(
            packing, resolved.exports, tmp / outputs.packing, packing_path, analyzers or None
        )
    if analysis is not None:
        analysis = analysis.moved(tmp, out)
    exports = tuple(rebase(p, tmp, out) for p in exports)
    return RunOutcome(packing, summary, packing_path, summary_path, analysis, exports)


def _params(plugin: ResolvedPlugin[Any]) -> dict[str, Any]:
    """Return the validated parameters of a plugin selection, without its ``kind``."""
    params = plugin.to_dict()
    params.pop("kind", None)
    return params


def summary_rows(summary: Mapping[str, Any]) -> list[tuple[str, str]]:
    """Human-readable ``(label, value)`` rows of a run summary."""

    def fmt(v: Any, spec: str = "") -> str:
        if isinstance(v, float) and math.isnan(v):
            return "n/a"
        return format(v, spec)

    rows = [
        ("scene", str(summary["scene"])),
        ("seed", str(summary["seed"])),
        ("tried", fmt(summary["tried"], ",")),
        ("placed", fmt(summary["placed"], ",")),
        ("not placed", fmt(summary["not_placed"], ",")),
        ("φ domain", fmt(summary["phi_domain"], ".4f")),
        (
            f"φ interior (margin {summary['interior_margin']:g})",
            fmt(summary["phi_interior"], ".4f"),
        ),
        *(
            [("φ references", references_row())]
            if summary.get("dimension") == 3 and "phi_references" in summary
            else []
        ),
        (
            "insertion time",
            f"{summary.get('insertion_time_s', summary['wall_time_s']):.2f} s"
            + (" (kernels compiled meanwhile)" if "insertion_time_note" in summary else ""),
        ),
    ]
    fabric = summary.get("fabric")
    if isinstance(fabric, Mapping):
        rows.extend(fabric_rows(fabric))
    compiled = summary.get("compile_time_s") or 0.0
    if compiled >= 0.05:
        rows.append(("compiling kernels", f"{compiled:.1f} s (first run only; then cached)"))
    if "eta" in summary:
        rows.insert(2, ("η", fmt(summary["eta"], "g")))
    checked = summary.get("verify")
    if checked is not None and "skipped" in checked:
        rows.append(("verified", f"skipped: {checked['skipped']}"))
    elif checked is not None:
        rows.append(
            (
                "verified",
                "OK"
                if checked["ok"]
                else f"VIOLATED: {checked['overlap_pairs']:,} pairs, "
                f"{checked['outside']:,} outside",
            )
        )
    return rows


_MOVED_3D = {
    "RunOutcome3D": "RunOutcome",
    "run_scene3d": "run_scene",
    "check_scene3d": "check_scene",
    "draw_population3d": "draw_population",
}
"""Names of the former 3D run module, now the names of this one for both dimensions."""


__getattr__ = renamed_names(__name__, _MOVED_3D)
"""Give the former 3D names (deprecated) the names that replaced them (PEP 562)."""
