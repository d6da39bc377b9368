from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from cli_helpers import one_error_line
from fakes import fake_registry

import regopack
import regopack.registry.manager
from regopack.cli import main
from regopack.packing.core import save
from regopack.testing import make_registry, packing_from_polygons

BUILTINS = ("regopack.plugins.density.eta",)


@pytest.fixture(autouse=True)
def fake_plugins(monkeypatch, tmp_path):
    """Every command sees the fake plugins and runs in a temporary directory."""
    monkeypatch.setattr(regopack.registry.manager, "default_registry", lambda **kw: fake_registry())
    monkeypatch.chdir(tmp_path)


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"regopack {regopack.__version__}"


def test_no_command_prints_help(capsys):
    assert main([]) == 2
    assert "usage: regopack" in capsys.readouterr().err


def test_unknown_option_is_a_usage_error(capsys):
    assert main(["run", "--bogus"]) == 2


def test_scenes(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    assert "table1" in out
    assert "small" in out


def test_config_prints_resolved_toml(capsys):
    assert main(["config", "small", "--set", "density.eta=5", "--seed", "3"]) == 0
    data = tomllib.loads(capsys.readouterr().out)
    assert data["name"] == "small"
    assert data["seed"] == 3
    assert data["density"] == {"kind": "eta", "eta": 5.0}
    assert data["insertion"]["tau"] == 0.65
    assert len(data["phases"]) == 6


def test_config_default_is_table1(capsys):
    assert main(["config"]) == 0
    assert tomllib.loads(capsys.readouterr().out)["name"] == "table1"


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (
            ["config", "--set", "density.eta=-3"],
            "regopack: error: --set: density.eta = -3: Input should be greater than or equal to 0",
        ),
        (
            ["config", "--set", "phases.0.shape.kind=octagn"],
            "regopack: error: --set: phases.0.shape.kind: "
            "unknown shape kind 'octagn'; did you mean 'octagon'? known kinds: octagon",
        ),
        (["run", "nope.toml"], "regopack: error: nope.toml: no such scene file"),
        (["run", "--set", "oops"], "regopack: error: --set 'oops': expected key=value"),
        (["verify", "missing.npz"], "regopack: error: missing.npz: no such file"),
    ],
)
def test_user_errors_are_one_line(capsys, argv, expected):
    assert main(argv) == 2
    assert one_error_line(capsys).startswith(expected)


def test_bad_scene_file_names_file_and_field(tmp_path, capsys):
    (tmp_path / "scene.toml").write_text(_small_with("eta = 0.0", "eta = -3"))
    assert main(["config", "scene.toml"]) == 2
    assert one_error_line(capsys) == (
        "regopack: error: scene.toml: density.eta = -3: Input should be greater than or equal to 0"
    )


def _small_with(old: str, new: str) -> str:
    from importlib.resources import files

    text = files("regopack.scenes").joinpath("small.toml").read_text(encoding="utf-8")
    return text.replace(old, new, 1)


def test_run_and_verify(tmp_path, capsys):
    assert main(["run", "small", "--set", "count=300", "--out", "out"]) == 0
    out = capsys.readouterr().out
    assert "placed" in out
    assert "out/packing.npz" in out
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["tried"] == 300
    assert main(["verify", "out/packing.npz"]) == 0
    assert "OK" in capsys.readouterr().out


