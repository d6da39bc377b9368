"""Experiments: sweeps of scene parameters described by a TOML file.

An experiment file names a base scene and the scene fields to vary::

    name = "eta-vs-seed"
    base = "small"                       # built-in scene or path of a scene file
    metrics = ["placed", "phi_interior"]  # optional; see DEFAULT_METRICS
    max_runs = 10000                     # optional; a larger grid is refused (MAX_RUNS)

    [set]                                # applied to every run
    count = 150

    [sweep]                              # every combination is run
    "density.eta" = [0, 5, 10]
    seed = "1..3"                        # integer range, both ends included

    [[zip]]                              # these vary together
    "domain.width" = [200, 400]
    "domain.height" = [200, 400]

:func:`load_experiment` reads and checks the file, :func:`expand` lists the
runs of the grid, :func:`check_runs` validates every run's scene, and
:func:`run_experiment` runs them (in worker processes, in-process, or on a Dask
cluster) and collects their summaries into ``results.csv``.

The code lies in one module per concern: :mod:`regopack.experiments.file` (the
model and reading the file), :mod:`regopack.experiments.grid` (the runs of the
grid), :mod:`regopack.experiments.workers` (running scenes on processes or
Dask), :mod:`regopack.experiments.results` (``results.csv``) and
:mod:`regopack.experiments.run` (the sweep as a whole); this module gathers
their public names.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.experiments.builtin import builtin_experiment_path as builtin_experiment_path
    from regopack.experiments.builtin import builtin_experiments as builtin_experiments
    from regopack.experiments.file import MAX_RUNS as MAX_RUNS
    from regopack.experiments.file import Experiment as Experiment
    from regopack.experiments.file import SweepValues as SweepValues
    from regopack.experiments.file import experiment_from_dict as experiment_from_dict
    from regopack.experiments.file import load_experiment as load_experiment
    from regopack.experiments.grid import ERROR_TXT as ERROR_TXT
    from regopack.experiments.grid import SCENE_JSON as SCENE_JSON
    from regopack.experiments.grid import RunSpec as RunSpec
    from regopack.experiments.grid import check_runs as check_runs
    from regopack.experiments.grid import expand as expand
    from regopack.experiments.results import DEFAULT_METRICS as DEFAULT_METRICS
    from regopack.experiments.results import RESULTS_CSV as RESULTS_CSV
    from regopack.experiments.results import ExperimentProgress as ExperimentProgress
    from regopack.experiments.results import ExperimentResult as ExperimentResult
    from regopack.experiments.results import RunResult as RunResult
    from regopack.experiments.run import EXPERIMENT_JSON as EXPERIMENT_JSON
    from regopack.experiments.run import default_experiment_dir as default_experiment_dir
    from regopack.experiments.run import run_experiment as run_experiment
    from regopack.experiments.workers import PARENT_POLL_S as PARENT_POLL_S
    from regopack.experiments.workers import verify_metrics as verify_metrics

__all__ = [
    "DEFAULT_METRICS",
    "ERROR_TXT",
    "EXPERIMENT_JSON",
    "MAX_RUNS",
    "PARENT_POLL_S",
    "RESULTS_CSV",
    "SCENE_JSON",
    "Experiment",
    "ExperimentProgress",
    "ExperimentResult",
    "RunResult",
    "RunSpec",
    "SweepValues",
    "builtin_experiment_path",
    "builtin_experiments",
    "check_runs",
    "default_experiment_dir",
    "expand",
    "experiment_from_dict",
    "load_experiment",
    "run_experiment",
    "verify_metrics",
]

_SOURCES = {
    "DEFAULT_METRICS": "regopack.experiments.results",
    "ERROR_TXT": "regopack.experiments.grid",
    "EXPERIMENT_JSON": "regopack.experiments.run",
    "Experiment": "regopack.experiments.file",
    "ExperimentProgress": "regopack.experiments.results",
    "ExperimentResult": "regopack.experiments.results",
    "MAX_RUNS": "regopack.experiments.file",
    "PARENT_POLL_S": "regopack.experiments.workers",
    "RESULTS_CSV": "regopack.experiments.results",
    "RunResult": "regopack.experiments.results",
    "RunSpec": "regopack.experiments.grid",
    "SCENE_JSON": "regopack.experiments.grid",
    "SweepValues": "regopack.experiments.file",
    "builtin_experiment_path": "regopack.experiments.builtin",
    "builtin_experiments": "regopack.experiments.builtin",
    "check_runs": "regopack.experiments.grid",
    "default_experiment_dir": "regopack.experiments.run",
    "expand": "regopack.experiments.grid",
    "experiment_from_dict": "regopack.experiments.file",
    "load_experiment": "regopack.experiments.file",
    "run_experiment": "regopack.experiments.run",
    "verify_metrics": "regopack.experiments.workers",
}

__getattr__, __dir__ = lazy_exports(globals(), _SOURCES)
