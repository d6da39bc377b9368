"""The table that ``regopack sweep`` prints at the end."""

from __future__ import annotations

from pathlib import Path

import pytest
from rich.console import Console

from regopack.cli.sweep import _results_table
from regopack.experiments import Experiment, ExperimentResult, RunResult, expand


def _outcome(tmp_path: Path) -> ExperimentResult:
    experiment = Experiment.model_validate(
        {
            "base": "small",
            "sweep": {
                "phases.0.shape.n_vertices": [8],
                "size.d_min": [10.25],
                "size.d_max": [200.5],
                "seed": [1, 2],
            },
        }
    )
    runs = tuple(
        RunResult(spec, "done", tmp_path / spec.run_id, {"placed": 100 + spec.index})
        for spec in expand(experiment)
    )
    return ExperimentResult(
        experiment,
        tmp_path,
        runs,
        ("tried", "placed", "phi_domain", "phi_interior"),
        tmp_path / "results.csv",
        tmp_path / "experiment.json",
    )


@pytest.mark.parametrize("width", [60, 80, 200])
def test_run_ids_are_shown_whole_at_any_width(tmp_path: Path, width: int) -> None:
    outcome = _outcome(tmp_path)
    ids = [run.run_id for run in outcome.runs]
    assert ids[0][:-1] == ids[1][:-1] and len(ids[0]) > 40
    console = Console(record=True, width=width)
    console.print(_results_table(outcome))
    lines = console.export_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("┡"))
    body = lines[start + 1 : -1]
    first_column = "".join(line.split("│")[1].strip() for line in body)
    assert first_column == "".join(ids)
