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

The code lies in one module per concern: :mod:`regopack.experiment_file` (the
model and reading the file), :mod:`regopack.experiment_grid` (the runs of the
grid), :mod:`regopack.experiment_workers` (running scenes on processes or
Dask), :mod:`regopack.experiment_results` (``results.csv``) and
:mod:`regopack.experiment_run` (the sweep as a whole); this module gathers
their public names.
"""

from __future__ import annotations

from regopack.experiment_file import MAX_RUNS as MAX_RUNS
from regopack.experiment_file import Experiment, SweepValues, experiment_from_dict, load_experiment
from regopack.experiment_grid import ERROR_TXT as ERROR_TXT
from regopack.experiment_grid import SCENE_JSON as SCENE_JSON
from regopack.experiment_grid import RunSpec, check_runs, expand
from regopack.experiment_results import (
    DEFAULT_METRICS,
    ExperimentProgress,
    ExperimentResult,
    RunResult,
)
from regopack.experiment_results import RESULTS_CSV as RESULTS_CSV
from regopack.experiment_run import EXPERIMENT_JSON as EXPERIMENT_JSON
from regopack.experiment_run import default_experiment_dir, run_experiment
from regopack.experiment_workers import PARENT_POLL_S as PARENT_POLL_S
from regopack.experiment_workers import verify_metrics

__all__ = [
    "DEFAULT_METRICS",
    "Experiment",
    "ExperimentProgress",
    "ExperimentResult",
    "RunResult",
    "RunSpec",
    "SweepValues",
    "check_runs",
    "default_experiment_dir",
    "expand",
    "experiment_from_dict",
    "load_experiment",
    "run_experiment",
    "verify_metrics",
]