def test_run_default_out_dir_and_quiet(tmp_path, capsys):
    assert main(["run", "small", "--set", "count=50", "--seed", "2", "--quiet"]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    assert (tmp_path / "runs" / "small-seed2" / "packing.npz").exists()
    assert (tmp_path / "runs" / "small-seed2" / "summary.json").exists()


def test_verify_violation_exits_1(tmp_path, capsys):
    sq = [(0, 0), (1, 0), (1, 1), (0, 1)]
    overlapping = packing_from_polygons([sq, [(x + 0.5, y) for x, y in sq]], domain=(0, 2, 0, 1))
    save(overlapping, tmp_path / "bad.npz")
    assert main(["verify", "bad.npz"]) == 1
    assert "VIOLATED" in capsys.readouterr().out


def test_verify_corrupt_file(tmp_path, capsys):
    (tmp_path / "bad.npz").write_bytes(b"garbage")
    assert main(["verify", "bad.npz"]) == 2
    assert "not a regopack packing file" in one_error_line(capsys)


def test_interrupt_exits_130_without_partial_files(tmp_path, capsys):
    assert main(["run", "small", "--set", "count=50", "--out", "out", "--quiet"]) == 0
    before = (tmp_path / "out" / "packing.npz").read_bytes()
    argv = ["run", "small", "--set", "count=50", "--set", "insertion.fail_after=5"]
    assert main([*argv, "--out", "out", "--seed", "7", "--quiet"]) == 130
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("regopack: interrupted")
    assert (tmp_path / "out" / "packing.npz").read_bytes() == before
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == [".regopack", "packing.npz", "summary.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize(
    "override",
    ['outputs.packing="../x.npz"', "outputs.packing=/tmp/regopack-x.npz", 'name="../../X"'],
)
def test_nothing_is_written_outside_the_output_folder(tmp_path, capsys, override):
    (tmp_path / "work").mkdir()
    argv = ["run", "small", "--set", "count=20", "--set", override, "--quiet"]
    for more in (["--out", "work/out"], []):
        assert main([*argv, *more]) == 2
        line = one_error_line(capsys)
        assert line.startswith("regopack: error: --set: ") and "contains '/'" in line
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["work"]
    assert not Path("/tmp/regopack-x.npz").exists()


def test_two_outputs_of_one_run_are_refused_before_anything_is_written(tmp_path, capsys):
    argv = ["run", "small", "--set", "count=20", "--set", "outputs.summary=packing.npz"]
    assert main([*argv, "--out", "out", "--quiet"]) == 2
    assert one_error_line(capsys) == (
        'regopack: error: --set: outputs.summary = "packing.npz": the same path as '
        'outputs.packing ("packing.npz"); every output of a run needs its own name'
    )
    assert list(tmp_path.iterdir()) == []


def test_running_twice_into_the_default_folder_replaces_the_run(tmp_path, capsys):
    for seed in ("1", "2"):
        assert main(["run", "small", "--set", "count=20", "--seed", seed, "--out", "o"]) == 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["seed"] == 2
    for _ in range(2):  # the README's quick start, run again
        assert main(["run", "small", "--set", "count=20", "--quiet"]) == 0
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == ["small-seed1"]


def test_an_output_folder_holding_the_scene_file_is_refused(tmp_path, capsys):
    assert main(["config", "small", "--set", "count=20"]) == 0
    scene = capsys.readouterr().out
    assert main(["run", "small", "--set", "count=20", "--out", "o", "--quiet"]) == 0
    (tmp_path / "o" / "mine.toml").write_text(scene)
    assert main(["run", "o/mine.toml", "--out", "o", "--quiet"]) == 2
    assert "holds the scene file o/mine.toml" in one_error_line(capsys)
    assert (tmp_path / "o" / "mine.toml").read_text() == scene


def test_a_folder_not_written_by_regopack_is_refused(tmp_path, capsys):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "notes.txt").write_text("mine")
    assert main(["run", "small", "--set", "count=20", "--out", "data", "--quiet"]) == 2
    assert one_error_line(capsys) == (
        "regopack: error: output folder data: exists and was not written by regopack "
        "(it has no .regopack file); the run replaces its whole output folder, so give a "
        "new or empty folder, or remove this one"
    )
    assert (tmp_path / "data" / "notes.txt").read_text() == "mine"


