"""Running an experiment: check every run, run the grid, collect the results.

:func:`run_experiment` expands and checks the grid, writes ``experiment.json``,
reuses the runs that finished before, runs the others (see
:mod:`regopack.experiments.workers`) and keeps ``results.csv`` up to date
after every run.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from regopack.base.errors import ConfigError
from regopack.base.outdir import check_replaceable, remove_leftovers, replace_folder
from regopack.experiments.file import Experiment, load_experiment
from regopack.experiments.grid import ERROR_TXT, SCENE_JSON, _sanitise, check_runs, expand
from regopack.experiments.results import (
    RESULTS_CSV,
    ExperimentProgress,
    ExperimentResult,
    RunResult,
    _collect,
    _metric_columns,
    _param_columns,
    _write_csv,
)
from regopack.experiments.workers import _dask, _Job, _one_line, _submit_dask, _submit_local
from regopack.packing.core import write_json_atomic
from regopack.run.pipeline import RUN_FOLDER
from regopack.scenes.model import ResolvedScene

__all__ = ["EXPERIMENT_JSON", "default_experiment_dir", "run_experiment"]

EXPERIMENT_JSON = "experiment.json"
"""Name of the file describing the resolved grid in the output directory."""


def _scene_text(scene: ResolvedScene) -> str:
    return json.dumps(scene.to_dict(), indent=2, sort_keys=True, default=str) + "\n"


def _read_text(path: Path) -> str | None:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _write_failed_run(run_dir: Path, scene_text: str, message: str) -> str:
    """Replace the run folder by the record of a failed run: its scene and its error.

    Returns the message to record: ``message``, plus why the record could not
    be written when the folder is not writable. That run fails alone; the
    sweep goes on with the others.
    """
    try:
        with replace_folder(run_dir, RUN_FOLDER) as tmp:
            (tmp / SCENE_JSON).write_text(scene_text, encoding="utf-8")
            (tmp / ERROR_TXT).write_text(message + "\n", encoding="utf-8")
    except (OSError, ConfigError) as err:
        return f"{message} (and {run_dir / ERROR_TXT} could not be written: {_one_line(err)})"
    return message


def _read_summary(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    return data if isinstance(data, dict) else None


def default_experiment_dir(experiment: Experiment) -> Path:
    """``runs/<experiment name>`` (relative to the working directory)."""
    return Path("runs") / _sanitise(experiment.experiment_name)


def run_experiment(
    experiment_path: str | Path,
    out_dir: str | Path | None = None,
    workers: int | None = None,
    progress: ExperimentProgress | None = None,
    *,
    scheduler: str | None = None,
) -> ExperimentResult:
    """Run every run of an experiment and collect the results.

    Parameters
    ----------
    experiment_path
        The experiment file (TOML).
    out_dir
        Output directory (default: ``runs/<experiment name>``). Each run writes
        into ``<out_dir>/<run id>/``; ``results.csv`` and ``experiment.json`` go
        into ``out_dir``.
    workers
        Number of local worker processes (default: ``os.cpu_count()``); ``1``
        runs everything in this process.
    progress
        Called as ``progress(result, finished, total)`` after each run.
    scheduler
        Address of a Dask scheduler (``tcp://host:port``); the runs are then
        submitted to that cluster through ``distributed.Client`` (install the
        ``dask`` extra). The workers must see ``out_dir``. ``workers`` and
        ``scheduler`` exclude each other.

    Returns
    -------
    ExperimentResult
        One result per run, in grid order.

    Notes
    -----
    Every run's scene, and every run folder, is checked before anything
    runs. Each run folder is written as a whole (see
    :func:`regopack.run.pipeline.run_scene`): it holds the run's ``scene.json``,
    packing and summary, or, for a run that raised, ``scene.json`` and
    ``error.txt`` with its message, never a mix of two runs. A run whose
    summary file exists, and whose ``scene.json`` matches its current
    resolved scene, is not run again, so restarting an interrupted sweep
    loses nothing (a run whose scene changed, e.g. through the experiment's
    ``set``, runs again). A failed run is also listed in ``results.csv``;
    the other runs go on. ``results.csv`` is rewritten (atomically) after
    every finished run.

    When the sweep is interrupted (``KeyboardInterrupt``, or
    :class:`~regopack.base.errors.Terminated` for SIGTERM), the local worker
    processes are stopped and the temporary folders of their unfinished runs
    removed; the finished runs stay in ``results.csv`` and are reused when
    the sweep is started again.

    Raises
    ------
    ConfigError
        A bad experiment file, a bad scene in any run, bad options, or an
        output directory that cannot be written.
    """
    experiment = load_experiment(experiment_path)
    if workers is not None and workers < 1:
        raise ConfigError(f"--workers {workers}: must be at least 1")
    if scheduler is not None and workers is not None:
        raise ConfigError("--workers and --scheduler exclude each other")
    if scheduler is not None:
        _dask(scheduler)
    runs = expand(experiment)
    resolved = check_runs(experiment, runs)
    out = Path(out_dir) if out_dir is not None else default_experiment_dir(experiment)
    for run in runs:
        try:
            check_replaceable(out / run.run_id, RUN_FOLDER)
        except ConfigError as err:
            raise ConfigError(f"{experiment.label}: run {run.run_id}: {err}") from err
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"cannot create the output directory {out}: {err}") from err
    results_path = out / RESULTS_CSV
    experiment_json = out / EXPERIMENT_JSON
    write_json_atomic(
        experiment_json,
        {
            "name": experiment.experiment_name,
            "experiment": str(Path(experiment_path).resolve()),
            "base": str(experiment.base_ref),
            "parameters": _param_columns(experiment),
            "metrics": list(experiment.metrics) if experiment.metrics is not None else None,
            "runs": [
                {**run.to_dict(), "scene": scene.to_dict()}
                for run, scene in zip(runs, resolved, strict=True)
            ],
        },
    )

    total = len(runs)
    finished: list[RunResult] = []

    def record(result: RunResult, *, write: bool = True) -> None:
        finished.append(result)
        if write:
            _write_csv(results_path, experiment, finished)
        if progress is not None:
            progress(result, len(finished), total)

    by_id = {run.run_id: run for run in runs}
    jobs: list[_Job] = []
    for run, scene in zip(runs, resolved, strict=True):
        run_dir = out / run.run_id
        scene_text = _scene_text(scene)
        summary = _read_summary(run_dir / scene.scene.outputs.summary)
        if summary is not None and _read_text(run_dir / SCENE_JSON) == scene_text:
            metrics = _collect(summary, experiment.metrics)
            record(RunResult(run, "done", run_dir, metrics, reused=True), write=False)
            continue
        # an older run in the folder stays until this one replaces it as a whole;
        # its scene.json does not match, so it is never taken for this run
        jobs.append(
            _Job(
                run_id=run.run_id,
                base=str(experiment.base_ref),
                overrides=run.overrides,
                out_dir=str(run_dir.resolve()),
                figures=experiment.figures,
                verify=experiment.verify,
                voids=experiment.voids,
                scene_text=scene_text,
            )
        )
    _write_csv(results_path, experiment, finished)
    stream: Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]
    if not jobs:
        stream = iter(())
    elif scheduler is not None:
        stream = _submit_dask(jobs, scheduler)
    else:
        count = (os.cpu_count() or 1) if workers is None else workers
        stream = _submit_local(jobs, max(1, min(count, len(jobs))))
    unfinished = {job.run_id: job for job in jobs}
    try:
        for job, (summary, error) in stream:
            run = by_id[job.run_id]
            run_dir = out / run.run_id
            if error is None and summary is not None:
                record(RunResult(run, "done", run_dir, _collect(summary, experiment.metrics)))
            else:
                message = _write_failed_run(
                    run_dir, job.scene_text, error or "the run returned no summary"
                )
                record(RunResult(run, "failed", run_dir, error=message))
            del unfinished[job.run_id]
    except BaseException:
        close = getattr(stream, "close", None)
        if close is not None:
            close()  # stops the workers now, not when the generator is collected
        if scheduler is None:
            for job in unfinished.values():
                remove_leftovers(job.out_dir)
        raise
    ordered = tuple(sorted(finished, key=lambda r: r.spec.index))
    columns = _metric_columns(experiment, ordered)
    return ExperimentResult(
        experiment=experiment,
        out_dir=out,
        runs=ordered,
        metrics=tuple(columns),
        results_path=results_path,
        json_path=experiment_json,
    )
