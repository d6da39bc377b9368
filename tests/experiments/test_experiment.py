from __future__ import annotations

import argparse
import csv
import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console

from regopack import experiments as experiment_module
from regopack.base.errors import ConfigError
from regopack.cli.sweep import add_sweep_parser, run_sweep_command
from regopack.experiments import (
    DEFAULT_METRICS,
    RunResult,
    check_runs,
    expand,
    experiment_from_dict,
    load_experiment,
    run_experiment,
)
from regopack.experiments import file as experiment_file
from regopack.experiments import grid as experiment_grid
from regopack.experiments import run as experiment_run
from regopack.experiments import workers as experiment_workers

TINY = """\
name = "tiny"
base = "small"

[set]
count = 150

[sweep]
"density.eta" = [0, 10]
seed = "1..2"
"""

IDS = ["eta=0,seed=1", "eta=0,seed=2", "eta=10,seed=1", "eta=10,seed=2"]


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as fh:
        return list(csv.DictReader(fh))


def ids(data: dict[str, Any]) -> list[str]:
    return [run.run_id for run in expand(experiment_from_dict(data, source="exp.toml"))]


# ---------------------------------------------------------------------------
# grid expansion


def test_product_in_file_order_last_axis_fastest() -> None:
    data = {"base": "small", "sweep": {"seed": [1, 2, 3], "density.eta": [0, 5]}}
    assert ids(data) == [
        "seed=1,eta=0",
        "seed=1,eta=5",
        "seed=2,eta=0",
        "seed=2,eta=5",
        "seed=3,eta=0",
        "seed=3,eta=5",
    ]


def test_overrides_apply_set_first_then_the_varied_fields() -> None:
    exp = experiment_from_dict(
        {"base": "small", "set": {"count": 150}, "sweep": {"insertion.t": [1, 0.99]}}
    )
    runs = expand(exp)
    assert [r.overrides for r in runs] == [
        ("count=150", "insertion.t=1"),
        ("count=150", "insertion.t=0.99"),
    ]
    assert [r.params for r in runs] == [{"insertion.t": 1}, {"insertion.t": 0.99}]
    assert [r.index for r in runs] == [0, 1]


def test_zip_groups_vary_together_after_the_sweep_axes() -> None:
    data = {
        "base": "small",
        "sweep": {"seed": [1, 2]},
        "zip": [{"domain.width": [200, 400], "domain.height": [100, 200]}],
    }
    assert ids(data) == [
        "seed=1,width=200,height=100",
        "seed=1,width=400,height=200",
        "seed=2,width=200,height=100",
        "seed=2,width=400,height=200",
    ]


@pytest.mark.parametrize(
    ("text", "values"),
    [("1..4", [1, 2, 3, 4]), ("-1..1", [-1, 0, 1]), ("0..10..5", [0, 5, 10]), ("3..3", [3])],
)
def test_integer_ranges_include_both_ends(text: str, values: list[int]) -> None:
    runs = expand(experiment_from_dict({"base": "small", "sweep": {"seed": text}}))
    assert [r.params["seed"] for r in runs] == values


def test_nested_tables_are_dotted_keys(tmp_path: Path) -> None:
    path = write(
        tmp_path / "exp.toml",
        'base = "small"\n[sweep]\ndensity.eta = [0, 5]\n[set.domain]\nwidth = 300\n',
    )
    runs = expand(load_experiment(path))
    assert [r.overrides for r in runs] == [
        ("domain.width=300", "density.eta=0"),
        ("domain.width=300", "density.eta=5"),
    ]


def test_ids_are_safe_file_names_and_shared_names_use_the_whole_key() -> None:
    data = {
        "base": "small",
        "sweep": {"name": ["a b/c"], "density.kind": ["eta"], "insertion.kind": ["available-arc"]},
    }
    assert ids(data) == ["name=a_b_c,density.kind=eta,insertion.kind=available-arc"]


def test_without_varied_fields_there_is_one_run() -> None:
    assert ids({"base": "small"}) == ["base"]


def test_long_ids_are_shortened_but_stay_distinct() -> None:
    data = {"base": "small", "sweep": {"name": ["x" * 300 + "1", "x" * 300 + "2"]}}
    first, second = ids(data)
    assert first != second
    assert len(first) <= 120 and len(second) <= 120


