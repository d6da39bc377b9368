"""``regopack analyze`` with the built-in analyzers."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("regopack.plugins.inserters.available_arc")

from cli_helpers import one_error_line

from regopack.cli import main
from regopack.packing.core import save
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene


@pytest.fixture(scope="module")
def packing_file(tmp_path_factory):
    scene = resolve_scene(load_scene("small", ["count=300"]), default_registry(autoload=False))
    path = tmp_path_factory.mktemp("run") / "packing.npz"
    save(run_scene(scene).packing, path)
    return path


def test_default_analyses_without_figures(packing_file, capsys):
    assert main(["analyze", str(packing_file), "--no-figures"]) == 0
    out = capsys.readouterr().out
    for label in ("φ domain", "φ interior", "contacts", "Z domain", "Z interior", "Z pyroxene"):
        assert label in out
    assert "first g(r) peak" in out
    out_dir = packing_file.parent / "analysis"  # the default: beside the packing
    assert "analysis.json" in out and "report.md" in out
    data = json.loads((out_dir / "analysis.json").read_text(encoding="utf-8"))
    assert data["analyses"] == ["density", "contacts", "coordination", "rdf", "network"]
    assert (data["tol"], data["eta"], data["interior_margin"]) == (0.05, 0.0, 40.0)
    assert data["packing"] == str(packing_file)
    for table in ("contacts", "particles", "z_tol", "rdf_near", "rdf_far", "network"):
        assert (out_dir / f"{table}.csv").exists()
    assert not (out_dir / "figures").exists()


def test_only_tol_set_out_and_npz(packing_file, tmp_path, capsys):
    argv = [
        "analyze",
        str(packing_file),
        "--only",
        "coordination",
        "--tol",
        "0.1",
        "--set",
        "contacts.tol_max=0.3",
        "--set",
        "coordination.tols=[0.1, 0.2, 0.3]",
        "--out",
        str(tmp_path / "a"),
        "--tables",
        "npz",
        "--no-figures",
    ]
    assert main(argv) == 0
    data = json.loads((tmp_path / "a" / "analysis.json").read_text(encoding="utf-8"))
    assert data["analyses"] == ["contacts", "coordination"]
    assert data["contacts"]["tol"] == 0.1
    assert data["contacts"]["tol_max"] == 0.3
    assert data["coordination"]["tol_sweep"] == [0.1, 0.2, 0.3]
    with np.load(tmp_path / "a" / "z_tol.npz") as npz:
        assert np.allclose(npz["tol"], [0.1, 0.2, 0.3])


def test_rdf_only_with_figures(packing_file, tmp_path, capsys):
    assert main(["analyze", str(packing_file), "--only", "rdf", "--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == ["rdf.png", "rdf.svg"]
    assert "figures" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        ([], "analyze: the following arguments are required: PACKING"),
        (["missing.npz"], "missing.npz: no such file"),
        (["{p}", "--only", "rdff"], "unknown analyzer 'rdff'; known analyzers: contacts, "),
        (["{p}", "--only", "rdf,"], "--only 'rdf,': empty analyzer name"),
        (["{p}", "--tol", "-1"], "--set: contacts.tol = -1.0: Input should be greater than 0"),
        (["{p}", "--tol", "abc"], "analyze: argument --tol: invalid float value: 'abc'"),
        (
            ["{p}", "--tol", "1", "--set", "contacts.tol_max=0.5"],
            "--set: contacts: tol_max (0.5) must be at least tol (1.0)",
        ),
        (["{p}", "--set", "tol=1"], "--set 'tol=1': expected NAME.FIELD=VALUE"),
        (
            ["{p}", "--set", "contacts.bogus=1"],
            "--set: contacts.bogus = 1: unknown field; allowed: tol, tol_max, margin",
        ),
        (["{p}", "--set", "nope.x=1"], "unknown analyzer 'nope'"),
        (["{p}", "--only", "rdf", "--tol", "0.1"], "parameters given for analyzer 'contacts'"),
        (["{p}", "--tables", "xls"], "analyze: argument --tables: invalid choice: 'xls'"),
        (
            ["{p}", "--set", "contacts.tol_max=0.2", "--set", "coordination.tols=[0.3]"],
            "coordination.tols: 0.3 exceeds contacts.tol_max = 0.2",
        ),
    ],
)
def test_user_mistakes_are_one_line(packing_file, tmp_path, capsys, args, expected):
    argv = ["analyze", *(a.replace("{p}", str(packing_file)) for a in args)]
    assert main([*argv, "--out", str(tmp_path), "--no-figures"]) == 2
    assert one_error_line(capsys).startswith(f"regopack: error: {expected}")


def test_a_directory_is_not_a_packing(tmp_path, capsys):
    assert main(["analyze", str(tmp_path)]) == 2
    assert "is a directory" in one_error_line(capsys)


def test_a_second_analysis_replaces_the_first(packing_file, tmp_path, capsys):
    out = tmp_path / "a"
    assert main(["analyze", str(packing_file), "--only", "rdf", "--out", str(out)]) == 0
    assert (out / "figures" / "rdf.png").is_file() and (out / "rdf_near.csv").is_file()
    argv = ["analyze", str(packing_file), "--only", "density", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == [".regopack", "analysis.json", "report.md"]
    assert json.loads((out / "analysis.json").read_text())["analyses"] == ["density"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a"]


def test_analyze_never_replaces_a_folder_it_did_not_write(packing_file, tmp_path, capsys):
    argv = ["analyze", str(packing_file), "--only", "density", "--no-figures", "--out"]
    assert main([*argv, str(packing_file.parent)]) == 2
    assert "holds the packing file" in one_error_line(capsys)
    (tmp_path / "notes.txt").write_text("mine")
    assert main([*argv, str(tmp_path)]) == 2
    assert "exists and was not written by regopack" in one_error_line(capsys)
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]
