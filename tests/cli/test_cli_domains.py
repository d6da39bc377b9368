"""Scenes in every domain kind from the command line: run, verify, analyse, export, errors."""

from __future__ import annotations

import json
import re
from importlib.resources import files

import pytest
from cli_helpers import one_error_line

from regopack.cli import main

SMALL = files("regopack.scenes").joinpath("small.toml").read_text(encoding="utf-8")


def _scene(domain: str) -> str:
    """The built-in small scene with its [domain] table replaced."""
    text = re.sub(r"\[domain\].*?(?=\n\[size\])", domain.strip() + "\n", SMALL, count=1, flags=re.S)
    assert "[domain]" in text
    return text


CIRCLE = '[domain]\nkind = "circle"\nradius = 90.0\ncenter = [5.0, -5.0]'
POLYGON = '[domain]\nkind = "polygon"\nvertices = [[-100, -80], [90, -100], [120, 60], [0, 110]]'
PERIODIC = '[domain]\nkind = "periodic"\nwidth = 150.0\nheight = 120.0'


@pytest.mark.parametrize(
    "domain", [CIRCLE, POLYGON, PERIODIC], ids=["circle", "polygon", "periodic"]
)
def test_run_verify_analyze_export(tmp_path, capsys, monkeypatch, domain):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scene.toml").write_text(_scene(domain))
    assert main(["run", "scene.toml", "--out", "out", "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["placed"] > 0.9 * summary["tried"]
    assert 0.7 < summary["phi_domain"] < 0.95
    assert main(["verify", "out/packing.npz"]) == 0
    assert "OK" in capsys.readouterr().out
    assert main(["analyze", "out/packing.npz", "--no-figures"]) == 0
    results = json.loads((tmp_path / "out" / "analysis" / "analysis.json").read_text())
    assert results["coordination"]["z_interior"] > 2.0
    g = results["rdf"]
    assert g["first_peak_fit_range"] is not None  # a top, a distinct peak or a plateau
    assert main(["export", "out/packing.npz", "--to", "svg"]) == 0
    svg = (tmp_path / "out" / "packing.svg").read_text()
    tag = {"circle": "<circle", "polygon": "<polygon class", "periodic": "<rect"}
    kind = re.search(r'kind = "(\w+)"', domain).group(1)  # type: ignore[union-attr]
    assert f'{tag[kind]} class="domain"' in svg or f'{tag[kind]}="domain"' in svg


@pytest.mark.parametrize(
    ("domain", "expected"),
    [
        (
            '[domain]\nkind = "circle"\nradius = 50.0\nwidth = 3.0',
            "regopack: error: scene.toml: domain: width does not apply to kind 'circle', "
            "which takes radius, center",
        ),
        (
            '[domain]\nkind = "circle"',
            "regopack: error: scene.toml: domain: kind 'circle' needs radius",
        ),
        (
            '[domain]\nkind = "polygon"\nvertices = [[0, 0], [10, 0], [0, 10], [10, 10]]',
            "regopack: error: scene.toml: domain: vertices: the corners must form a strictly "
            "convex polygon",
        ),
        (
            '[domain]\nkind = "circle"\nradius = -2.0',
            "regopack: error: scene.toml: domain.radius = -2.0: Input should be greater than 0",
        ),
        (
            '[domain]\nkind = "periodic"\nwidth = 40.0\nheight = 40.0',
            "regopack: error: scene.toml: domain.width = 40.0: a periodic domain must be wider "
            "and higher than 4 x the largest particle circumradius",
        ),
    ],
    ids=["foreign-field", "missing-radius", "not-convex", "negative-radius", "periodic-too-small"],
)
def test_domain_mistakes_are_one_line(tmp_path, capsys, monkeypatch, domain, expected):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scene.toml").write_text(_scene(domain).replace('count = "auto"', "count = 500"))
    assert main(["run", "scene.toml", "--out", "out", "--quiet"]) == 2
    assert one_error_line(capsys).startswith(expected)


def test_disks_from_the_command_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    disks = ["--set", 'phases.0.shape={kind = "disk"}', "--set", 'phases.2.shape={kind = "disk"}']
    assert main(["run", "small", *disks, "--out", "out", "--quiet"]) == 0
    assert main(["verify", "out/packing.npz"]) == 0
    assert "OK" in capsys.readouterr().out
    assert main(["analyze", "out/packing.npz", "--no-figures"]) == 0
    results = json.loads((tmp_path / "out" / "analysis" / "analysis.json").read_text())
    assert results["contacts"]["n_contacts"] > 0
    for fmt in ("csv", "json", "svg", "vtk", "lammps", "gsd"):
        assert main(["export", "out/packing.npz", "--to", fmt]) == 0