def test_expansion_is_deterministic() -> None:
    data = {"base": "small", "sweep": {"seed": "1..3", "density.eta": [0, 5, 10]}}
    assert ids(data) == ids(data)


# ---------------------------------------------------------------------------
# validation: one line naming the file and the key


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            'base = "small"\n[sweep]\n"density.eta" = [0, -3]\n',
            "exp.toml: sweep.density.eta = -3: Input should be greater than or equal to 0",
        ),
        (
            'base = "small"\n[sweep]\n"domain.widht" = [100]\n',
            "exp.toml: sweep.domain.widht = 100: unknown field; did you mean 'width'?",
        ),
        (
            'base = "small"\n[set]\n"insertion.t" = 2\n',
            "exp.toml: set.insertion.t = 2",
        ),
        (
            'base = "small"\n[[zip]]\n"domain.width" = [1, 2]\n"domain.height" = [0, 1]\n',
            "exp.toml: zip.0.domain.height = 0",
        ),
        ('base = "small"\n[sweep]\nseed = "a..b"\n', "exp.toml: sweep.seed: expected a list"),
        ('base = "small"\n[sweep]\nseed = "9..1"\n', "exp.toml: sweep.seed: range '9..1' is empty"),
        ('base = "small"\n[sweep]\nseed = []\n', "exp.toml: sweep.seed: "),
        ('base = "small"\nsweeps = 1\n', "exp.toml: sweeps: Extra inputs are not permitted"),
        ("[sweep]\nseed = [1]\n", "exp.toml: base: Field required"),
        ('base = "small"\n[sweep]\nseed = [1, 1]\n', "exp.toml: runs 0 and 1 get the same id"),
        (
            'base = "small"\n[sweep]\nseed = [1]\n[set]\nseed = 2\n',
            "exp.toml: sweep.seed: also set in set",
        ),
        (
            'base = "small"\n[[zip]]\n"domain.width" = [1, 2]\n"domain.height" = [1]\n',
            "exp.toml: zip.0: the lists of a zip group must have the same length",
        ),
        ('base = "missing.toml"\n', "exp.toml: base scene: "),
        (
            'base = "small"\nmetrics = ["analyses.rdf.g_max"]\n',
            "exp.toml: metrics: 'analyses.rdf.g_max' needs the analysis 'rdf'",
        ),
        ('base = "small"\n[sweep]\n"density.kind" = ["nope"]\n', "exp.toml: sweep.density.kind"),
        ('base = "small"\n[sweep\n', "exp.toml: invalid TOML"),
    ],
)
def test_bad_experiments_give_one_line_naming_the_key(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, expected: str
) -> None:
    monkeypatch.chdir(tmp_path)
    write(tmp_path / "exp.toml", text)
    with pytest.raises(ConfigError) as info:
        check_runs(load_experiment("exp.toml"))
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(expected), message


def test_every_run_is_validated_before_anything_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[str] = []
    monkeypatch.setattr(experiment_workers, "run_scene", lambda *a, **k: calls.append("run"))
    path = write(tmp_path / "exp.toml", 'base = "small"\n[sweep]\n"density.eta" = [0, 5, -1]\n')
    with pytest.raises(ConfigError, match=r"\(run eta=-1\)$"):
        run_experiment(path, tmp_path / "out", workers=1)
    assert calls == []
    assert not (tmp_path / "out").exists()


def test_a_base_scene_path_is_relative_to_the_experiment_file(tmp_path: Path) -> None:
    (tmp_path / "scenes").mkdir()
    base = (Path(experiment_module.__file__).parents[1] / "scenes" / "small.toml").read_text()
    write(tmp_path / "scenes" / "mine.toml", base.replace('name = "small"', 'name = "mine"'))
    path = write(tmp_path / "exp.toml", 'base = "scenes/mine.toml"\n[sweep]\nseed = [1, 2]\n')
    resolved = check_runs(load_experiment(path))
    assert [r.name for r in resolved] == ["mine", "mine"]
    assert [r.seed for r in resolved] == [1, 2]


