from __future__ import annotations

import argparse
import csv
import tomllib
from pathlib import Path

import pytest
from rich.console import Console

from regopack.base.errors import ConfigError
from regopack.cli.sweep import run_sweep_command
from regopack.experiments import check_runs, expand, load_experiment, run_experiment
from regopack.experiments.builtin import builtin_experiment_path, builtin_experiments

NAMES = ["eta", "scaling", "screening", "seeds", "stress"]


def test_builtin_names_and_descriptions() -> None:
    found = builtin_experiments()
    assert sorted(found) == NAMES
    assert all(found[name] for name in NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_builtin_loads_expands_and_validates(name: str) -> None:
    experiment = load_experiment(builtin_experiment_path(name))
    runs = expand(experiment)
    assert runs
    assert len(check_runs(experiment, runs)) == len(runs)
    assert len({run.run_id for run in runs}) == len(runs)


def test_builtin_grids() -> None:
    eta = expand(load_experiment(builtin_experiment_path("eta")))
    assert [run.params["density.eta"] for run in eta] == list(range(0, 51, 5))
    seeds = expand(load_experiment(builtin_experiment_path("seeds")))
    assert [run.params["seed"] for run in seeds] == list(range(1, 10))
    scaling = expand(load_experiment(builtin_experiment_path("scaling")))
    assert {run.params["insertion.t"] for run in scaling} == {1.0, 0.999, 0.99}
    linear = {
        run.params["domain.width"] for run in scaling if run.params["insertion.search"] == "linear"
    }
    assert linear == {200, 400}
    stress = load_experiment(builtin_experiment_path("stress"))
    assert stress.verify
    params = [run.params for run in expand(stress)]
    assert max(p["size.d_max"] / p["size.d_min"] for p in params) == pytest.approx(1e4)
    assert {p["phases.0.shape.psi"] for p in params} >= {0.01, 1000}
    assert min(p["domain.width"] for p in params) == pytest.approx(400e-6)
    assert max(p["domain.width"] for p in params) == pytest.approx(400e6)


def test_unknown_builtin_is_one_line() -> None:
    with pytest.raises(ConfigError) as info:
        builtin_experiment_path("nope")
    message = str(info.value)
    assert "\n" not in message
    assert all(name in message for name in NAMES)


def _args(**kw: object) -> argparse.Namespace:
    base = {
        "experiment": None,
        "builtin": None,
        "list_builtin": False,
        "out": None,
        "workers": 1,
        "scheduler": None,
        "quiet": True,
        "no_plots": False,
    }
    base.update(kw)
    return argparse.Namespace(**base)


def test_list_builtin_prints_names() -> None:
    console = Console(record=True, width=200)
    assert run_sweep_command(_args(list_builtin=True), console) == 0
    text = console.export_text()
    assert all(name in text for name in NAMES)


def test_file_and_builtin_exclude_each_other(tmp_path: Path) -> None:
    with pytest.raises(ConfigError):
        run_sweep_command(_args(experiment=tmp_path / "x.toml", builtin="eta"), Console())
    with pytest.raises(ConfigError):
        run_sweep_command(_args(), Console())


def _tiny_stress(tmp_path: Path) -> Path:
    """The stress experiment with 30 particles and its first, extreme points only."""
    source = builtin_experiment_path("stress")
    data = tomllib.loads(source.read_text(encoding="utf-8"))
    group = data["zip"][0]
    keep = [0, 4, 8, 12, 13, 16]  # psi 0.01, psi 1000, a = 1, ratio 1e4, scale 1e-6, 1e6
    lines = [
        'name = "tiny-stress"',
        f'base = "{source.parent / "stress-scene.toml"}"',
        "verify = true",
        "",
        "[set]",
        "count = 30",
        "",
        "[[zip]]",
    ]
    for key, values in group.items():
        lines.append(f'"{key}" = [{", ".join(repr(values[k]) for k in keep)}]')
    path = tmp_path / "stress.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_stress_verify_metrics(tmp_path: Path) -> None:
    result = run_experiment(_tiny_stress(tmp_path), tmp_path / "out", workers=1)
    assert result.ok, [r.error for r in result.failed]
    for run in result.runs:
        m = run.metrics
        assert m["verify.overlap_pairs"] == 0
        assert m["verify.outside"] == 0
        assert m["verify.any_nan"] is False
        assert m["verify.ok"] is True
        assert m["verify.worst_overlap"] == 0.0
        assert m["placed"] > 0
    with result.results_path.open(newline="") as fh:
        header = next(csv.reader(fh))
    assert {
        "verify.overlap_pairs",
        "verify.worst_overlap",
        "verify.outside",
        "verify.any_nan",
        "fabric.anisotropy",
        "fabric.anisotropy_error",
        "fabric.z_mechanical",
        "fabric.rattler_fraction",
    } <= set(header)
    assert "fabric.principal_direction" not in header  # a list, not a single value