def test_unexpected_errors_keep_their_traceback(monkeypatch):
    def broken(**kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(regopack.registry.manager, "default_registry", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["config"])


def test_python_dash_m(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "regopack", "--version"], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0
    assert result.stdout.strip() == f"regopack {regopack.__version__}"


def test_import_is_light():
    code = "import sys, regopack; print('numba' in sys.modules, 'shapely' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.split() == ["False", "False"]


# ---------------------------------------------------------------------------
# regopack plugins


def test_plugins_lists_every_plugin_with_origin_and_fields(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    for name in ("change5", "octagon", "available-arc", "eta"):
        assert name in out
    assert "fakes" in out  # the module of the fake plugins
    assert "d_min" in out and "smallest diameter" in out  # a field and its description
    assert "number, > 0" in out  # its type with the bound
    assert "required" not in out  # every fake field has a default


def test_plugins_json(capsys):
    assert main(["plugins", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["regopack"] == regopack.__version__
    entries = {(e["kind"], e["name"]): e for e in data["plugins"]}
    assert set(entries) == {
        ("size", "change5"),
        ("shape", "octagon"),
        ("insertion", "available-arc"),
        ("density", "eta"),
    }
    size = entries["size", "change5"]
    assert size["module"] == "fakes"
    assert size["distribution"] is None and size["version"] is None
    assert size["description"] == "fake sizes"
    assert [f["name"] for f in size["fields"]] == ["d_min", "d_max", "d0", "alpha"]
    assert size["fields"][0] == {
        "name": "d_min",
        "type": "number, > 0",
        "required": False,
        "default": 2.0,
        "description": "smallest diameter",
        "schema": {
            "default": 2.0,
            "description": "smallest diameter",
            "exclusiveMinimum": 0.0,
            "title": "D Min",
            "type": "number",
        },
    }


def test_plugins_kind_filter(capsys):
    assert main(["plugins", "--kind", "shape", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [(e["kind"], e["name"]) for e in data["plugins"]] == [("shape", "octagon")]
    assert main(["plugins", "--kind", "analysis"]) == 0
    assert "(none)" in capsys.readouterr().out


def test_plugins_unknown_kind_is_a_usage_error(capsys):
    assert main(["plugins", "--kind", "colour"]) == 2
    assert "invalid choice: 'colour'" in one_error_line(capsys)


def test_plugins_shows_the_distribution_of_builtin_plugins(capsys, monkeypatch):
    monkeypatch.setattr(
        regopack.registry.manager, "default_registry", lambda **kw: make_registry(builtins=BUILTINS)
    )
    assert main(["plugins", "--kind", "density", "--json"]) == 0
    [entry] = json.loads(capsys.readouterr().out)["plugins"]
    assert (entry["module"], entry["distribution"], entry["version"]) == (
        "regopack.plugins.density.eta",
        "regopack",
        regopack.__version__,
    )
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["plugins", "--kind", "density"]) == 0
    assert f"regopack {regopack.__version__}" in capsys.readouterr().out


# ---------------------------------------------------------------------------
# regopack schema


def test_schema_prints_json_schema(capsys):
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["title"] == "regopack scene"
    assert schema["properties"]["density"]["properties"]["kind"]["enum"] == ["eta"]


def test_schema_output_file(tmp_path, capsys):
    target = tmp_path / "scene.schema.json"
    assert main(["schema", "--output", str(target)]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    assert str(target) in captured.err
    assert json.loads(target.read_text())["title"] == "regopack scene"


def test_schema_output_error_is_one_line(tmp_path, capsys):
    target = tmp_path / "missing" / "scene.schema.json"
    assert main(["schema", "--output", str(target)]) == 2
    line = one_error_line(capsys)
    assert f"cannot write the schema to {target}: No such file or directory" in line


def test_first_run_notice_depends_on_the_kernel_cache(tmp_path, monkeypatch):
    from regopack.api.functions import kernels_cached

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not kernels_cached()
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "kernel.f-1.py311.nbi").write_bytes(b"")
    assert kernels_cached()
