"""A 3D run: draw the solids, insert them, measure, verify and write the run folder.

The counterpart of :mod:`regopack.run.pipeline` for scenes whose domain is a box
(:attr:`regopack.scenes.model.Domain.dimension` is 3). The random draws
happen in the order of 2D: the radii, the minerals, then each phase's solids.
:func:`regopack.run.pipeline.run_scene` hands 3D scenes to :func:`run_scene3d`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ConfigError, GeometryError, PluginError
from regopack.base.limits import LimitError
from regopack.base.outdir import check_replaceable, rebase, replace_folder
from regopack.exports.pipeline import run_exports
from regopack.geometry.domain import Box
from regopack.geometry.population import Population
from regopack.geometry.solids import SolidBatch, concat_solids
from regopack.packing.core import write_json_atomic
from regopack.packing.core3d import Packing3D, save3d
from regopack.packing.solid_fraction import phi_in_box
from regopack.registry.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
    SizeDistribution,
    SolidGenerator,
)
from regopack.run.compilation import CompileTime, compile_timer
from regopack.scenes.model import ResolvedScene

if TYPE_CHECKING:
    from regopack.analysis.pipeline import AnalysisFiles
    from regopack.verification.polyhedra import Report3D

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

__all__ = ["RunOutcome3D", "check_scene3d", "draw_population3d", "phi_in_box", "run_scene3d"]


@dataclass(frozen=True)
class RunOutcome3D:
    """Result of :func:`run_scene3d`: the packing, its summary and the files written."""

    packing: Packing3D
    summary: dict[str, Any]
    packing_path: Path | None = None
    summary_path: Path | None = None
    analysis: AnalysisFiles | None = None
    exports: tuple[Path, ...] = ()


def _located(scene: ResolvedScene, loc: str, text: str) -> str:
    from regopack.run.pipeline import _located as located

    return located(scene, loc, text)


def _box(scene: ResolvedScene) -> Box:
    return scene.scene.domain.to_box()


def check_scene3d(scene: ResolvedScene) -> int:
    """Check that a 3D scene can be drawn at all; return its particle count.

    Refused in one line: particles whose volume overflows, a smallest
    particle larger than the box, ``count = "auto"`` with a size
    distribution that does not know its mean volume, a count whose
    memory exceeds the machine's (:func:`regopack.run.pipeline.particle_bytes`), a box
    side more than :data:`~regopack.base.limits.MAX_EXTENT_RATIO` smallest
    diameters long, a shape that cannot be drawn, and what the inserter says
    it cannot pack.
    """
    from regopack.run.pipeline import (
        _build,
        check_extents,
        check_inserter,
        check_particle_memory,
        check_shapes,
        domain_extents,
    )

    check_inserter(scene)
    size_dist: SizeDistribution = _build(scene.size, SizeDistribution, "size")
    r_min, r_max = float(size_dist.r_min), float(size_dist.r_max)
    vol_max = 4.0 / 3.0 * math.pi * r_max * r_max * r_max
    if not math.isfinite(vol_max):
        raise ConfigError(
            _located(
                scene,
                "size",
                f"the largest particle (diameter {2 * r_max:g}) has a volume of {vol_max:g}: "
                "its size overflows 64-bit floats; give smaller sizes",
            )
        )
    vol_min = 4.0 / 3.0 * math.pi * r_min * r_min * r_min
    if not vol_min >= 1e-300:
        raise ConfigError(
            _located(
                scene,
                "size",
                f"the smallest particle (diameter {2 * r_min:g}) has a volume of {vol_min:g}: "
                "its size underflows 64-bit floats; give larger sizes",
            )
        )
    box = _box(scene)
    if vol_min > box.volume:
        domain_set = scene.scene.origin("domain") != scene.scene.source
        size_given = scene.scene.origin("size") == scene.scene.source
        raise ConfigError(
            _located(
                scene,
                "domain" if domain_set and size_given else "size",
                f"the smallest particle (diameter {2 * r_min:g}) is larger than the box "
                f"(volume {box.volume:g}), so no particle can be placed",
            )
        )
    check_extents(scene, domain_extents(scene), 2.0 * r_min)
    check_shapes(scene, r_min)
    count = scene.scene.count
    if count == "auto":
        mean = float(size_dist.mean_volume)
        if not (math.isfinite(mean) and mean > 0):
            raise ConfigError(
                _located(
                    scene,
                    "count",
                    f"count = 'auto' needs the mean particle volume, which the "
                    f"{scene.size.kind!r} size distribution does not give; give a count",
                )
            )
        auto = box.volume / mean
        if not math.isfinite(auto):
            raise ConfigError(
                _located(scene, "count", "box volume / mean particle volume is not finite")
            )
        n = round(auto)
    else:
        n = int(count)
    how = (
        f"box volume {box.volume:g} / mean particle volume {float(size_dist.mean_volume):g}"
        if count == "auto"
        else ""
    )
    check_particle_memory(scene, n, how)
    return n


def draw_population3d(scene: ResolvedScene, rng: np.random.Generator) -> Population:
    """Draw every solid of a 3D scene up front, in insertion order (the 2D draw order)."""
    from regopack.run.pipeline import _build, draw_sizes_and_minerals

    n = check_scene3d(scene)
    radii, minerals = draw_sizes_and_minerals(scene, rng, n)
    parts: list[tuple[IntArray, SolidBatch]] = []
    for p, phase in enumerate(scene.phases):
        generator: SolidGenerator = _build(phase.shape, SolidGenerator, "shape")
        idx = np.flatnonzero(minerals == p).astype(np.int64)
        batch = generator.generate(radii[idx], rng)
        if not isinstance(batch, SolidBatch) or len(batch) != len(idx):
            raise PluginError(
                f"shape plugin {phase.shape.kind!r} returned {type(batch).__name__} "
                f"for {len(idx)} radii (phase {phase.name!r}); expected one solid per radius"
            )
        if not np.isfinite(batch.vertices).all():
            raise GeometryError(
                _located(
                    scene,
                    f"phases.{p}.shape",
                    f"the {phase.shape.kind!r} solids of phase {phase.name!r} have non-finite "
                    "vertices (64-bit float overflow); give smaller sizes",
                )
            )
        parts.append((idx, batch))
    shapes = concat_solids(parts, n)
    return Population(
        radius=radii,
        mineral=minerals,
        mineral_names=scene.phase_names,
        shapes=shapes,  # type: ignore[arg-type]
    )


def verify_packing3d(packing: Packing3D, rel_tol: float = 1e-9) -> Report3D:
    """Check a 3D packing of sharp polyhedra or of spheres with the independent oracle.

    Raises
    ------
    ConfigError
        For rounded polyhedra, which the oracle does not check yet.
    """
    from regopack.verification.polyhedra import verify_polyhedra, verify_spheres

    placed = packing.placed_in_order()
    box = packing.domain
    solids = packing.solids
    lo = [box.xmin, box.ymin, box.zmin]
    hi = [box.xmax, box.ymax, box.zmax]
    if packing.rounded:
        if solids.normals.shape[0] != 0:
            raise ConfigError("verify: rounded polyhedra are not verified yet")
        report = verify_spheres(
            packing.centre[placed] + solids.vertices[solids.offsets[placed]],
            solids.rounding_radius[placed],
            lo,
            hi,
            periodic=box.periodic,
            rel_tol=rel_tol,
        )
    else:
        report = verify_polyhedra(
            [packing.world_vertices(int(j)) for j in placed],
            None,
            lo,
            hi,
            periodic=box.periodic,
            rel_tol=rel_tol,
        )
    import dataclasses

    ix = [int(j) for j in placed]

    def pair(p: tuple[int, int]) -> tuple[int, int]:
        a, b = sorted((ix[p[0]], ix[p[1]]))
        return (a, b)

    return dataclasses.replace(
        report,
        overlapping_pairs=tuple(sorted(pair(p) for p in report.overlapping_pairs)),
        worst_pair=None if report.worst_pair is None else pair(report.worst_pair),
        worst_outside=None
        if report.worst_outside is None
        else (ix[report.worst_outside[0]], report.worst_outside[1]),
    )


def verify_summary3d(packing: Packing3D) -> dict[str, Any]:
    """Return the ``verify`` entry of a 3D run's summary, from the independent oracle."""
    if packing.rounded and packing.solids.normals.shape[0] != 0:
        return {"skipped": "rounded polyhedra are not verified yet"}
    report = verify_packing3d(packing)
    return {
        "ok": bool(report.ok),
        "overlap_pairs": int(report.n_overlapping_pairs),
        "worst_overlap": float(report.worst_overlap_fraction),
        "outside": int(report.n_outside),
    }


