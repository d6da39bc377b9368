"""What the runs of an experiment gave, and the table of results (``results.csv``).

:class:`RunResult` is the outcome of one run, :class:`ExperimentResult` that of
the whole sweep; the metrics of each run are collected from its summary
(:data:`DEFAULT_METRICS`, or the experiment's ``metrics``) and written, one
row per run in grid order, into ``results.csv``.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from regopack.experiments.file import Experiment
from regopack.experiments.grid import RunSpec
from regopack.packing.core import _atomic_file

__all__ = [
    "DEFAULT_METRICS",
    "RESULTS_CSV",
    "ExperimentProgress",
    "ExperimentResult",
    "RunResult",
]

DEFAULT_METRICS: tuple[str, ...] = (
    "tried",
    "placed",
    "phi_domain",
    "phi_interior",
    "wall_time_s",
    "insert_time_s",
    "insertion_time_s",
    "compile_time_s",
    "candidate_analyses",
)
"""Summary keys collected when an experiment lists no ``metrics``.

The scalar results of the analyses a scene lists are added as
``analyses.<name>.<key>``, and those of the summary's ``verify``, ``voids``,
``fabric`` and ``density_target`` blocks as ``<block>.<key>``.
"""

RESULTS_CSV = "results.csv"
"""Name of the table of results in the experiment's output directory."""


@dataclass(frozen=True)
class RunResult:
    """What one run of an experiment gave.

    Attributes
    ----------
    spec
        The run.
    status
        ``"done"`` or ``"failed"``.
    out_dir
        The run's folder.
    metrics
        The collected metrics (``None`` where the summary has no such value).
    error
        One-line error message of a failed run.
    reused
        True when the run had finished before (its summary existed) and was not run again.
    """

    spec: RunSpec
    status: Literal["done", "failed"]
    out_dir: Path
    metrics: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    reused: bool = False

    @property
    def run_id(self) -> str:
        """The run's id."""
        return self.spec.run_id

    @property
    def ok(self) -> bool:
        """True when the run finished without error."""
        return self.status == "done"


ExperimentProgress = Callable[[RunResult, int, int], None]
"""Called as ``progress(result, finished, total)`` each time a run ends (or is reused)."""


@dataclass(frozen=True)
class ExperimentResult:
    """Outcome of :func:`run_experiment`.

    Attributes
    ----------
    experiment
        The experiment.
    out_dir
        Its output directory.
    runs
        One result per run, in grid order.
    metrics
        The metric columns of ``results.csv``.
    results_path, json_path
        ``results.csv`` and ``experiment.json``.
    """

    experiment: Experiment
    out_dir: Path
    runs: tuple[RunResult, ...]
    metrics: tuple[str, ...]
    results_path: Path
    json_path: Path

    @property
    def failed(self) -> tuple[RunResult, ...]:
        """The runs that raised."""
        return tuple(r for r in self.runs if not r.ok)

    @property
    def ok(self) -> bool:
        """True when every run finished."""
        return not self.failed


def _lookup(summary: Mapping[str, Any], dotted: str) -> Any:
    node: Any = summary
    for part in dotted.split("."):
        if isinstance(node, Mapping) and part in node:
            node = node[part]
        else:
            return None
    return node


def _is_scalar(value: Any) -> bool:
    return isinstance(value, bool | int | float | str) or (
        hasattr(value, "item") and getattr(value, "ndim", 1) == 0
    )


def _collect(summary: Mapping[str, Any], metrics: Sequence[str] | None) -> dict[str, Any]:
    if metrics is not None:
        return {m: _lookup(summary, m) for m in metrics}
    out = {m: summary.get(m) for m in DEFAULT_METRICS}
    for group in ("verify", "voids", "fabric", "density_target"):
        values = summary.get(group)
        if isinstance(values, Mapping):
            for key, value in values.items():
                if _is_scalar(value):
                    out[f"{group}.{key}"] = value
    analyses = summary.get("analyses")
    if isinstance(analyses, Mapping):
        for name, results in analyses.items():
            if isinstance(results, Mapping):
                for key, value in results.items():
                    if _is_scalar(value):
                        out[f"analyses.{name}.{key}"] = value
    return out


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
        value = value.item()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    if isinstance(value, int | str):
        return str(value)
    return json.dumps(value, default=str)


def _metric_columns(experiment: Experiment, results: Sequence[RunResult]) -> list[str]:
    if experiment.metrics is not None:
        return list(experiment.metrics)
    extra = sorted({k for r in results for k in r.metrics} - set(DEFAULT_METRICS))
    return [*DEFAULT_METRICS, *extra]


def _param_columns(experiment: Experiment) -> list[str]:
    return [*experiment.sweep, *(k for g in experiment.zip_groups for k in g)]


def _write_csv(path: Path, experiment: Experiment, results: Sequence[RunResult]) -> list[str]:
    """Write the finished runs (grid order) as CSV, atomically; return the metric columns."""
    params = _param_columns(experiment)
    metrics = _metric_columns(experiment, results)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["run_id", *params, "status", "error", *metrics])
    for r in sorted(results, key=lambda r: r.spec.index):
        writer.writerow(
            [
                r.run_id,
                *(_cell(r.spec.params.get(p)) for p in params),
                r.status,
                r.error or "",
                *(_cell(r.metrics.get(m)) for m in metrics),
            ]
        )
    with _atomic_file(path) as fh:
        fh.write(buffer.getvalue().encode("utf-8"))
    return metrics