def test_workers_must_be_positive(tmp_path: Path) -> None:
    path = write(tmp_path / "exp.toml", TINY)
    with pytest.raises(ConfigError, match="--workers 0"):
        run_experiment(path, tmp_path / "out", workers=0)


# ---------------------------------------------------------------------------
# running


@pytest.fixture(scope="module")
def tiny_sweep(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any, list[list[str]]]:
    """The tiny 2 x 2 sweep run in-process, with the CSV seen after each finished run."""
    root = tmp_path_factory.mktemp("sweep")
    path = write(root / "tiny.toml", TINY)
    seen: list[list[str]] = []

    def progress(result: RunResult, finished: int, total: int) -> None:
        assert total == 4
        seen.append([row["run_id"] for row in read_csv(root / "out" / "results.csv")])

    outcome = run_experiment(path, root / "out", workers=1, progress=progress)
    return root, outcome, seen


def test_a_sweep_writes_one_folder_per_run(tiny_sweep: tuple[Path, Any, Any]) -> None:
    root, outcome, _ = tiny_sweep
    assert outcome.ok
    assert [r.run_id for r in outcome.runs] == IDS
    for run_id in IDS:
        assert (root / "out" / run_id / "packing.npz").is_file()
        assert (root / "out" / run_id / "scene.json").is_file()
        summary = json.loads((root / "out" / run_id / "summary.json").read_text())
        assert summary["tried"] == 150
    assert {json.loads((root / "out" / i / "summary.json").read_text())["seed"] for i in IDS} == {
        1,
        2,
    }


def test_results_csv_has_a_row_per_run_with_the_metrics(
    tiny_sweep: tuple[Path, Any, Any],
) -> None:
    root, outcome, _ = tiny_sweep
    rows = read_csv(root / "out" / "results.csv")
    assert [row["run_id"] for row in rows] == IDS
    head = ["run_id", "density.eta", "seed", "status", "error", *DEFAULT_METRICS]
    assert list(rows[0])[: len(head)] == head
    fabric = [
        f"fabric.{key}"
        for key in json.loads((root / "out" / IDS[0] / "summary.json").read_text())["fabric"]
        if key != "principal_direction"
    ]
    assert sorted(list(rows[0])[len(head) :]) == sorted(fabric) and "fabric.anisotropy" in fabric
    assert [(row["density.eta"], row["seed"]) for row in rows] == [
        ("0", "1"),
        ("0", "2"),
        ("10", "1"),
        ("10", "2"),
    ]
    for row, run in zip(rows, outcome.runs, strict=True):
        assert row["status"] == "done" and row["error"] == ""
        assert row["tried"] == "150"
        assert int(row["placed"]) == run.metrics["placed"] > 0
        assert 0 < float(row["phi_domain"]) < 1
        assert float(row["wall_time_s"]) > 0
    assert outcome.metrics[: len(DEFAULT_METRICS)] == DEFAULT_METRICS
    assert sorted(outcome.metrics[len(DEFAULT_METRICS) :]) == sorted(fabric)


def test_results_csv_is_complete_after_every_run(tiny_sweep: tuple[Path, Any, Any]) -> None:
    _, _, seen = tiny_sweep
    assert seen == [IDS[:1], IDS[:2], IDS[:3], IDS]


def test_experiment_json_holds_the_resolved_grid(tiny_sweep: tuple[Path, Any, Any]) -> None:
    root, _, _ = tiny_sweep
    data = json.loads((root / "out" / "experiment.json").read_text())
    assert data["name"] == "tiny"
    assert data["parameters"] == ["density.eta", "seed"]
    assert [run["id"] for run in data["runs"]] == IDS
    last = data["runs"][-1]
    assert last["params"] == {"density.eta": 10, "seed": 2}
    assert last["scene"]["density"]["eta"] == 10.0
    assert last["scene"]["count"] == 150


