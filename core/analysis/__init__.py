"""The analysis pipeline: run analyzers on a packing, write their results, tables and figures."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from regopack._exports import load_export

if TYPE_CHECKING:
    from regopack.analysis.pipeline import DEFAULT_ANALYSES as DEFAULT_ANALYSES
    from regopack.analysis.pipeline import DEFAULT_ANALYSES_3D as DEFAULT_ANALYSES_3D
    from regopack.analysis.pipeline import AnalysisFiles as AnalysisFiles
    from regopack.analysis.pipeline import analysis_summary as analysis_summary
    from regopack.analysis.pipeline import main_numbers as main_numbers
    from regopack.analysis.pipeline import run_analyses as run_analyses
    from regopack.analysis.pipeline import write_analysis as write_analysis
    from regopack.analysis.pipeline import write_analysis_files as write_analysis_files

__all__ = [
    "DEFAULT_ANALYSES",
    "DEFAULT_ANALYSES_3D",
    "AnalysisFiles",
    "analysis_summary",
    "main_numbers",
    "run_analyses",
    "write_analysis",
    "write_analysis_files",
]

_SOURCES = dict.fromkeys(__all__, "regopack.analysis.pipeline")


def __getattr__(name: str) -> Any:
    """Load the names of :mod:`regopack.analysis.pipeline` on first use (PEP 562)."""
    return load_export(globals(), _SOURCES, name)


def __dir__() -> list[str]:
    return sorted(__all__)
