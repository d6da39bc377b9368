"""The analyses of a 3D run: checked before the packing, computed after it, written with it.

A 3D scene lists its analyzers in ``outputs.analyses`` as a 2D scene does;
they must be analyzers of 3D packings (see
:attr:`regopack.registry.plugin_types.AnalyzerSpec.dimensions`). Their results go
into the run's ``summary.json`` under ``analyses`` and, when the run writes
a folder, into ``<out_dir>/analysis`` (see :func:`regopack.analysis.pipeline.write_analysis`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from regopack.analysis.pipeline import AnalysisFiles, write_analysis_files
from regopack.packing.core3d import Packing3D
from regopack.registry.interfaces import Analyzer
from regopack.scenes.analysis_plan import check_dimension, run_analyses
from regopack.scenes.model import ANALYSIS_FOLDER, ResolvedScene

__all__ = ["check_scene_analyses", "run_scene_analyses", "write_scene_analyses"]


def _source(resolved: ResolvedScene) -> str:
    where = resolved.scene.origin("outputs")
    return f"{where}: outputs.analyses" if where else "outputs.analyses"


def check_scene_analyses(resolved: ResolvedScene) -> None:
    """Refuse, before anything is packed, an analyzer of the scene that does not analyse 3D."""
    names = [p.kind for p in resolved.analyses]
    check_dimension(resolved.registry, names, 3, _source(resolved))


def run_scene_analyses(
    resolved: ResolvedScene, packing: Packing3D, summary: dict[str, Any]
) -> dict[str, Analyzer]:
    """Compute the scene's analyzers and put their results into ``summary["analyses"]``."""
    if not resolved.analyses:
        return {}
    from regopack.run.pipeline import _params

    requests = [(p.kind, _params(p)) for p in resolved.analyses]
    analyzers = run_analyses(packing, resolved.registry, requests, source=_source(resolved))
    summary["analyses"] = {p.kind: analyzers[p.kind].results() for p in resolved.analyses}
    return analyzers


def write_scene_analyses(
    resolved: ResolvedScene,
    packing: Packing3D,
    analyzers: Mapping[str, Analyzer],
    tmp: Path,
    out: Path,
    figures: bool = True,
) -> AnalysisFiles | None:
    """Write the analysis folder of a run being written in ``tmp``, which becomes ``out``."""
    if not analyzers:
        return None
    files = write_analysis_files(
        tmp / ANALYSIS_FOLDER,
        packing,
        analyzers,
        figures=figures,
        packing_path=out / resolved.scene.outputs.packing,
        registry=resolved.registry,
    )
    return files.moved(tmp, out)