def test_a_rerun_skips_the_finished_runs(
    tiny_sweep: tuple[Path, Any, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    root, first, _ = tiny_sweep
    calls: list[Any] = []
    monkeypatch.setattr(experiment_workers, "run_scene", lambda *a, **k: calls.append(a))
    mtimes = {i: (root / "out" / i / "packing.npz").stat().st_mtime_ns for i in IDS}
    again = run_experiment(root / "tiny.toml", root / "out", workers=1)
    assert calls == []
    assert all(r.reused for r in again.runs)
    assert [r.metrics for r in again.runs] == [r.metrics for r in first.runs]
    assert mtimes == {i: (root / "out" / i / "packing.npz").stat().st_mtime_ns for i in IDS}
    assert [row["status"] for row in read_csv(root / "out" / "results.csv")] == ["done"] * 4


def test_only_the_unfinished_runs_run_again(tmp_path: Path) -> None:
    path = write(tmp_path / "tiny.toml", TINY)
    run_experiment(path, tmp_path / "out", workers=1)
    (tmp_path / "out" / IDS[2] / "summary.json").unlink()
    keep = (tmp_path / "out" / IDS[0] / "packing.npz").stat().st_mtime_ns
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.reused for r in outcome.runs] == [True, True, False, True]
    assert (tmp_path / "out" / IDS[2] / "summary.json").is_file()
    assert (tmp_path / "out" / IDS[0] / "packing.npz").stat().st_mtime_ns == keep


def test_an_interrupted_sweep_keeps_a_correct_csv_and_resumes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = experiment_workers.run_scene

    def interrupted(resolved: Any, out_dir: Any, *args: Any, **kwargs: Any) -> Any:
        if Path(out_dir).name == IDS[2]:
            raise KeyboardInterrupt
        return real(resolved, out_dir, *args, **kwargs)

    monkeypatch.setattr(experiment_workers, "run_scene", interrupted)
    path = write(tmp_path / "tiny.toml", TINY)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(path, tmp_path / "out", workers=1)
    rows = read_csv(tmp_path / "out" / "results.csv")
    assert [(row["run_id"], row["status"]) for row in rows] == [(i, "done") for i in IDS[:2]]

    monkeypatch.setattr(experiment_workers, "run_scene", real)
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.reused for r in outcome.runs] == [True, True, False, False]
    assert [row["run_id"] for row in read_csv(tmp_path / "out" / "results.csv")] == IDS


def test_a_run_whose_scene_changed_runs_again(tmp_path: Path) -> None:
    path = write(tmp_path / "tiny.toml", TINY.replace('seed = "1..2"', "seed = [1]"))
    run_experiment(path, tmp_path / "out", workers=1)
    write(path, path.read_text().replace("count = 150", "count = 120"))
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.reused for r in outcome.runs] == [False, False]
    assert [r.metrics["tried"] for r in outcome.runs] == [120, 120]
    again = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.reused for r in again.runs] == [True, True]


def test_worker_processes_give_the_same_results(
    tiny_sweep: tuple[Path, Any, Any], tmp_path: Path
) -> None:
    root, in_process, _ = tiny_sweep
    outcome = run_experiment(root / "tiny.toml", tmp_path / "out", workers=2)
    assert outcome.ok
    assert [r.run_id for r in outcome.runs] == IDS
    rows = read_csv(tmp_path / "out" / "results.csv")
    assert [row["run_id"] for row in rows] == IDS

    def placed(run: RunResult) -> tuple[Any, ...]:
        return run.metrics["placed"], run.metrics["phi_domain"], run.metrics["phi_interior"]

    assert [placed(r) for r in outcome.runs] == [placed(r) for r in in_process.runs]


