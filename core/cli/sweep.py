"""The ``regopack sweep`` command: run an experiment file (see :mod:`regopack.experiments`).

``regopack sweep EXPERIMENT.toml [--out DIR] [--workers N] [--scheduler ADDR]``
(or ``regopack sweep --builtin NAME``) validates every run's scene, runs the
grid with a progress display (runs finished out of the total, failures),
prints a table of the runs and draws the plots its results allow (see
:mod:`regopack.experiments.plots`). It exits
with status 0 when every run finished and 1 when some failed; a bad experiment
file raises :class:`~regopack.base.errors.ConfigError` (one line, status 2 in
:func:`regopack.cli.commands.main`).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

if TYPE_CHECKING:
    from regopack.experiments import ExperimentResult

__all__ = ["add_sweep_parser", "run_sweep_command"]

EXIT_OK = 0
EXIT_FAILED_RUNS = 1

_TABLE_METRICS = 4
"""Metric columns shown in the final table (all of them are in results.csv)."""


def add_sweep_parser(subparsers: argparse._SubParsersAction[Any]) -> None:
    """Add the ``sweep`` command to the ``regopack`` sub-command parsers.

    The parser's ``handler`` default is ``handler(args, out, err) -> int``, the
    convention of :func:`regopack.cli.commands.main`.
    """
    sweep = subparsers.add_parser(
        "sweep",
        help="run an experiment: a sweep of scene values, collected into results.csv",
        description=(
            "Run every combination of the scene values an experiment file lists, each "
            "into its own folder, and collect the summaries into results.csv. Finished "
            "runs are skipped when the sweep is started again."
        ),
    )
    sweep.add_argument(
        "experiment",
        type=Path,
        nargs="?",
        metavar="EXPERIMENT",
        help="experiment file (TOML); not with --builtin",
    )
    sweep.add_argument(
        "--builtin",
        metavar="NAME",
        help="run a built-in experiment instead of a file (see --list-builtin)",
    )
    sweep.add_argument(
        "--list-builtin",
        action="store_true",
        help="list the built-in experiments and exit",
    )
    from regopack.cli.args import output_path

    sweep.add_argument(
        "--out",
        type=output_path,
        metavar="DIR",
        help="output directory (default: runs/<experiment name>)",
    )
    sweep.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="local worker processes (default: the number of CPUs; 1 runs in-process)",
    )
    sweep.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="run on a Dask cluster, e.g. tcp://host:8786 (needs Dask: pip install distributed)",
    )
    sweep.add_argument("--quiet", action="store_true", help="print no progress and no table")
    sweep.add_argument(
        "--no-plots", action="store_true", help="do not draw the plots into DIR/plots"
    )
    sweep.set_defaults(handler=_handler)


def _handler(args: argparse.Namespace, out: Console, err: Console) -> int:
    return run_sweep_command(args, out, err)


def _fmt(value: Any) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return "n/a" if math.isnan(value) else f"{value:.4g}"
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{value:,}"
    return str(value)


def _results_table(outcome: ExperimentResult) -> Table:
    """One row per run: its id, status, the first metrics and the error of a failed run.

    Run ids are shown whole (folded onto several lines when the terminal is
    narrow), so that no two runs look alike.
    """
    metrics = list(outcome.metrics[:_TABLE_METRICS])
    table = Table(title=f"regopack sweep: {outcome.experiment.experiment_name}")
    # a narrow terminal folds a long run id onto more lines; cutting it short
    # ("eta=0,seed=1,wid…") could show two runs under the same text
    table.add_column("run", style="bold", overflow="fold")
    table.add_column("status")
    for name in metrics:
        table.add_column(name, justify="right")
    if outcome.failed:
        table.add_column("error", overflow="fold")
    for run in outcome.runs:
        if run.ok:
            status = Text("done (reused)" if run.reused else "done")
            cells = [Text(_fmt(run.metrics.get(m))) for m in metrics]
        else:
            status = Text("failed", style="red")
            cells = [Text("") for _ in metrics]
        if outcome.failed:
            cells.append(Text(run.error or ""))
        table.add_row(Text(run.run_id), status, *cells)
    return table


def run_sweep_command(
    args: argparse.Namespace, console: Console, progress_console: Console | None = None
) -> int:
    """Run ``regopack sweep`` with parsed arguments.

    Parameters
    ----------
    args
        Namespace with ``experiment``, ``builtin``, ``list_builtin``, ``out``,
        ``workers``, ``scheduler``, ``quiet`` and ``no_plots`` (missing
        attributes take their defaults).
    console
        Where the final table goes.
    progress_console
        Where the progress display goes (default: ``console``).

    Returns
    -------
    int
        0 when every run finished, 1 when some failed.
    """
    from regopack.base.errors import ConfigError
    from regopack.experiments.api import run_sweep
    from regopack.experiments.builtin import builtin_experiment_path, builtin_experiments

    if getattr(args, "list_builtin", False):
        for name, description in builtin_experiments().items():
            console.print(Text(f"{name:<10} {description}"), soft_wrap=True)
        return EXIT_OK
    builtin = getattr(args, "builtin", None)
    experiment_path = getattr(args, "experiment", None)
    if builtin is not None:
        if experiment_path is not None:
            raise ConfigError("give an experiment file or --builtin NAME, not both")
        experiment_path = builtin_experiment_path(builtin)
    elif experiment_path is None:
        raise ConfigError("give an experiment file, --builtin NAME or --list-builtin")
    quiet = bool(getattr(args, "quiet", False))
    table = run_sweep(
        experiment_path,
        out=getattr(args, "out", None),
        workers=getattr(args, "workers", None),
        scheduler=getattr(args, "scheduler", None),
        progress=not quiet,
        plots=not getattr(args, "no_plots", False),
        console=progress_console if progress_console is not None else console,
    )
    outcome, plots = table.result, table.plots
    if not quiet:
        console.print(_results_table(outcome))
        if plots:
            console.print(Text(f"plots: {outcome.out_dir / 'plots'} ({len(plots)} files)"))
        done = len(outcome.runs) - len(outcome.failed)
        console.print(
            Text(
                f"{done}/{len(outcome.runs)} runs done, {len(outcome.failed)} failed; "
                f"results: {outcome.results_path}"
            )
        )
    return EXIT_OK if outcome.ok else EXIT_FAILED_RUNS
