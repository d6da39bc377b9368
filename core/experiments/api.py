"""Sweeps from Python: :func:`run_sweep` and the :class:`SweepTable` it returns."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from regopack.base.errors import ConfigError

if TYPE_CHECKING:
    from rich.console import Console

    from regopack.experiments import ExperimentProgress, ExperimentResult

__all__ = ["SweepTable", "experiment_path", "run_sweep"]


@dataclass(frozen=True)
class SweepTable:
    """The results of a sweep: one row per run, in grid order (``results.csv`` as data).

    Attributes
    ----------
    columns
        ``run_id``, the varied scene fields, ``status``, ``error`` and the metrics.
    rows
        One dictionary per run, keyed by the columns (``None`` where a run has
        no value, e.g. the metrics of a failed run).
    result
        The full outcome: run folders, specs and paths.
    plots
        The plots drawn into ``<out>/plots``.
    """

    columns: tuple[str, ...]
    rows: tuple[dict[str, Any], ...]
    result: ExperimentResult
    plots: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        """True when every run finished."""
        return self.result.ok

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.rows)

    def column(self, name: str) -> np.ndarray:
        """Return one column as an array (floats with NaN for missing numbers, else objects)."""
        if name not in self.columns:
            raise KeyError(f"no column {name!r} (columns: {', '.join(self.columns)})")
        values = [row.get(name) for row in self.rows]
        numbers = [v for v in values if v is not None]
        if all(isinstance(v, int | float) and not isinstance(v, bool) for v in numbers):
            return np.array([math.nan if v is None else float(v) for v in values])
        return np.array(values, dtype=object)

    def to_pandas(self) -> Any:
        """Return the table as a ``pandas.DataFrame`` (pandas is not a regopack dependency)."""
        try:
            import pandas as pd
        except ImportError:
            raise ConfigError(
                "to_pandas() needs pandas, which regopack does not install: pip install pandas"
            ) from None
        return pd.DataFrame(list(self.rows), columns=list(self.columns))

    def __repr__(self) -> str:
        done = sum(row["status"] == "done" for row in self.rows)
        return (
            f"<SweepTable {self.result.experiment.experiment_name!r}: {done}/{len(self.rows)} "
            f"runs done, columns {', '.join(self.columns)}>"
        )


def table_from_result(outcome: ExperimentResult, plots: Sequence[Path] = ()) -> SweepTable:
    """Collect an experiment's outcome into a :class:`SweepTable`."""
    experiment = outcome.experiment
    params = [*experiment.sweep, *(k for g in experiment.zip_groups for k in g)]
    metrics = list(outcome.metrics)
    columns = ("run_id", *params, "status", "error", *metrics)
    rows = []
    for run in sorted(outcome.runs, key=lambda r: r.spec.index):
        row: dict[str, Any] = {"run_id": run.run_id}
        row.update({p: run.spec.params.get(p) for p in params})
        row["status"] = run.status
        row["error"] = run.error
        row.update({m: run.metrics.get(m) for m in metrics})
        rows.append(row)
    return SweepTable(columns, tuple(rows), outcome, tuple(plots))


def experiment_path(experiment: str | os.PathLike[str]) -> Path:
    """Return the file of an experiment given as a path or as a built-in experiment's name."""
    from regopack.experiments.builtin import builtin_experiment_path, builtin_experiments

    text = os.fspath(experiment)
    if isinstance(experiment, str) and not text.endswith(".toml") and not Path(text).exists():
        if text in builtin_experiments():
            return builtin_experiment_path(text)
    return Path(text)


@contextmanager
def _sweep_progress(
    enabled: bool, label: str, console: Console | None
) -> Iterator[ExperimentProgress | None]:
    if not enabled:
        yield None
        return
    import sys

    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    from regopack.run.progress import shown_until_error

    columns = (
        TextColumn("{task.description}"),
        BarColumn(bar_width=30),
        MofNCompleteColumn(),
        TextColumn("runs, {task.fields[failed]} failed, {task.fields[reused]} reused"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    live = console if console is not None else Console(file=sys.stderr)
    progress = Progress(*columns, console=live, transient=False)
    with shown_until_error(progress) as bar:
        task = bar.add_task(label, total=None, failed=0, reused=0)
        failed = reused = 0

        def update(result: Any, finished: int, total: int) -> None:
            nonlocal failed, reused
            failed += not result.ok
            reused += result.reused
            bar.update(task, completed=finished, total=total, failed=failed, reused=reused)

        yield update


def run_sweep(
    experiment: str | os.PathLike[str],
    *,
    out: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    plots: bool = True,
    console: Console | None = None,
) -> SweepTable:
    """Run an experiment and return its table (see :func:`regopack.sweep`).

    ``console`` is where the progress bar goes (default: stderr).
    """
    from regopack.experiments import run_experiment

    path = experiment_path(experiment)
    with _sweep_progress(progress, f"sweep {experiment}", console) as update:
        outcome = run_experiment(
            path,
            None if out is None else Path(out),
            workers=workers,
            progress=update,
            scheduler=scheduler,
        )
    drawn: list[Path] = []
    if plots:
        from regopack.experiments.plots import plot_experiment

        drawn = plot_experiment(outcome.out_dir)
    return table_from_result(outcome, drawn)