def test_a_failing_run_is_recorded_and_the_others_finish(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = experiment_workers.run_scene

    def flaky(resolved: Any, out_dir: Any, *args: Any, **kwargs: Any) -> Any:
        if Path(out_dir).name == IDS[1]:
            raise RuntimeError("the disk\nis on fire")
        return real(resolved, out_dir, *args, **kwargs)

    monkeypatch.setattr(experiment_workers, "run_scene", flaky)
    path = write(tmp_path / "tiny.toml", TINY)
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert not outcome.ok
    assert [r.run_id for r in outcome.failed] == [IDS[1]]
    assert outcome.failed[0].error == "RuntimeError: the disk is on fire"
    assert (tmp_path / "out" / IDS[1] / "error.txt").read_text() == (
        "RuntimeError: the disk is on fire\n"
    )
    rows = read_csv(tmp_path / "out" / "results.csv")
    assert [row["status"] for row in rows] == ["done", "failed", "done", "done"]
    assert rows[1]["error"] == "RuntimeError: the disk is on fire"
    assert rows[1]["placed"] == "" and rows[2]["placed"] != ""

    monkeypatch.setattr(experiment_workers, "run_scene", real)
    retried = run_experiment(path, tmp_path / "out", workers=1)
    assert retried.ok
    assert [r.reused for r in retried.runs] == [True, False, True, True]
    assert not (tmp_path / "out" / IDS[1] / "error.txt").exists()


def test_an_unwritable_run_folder_fails_that_run_only(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Neither the run nor the record of its failure can be written: the others go on."""
    import errno
    from contextlib import contextmanager

    real_run, real_replace = experiment_workers.run_scene, experiment_run.replace_folder

    def refuse(name: Any) -> None:
        if Path(name).name == IDS[1]:
            raise PermissionError(errno.EACCES, "Permission denied", str(name))

    def run_scene(resolved: Any, out_dir: Any, *args: Any, **kwargs: Any) -> Any:
        refuse(out_dir)
        return real_run(resolved, out_dir, *args, **kwargs)

    @contextmanager
    def replace_folder(folder: Any, kind: str) -> Any:
        refuse(folder)
        with real_replace(folder, kind) as tmp:
            yield tmp

    monkeypatch.setattr(experiment_workers, "run_scene", run_scene)
    monkeypatch.setattr(experiment_run, "replace_folder", replace_folder)
    path = write(tmp_path / "tiny.toml", TINY)
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.run_id for r in outcome.failed] == [IDS[1]]
    assert "could not be written" in (outcome.failed[0].error or "")
    rows = read_csv(tmp_path / "out" / "results.csv")
    assert [row["status"] for row in rows] == ["done", "failed", "done", "done"]


def test_outputs_outside_the_run_folders_are_refused_before_anything_runs(
    tmp_path: Path,
) -> None:
    text = TINY.replace("count = 150", 'count = 150\n"outputs.packing" = "../x.npz"')
    path = write(tmp_path / "tiny.toml", text)
    with pytest.raises(ConfigError) as info:
        run_experiment(path, tmp_path / "out", workers=1)
    assert str(info.value).startswith(
        f"{path}: set.outputs.packing = \"../x.npz\": contains '/'; an output is a plain "
        "file name inside the run folder"
    )
    assert str(info.value).endswith("(run eta=0,seed=1)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.toml"]


def test_runs_whose_folders_differ_only_in_case_are_refused() -> None:
    data = {"base": "small", "sweep": {"name": ["A", "a"]}}
    with pytest.raises(ConfigError) as info:
        expand(experiment_from_dict(data, source="exp.toml"))
    assert str(info.value) == (
        "exp.toml: runs 0 ('name=A') and 1 ('name=a') would write the same folder on a "
        "case-insensitive file system; make the values differ by more than case"
    )


def test_an_output_named_like_a_file_of_the_sweep_is_refused(tmp_path: Path) -> None:
    text = TINY.replace("count = 150", 'count = 150\n"outputs.summary" = "Scene.json"')
    path = write(tmp_path / "tiny.toml", text)
    with pytest.raises(ConfigError) as info:
        run_experiment(path, tmp_path / "out", workers=1)
    assert str(info.value) == (
        f"{path}: set.outputs.summary: writes Scene.json, the same file as the sweep's "
        "scene.json in every run folder; give it another name (run eta=0,seed=1)"
    )
    assert not (tmp_path / "out").exists()


def test_a_run_folder_regopack_did_not_write_stops_the_sweep_before_it_runs(
    tmp_path: Path,
) -> None:
    path = write(tmp_path / "tiny.toml", TINY)
    (tmp_path / "out" / IDS[1]).mkdir(parents=True)
    (tmp_path / "out" / IDS[1] / "notes.txt").write_text("mine")
    with pytest.raises(ConfigError, match=f"run {IDS[1]}: output folder .*: exists and was not"):
        run_experiment(path, tmp_path / "out", workers=1)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [IDS[1]]


def test_a_failed_run_replaces_the_older_run_in_its_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write(tmp_path / "tiny.toml", TINY.replace('seed = "1..2"', "seed = [1]"))
    run_experiment(path, tmp_path / "out", workers=1)
    folder = tmp_path / "out" / IDS[0]
    assert sorted(p.name for p in folder.iterdir()) == [
        ".regopack",
        "packing.npz",
        "scene.json",
        "summary.json",
    ]

    def broken(*args: Any, **kwargs: Any) -> Any:
        raise RuntimeError("no room")

    monkeypatch.setattr(experiment_workers, "run_scene", broken)
    write(path, path.read_text().replace("count = 150", "count = 120"))
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert [r.status for r in outcome.runs] == ["failed", "failed"]
    assert sorted(p.name for p in folder.iterdir()) == [".regopack", "error.txt", "scene.json"]
    assert json.loads((folder / "scene.json").read_text())["count"] == 120
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "eta=0,seed=1",
        "eta=10,seed=1",
        "experiment.json",
        "results.csv",
    ]


def test_explicit_metrics_follow_dotted_paths(tmp_path: Path) -> None:
    text = TINY.replace(
        'base = "small"\n',
        'base = "small"\nmetrics = ["placed", "analyses.contacts.n_contacts", "nothing.here"]\n',
    ).replace("count = 150\n", 'count = 150\n"outputs.analyses" = ["contacts"]\n')
    text = text.replace('seed = "1..2"', "seed = [1]").replace("[0, 10]", "[0]")
    path = write(tmp_path / "exp.toml", text)
    outcome = run_experiment(path, tmp_path / "out", workers=1)
    assert outcome.metrics == ("placed", "analyses.contacts.n_contacts", "nothing.here")
    [row] = read_csv(tmp_path / "out" / "results.csv")
    assert int(row["analyses.contacts.n_contacts"]) > 0
    assert row["nothing.here"] == ""


@pytest.mark.skipif(
    importlib.util.find_spec("distributed") is None,
    reason="Dask's distributed package is not installed (pip install 'regopack[dask]')",
)
def test_a_sweep_runs_on_a_dask_cluster(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    path = write(tmp_path / "exp.toml", TINY.replace('seed = "1..2"', "seed = [1]"))
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        outcome = run_experiment(path, tmp_path / "out", scheduler=cluster.scheduler_address)
    assert outcome.ok
    assert [r.run_id for r in outcome.runs] == ["eta=0,seed=1", "eta=10,seed=1"]
    assert len(read_csv(tmp_path / "out" / "results.csv")) == 2


def test_a_missing_dask_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)
    path = write(tmp_path / "exp.toml", TINY)
    with pytest.raises(ConfigError, match=r"^--scheduler tcp://h:1: Dask is not installed"):
        run_experiment(path, tmp_path / "out", scheduler="tcp://h:1")
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------
# command line


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="regopack")
    add_sweep_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(argv)


def test_sweep_command_prints_a_table(tiny_sweep: tuple[Path, Any, Any], tmp_path: Path) -> None:
    root, _, _ = tiny_sweep
    args = parse(["sweep", str(root / "tiny.toml"), "--out", str(root / "out"), "--workers", "1"])
    out = Console(record=True, width=120)
    err = Console(record=True, width=120)
    assert args.handler(args, out, err) == 0
    text = out.export_text()
    for run_id in IDS:
        assert run_id in text
    assert "4/4 runs done, 0 failed" in text
    assert "4/4" in err.export_text()


def test_sweep_command_exits_1_when_a_run_fails(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(*args: Any, **kwargs: Any) -> Any:
        raise ConfigError("no room")

    monkeypatch.setattr(experiment_workers, "run_scene", broken)
    path = write(tmp_path / "exp.toml", TINY)
    args = parse(["sweep", str(path), "--out", str(tmp_path / "out"), "--workers", "1", "--quiet"])
    console = Console(record=True, width=120)
    assert run_sweep_command(args, console) == 1
    assert console.export_text() == ""
    assert (tmp_path / "out" / IDS[0] / "error.txt").read_text() == "no room\n"


def test_docstring_examples() -> None:
    import doctest

    for module in (experiment_file, experiment_grid):
        result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
        assert result.attempted > 0
        assert result.failed == 0
