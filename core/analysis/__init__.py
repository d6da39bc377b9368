"""The analysis pipeline: run analyzers on a packing, write their results, tables and figures."""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

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

__getattr__, __dir__ = lazy_exports(globals(), "regopack.analysis.pipeline")