def run_scene3d(
    resolved: ResolvedScene,
    out_dir: str | Path | None = None,
    progress: ProgressCallback | None = None,
    *,
    verify: bool | None = None,
    figures: bool = True,
) -> RunOutcome3D:
    """Draw, insert, measure, analyse and write a 3D scene (as ``run_scene``).

    ``verify`` (default: True) checks the packing with the independent
    oracle :func:`regopack.verification.polyhedra.verify_polyhedra`. The analyzers
    of ``outputs.analyses`` (3D ones, checked before anything is drawn) run
    after the packing (see :mod:`regopack.analysis.pipeline3d`); ``figures`` draws
    their figures into the analysis folder.
    """
    from regopack.analysis.pipeline3d import check_scene_analyses
    from regopack.run.pipeline import RUN_FOLDER

    check_scene_analyses(resolved)
    if out_dir is not None:
        check_replaceable(out_dir, RUN_FOLDER)
    with compile_timer() as compiling:
        return _run3d(resolved, out_dir, progress, verify, compiling, figures)


def _run3d(
    resolved: ResolvedScene,
    out_dir: str | Path | None,
    progress: ProgressCallback | None,
    verify: bool | None,
    compiling: CompileTime,
    figures: bool = True,
) -> RunOutcome3D:
    from regopack.run.pipeline import RUN_FOLDER, _build

    start = time.perf_counter()
    rng = np.random.default_rng(resolved.seed)
    population = draw_population3d(resolved, rng)
    inserter: InsertionStrategy = _build(resolved.insertion, InsertionStrategy, "insertion")
    controller: DensityController = _build(resolved.density, DensityController, "density")
    box = _box(resolved)
    try:
        result: InsertionResult = inserter.pack(population, box, controller, rng, progress)
    except LimitError as err:  # a size the inserter derived from the scene, refused
        from regopack.run.pipeline import located_limit

        raise located_limit(resolved, err) from None
    times = compiling.run_times(time.perf_counter() - start)  # now, before any later compiling
    size_dist: SizeDistribution = _build(resolved.size, SizeDistribution, "size")
    packing = Packing3D.from_parts(
        population, result, box, resolved.to_dict(), resolved.seed, result.stats
    )
    margin = 2.0 * float(size_dist.r_max)
    if box.periodic:
        phi_interior = packing.phi  # no walls: the whole cell is interior
    else:
        try:
            phi_interior = phi_in_box(packing, box.interior(margin))
        except NotImplementedError:
            phi_interior = math.nan
    summary: dict[str, Any] = {
        "scene": resolved.name,
        "seed": resolved.seed,
        "dimension": 3,
        "tried": packing.n_particles,
        "placed": packing.n_placed,
        "not_placed": packing.n_particles - packing.n_placed,
        "phi_domain": packing.phi,
        "phi_interior": phi_interior,
        "interior_margin": margin,
        **times,
    }
    if packing.n_placed < packing.n_particles:
        from regopack.packing.sieve import unplaced_per_class

        d_min = getattr(resolved.size.config, "d_min", None)
        rows = unplaced_per_class((2.0 * packing.radius, packing.placed), d_min)
        summary["not_placed_by_class"] = [row for row in rows if row["not_placed"] > 0]
    for key, value in result.stats.items():
        summary.setdefault(key, value)
    if verify is None or verify:
        summary["verify"] = verify_summary3d(packing)
    from regopack.analysis.pipeline3d import run_scene_analyses, write_scene_analyses

    analyzers = run_scene_analyses(resolved, packing, summary)
    summary["compile_time_s"] = compiling.seconds
    if out_dir is None:
        return RunOutcome3D(packing, summary)
    out = Path(out_dir)
    outputs = resolved.scene.outputs
    with replace_folder(out, RUN_FOLDER) as tmp:
        try:
            save3d(packing, tmp / outputs.packing)
            write_json_atomic(tmp / outputs.summary, summary)
        except (PermissionError, IsADirectoryError, NotADirectoryError) as err:
            raise ConfigError(f"cannot write the run's output: {err}") from err
        analysis = write_scene_analyses(resolved, packing, analyzers, tmp, out, figures)
        exports = run_exports(
            packing, resolved.exports, tmp / outputs.packing, out / outputs.packing
        )
    exports = tuple(rebase(p, tmp, out) for p in exports)
    return RunOutcome3D(
        packing, summary, out / outputs.packing, out / outputs.summary, analysis, exports
    )
