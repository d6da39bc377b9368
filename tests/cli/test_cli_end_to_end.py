"""End-to-end checks with the built-in plugins (skipped while they are missing)."""

from __future__ import annotations

import json
import tomllib

import pytest

import regopack

pytest.importorskip("regopack.plugins.inserters.available_arc")

from regopack.cli import main
from regopack.packing.core import load
from regopack.registry.manager import default_registry
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import assert_valid_packing


def test_default_registry_has_the_builtins():
    reg = default_registry(autoload=False)
    assert reg.names("size") == [
        "change5",
        "lognormal",
        "monodisperse",
        "rosin-rammler",
        "tabulated",
        "uniform",
    ]
    assert reg.names("shape") == [
        "disk",
        "octagon",
        "polyhedron",
        "random-polygon",
        "regular",
        "sphere",
        "template",
        "template-3d",
    ]
    assert reg.names("insertion") == ["available-arc", "available-surface", "rsa"]
    assert reg.names("density") == ["eta", "target"]
    assert reg.names("export") == [
        "csv",
        "gsd",
        "image",
        "json",
        "lammps",
        "liggghts",
        "slice",
        "stl",
        "svg",
        "vtk",
        "yade",
    ]
    assert reg.aliases("export") == {"gsd3d": "gsd", "lammps3d": "lammps", "vtk3d": "vtk"}
    assert reg.origin("shape", "octagon") == "regopack.plugins.shapes.octagon"
    assert default_registry(autoload=False) is not reg


def test_builtin_scenes_resolve():
    reg = default_registry(autoload=False)
    for name in ("table1", "small", "dem", "table1-3d", "dem3d"):
        resolve_scene(load_scene(name), reg)


def test_config_prints_the_default_scene(capsys):
    assert main(["config"]) == 0
    data = tomllib.loads(capsys.readouterr().out)
    expected = resolve_scene(load_scene(None), default_registry()).to_dict()
    assert data == expected


def test_run_small_end_to_end(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "small", "--set", "count=300", "--out", str(out), "--quiet"]) == 0
    packing = load(out / "packing.npz")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tried"] == 300
    assert summary["placed"] == packing.n_placed > 0
    assert_valid_packing(packing)
    assert main(["verify", str(out / "packing.npz")]) == 0


def test_run_table1_3d_end_to_end_in_a_smaller_box(tmp_path, capsys):
    out = tmp_path / "out"
    sides = [f"domain.{k}=30" for k in ("width", "height", "depth")]
    args = ["run", "table1-3d", *[a for s in sides for a in ("--set", s)], "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "φ domain" in printed and "OK" in printed
    packing = regopack.load(out / "packing.npz")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["dimension"] == 3 and summary["verify"]["ok"]
    assert summary["placed"] == packing.n_placed > 30
    assert summary["phi_domain"] == pytest.approx(packing.phi)
    assert main(["verify", str(out / "packing.npz")]) == 0


def test_run_dem3d_end_to_end_in_a_smaller_box(tmp_path, capsys):
    """The 3D DEM scene packs by the sweep, verified, and its layers are measured."""
    out = tmp_path / "out"
    sides = [f"domain.{k}=24" for k in ("width", "height", "depth")] + ["size.d_max=6"]
    args = ["run", "dem3d", *[a for s in sides for a in ("--set", s)], "--out", str(out)]
    assert main([*args, "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["dimension"] == 3 and summary["verify"]["ok"]
    assert summary["zone_raises"] > 0  # the sweep's zone rose from the floor
    packing = regopack.load(out / "packing.npz")
    assert packing.scene["insertion"]["order"] == "sweep"
    res = regopack.analyze(packing, ["homogeneity"])["homogeneity"]
    assert res["layers"] == 6 and res["layer_phi_max_rel_dev"] is not None


def _arrays(packing):
    return (
        packing.centre,
        packing.insertion_index,
        packing.vertices,
        packing.radius,
        packing.mineral,
    )


@pytest.mark.parametrize(
    ("scene", "overrides"),
    [
        ("small", ["count=500", "seed=3"]),
        ("small", ["count=500", "seed=4", "density.eta=10"]),
        ("table1", ["domain.width=120", "domain.height=80", "seed=5", "insertion.t=1"]),
    ],
)
def test_linear_scan_reference_gives_the_same_packing(scene, overrides, tmp_path):
    reg = default_registry(autoload=False)
    from regopack.run.pipeline import run_scene

    packings = []
    for search in ("linear", "indexed"):
        resolved = resolve_scene(load_scene(scene, [*overrides, f"insertion.search={search}"]), reg)
        packings.append(run_scene(resolved, None).packing)
    for a, b in zip(_arrays(packings[0]), _arrays(packings[1]), strict=True):
        assert a.tobytes() == b.tobytes()


def test_same_scene_and_seed_give_identical_files(tmp_path):
    for name in ("a", "b"):
        assert (
            main(
                [
                    "run",
                    "small",
                    "--set",
                    "count=400",
                    "--seed",
                    "9",
                    "--out",
                    str(tmp_path / name),
                    "--quiet",
                ]
            )
            == 0
        )
    a = load(tmp_path / "a" / "packing.npz")
    b = load(tmp_path / "b" / "packing.npz")
    for x, y in zip(_arrays(a), _arrays(b), strict=True):
        assert x.tobytes() == y.tobytes()


def test_mineral_frequencies_follow_the_fractions():
    import numpy as np
    from scipy import stats

    from regopack.run.pipeline import draw_population

    resolved = resolve_scene(load_scene("table1"), default_registry(autoload=False))
    pop = draw_population(resolved, np.random.default_rng(0))
    counts = np.bincount(pop.mineral, minlength=len(resolved.phase_names))
    expected = np.asarray(resolved.fractions) * len(pop)
    assert len(pop) == 16579
    assert stats.chisquare(counts, expected).pvalue > 1e-3
    # and the test can fail: a skewed draw is detected
    skewed = counts.copy()
    skewed[0] += 300
    skewed[1] -= 300
    assert stats.chisquare(skewed, expected).pvalue < 1e-3
    # minerals are independent of size
    big = pop.radius > np.median(pop.radius)
    table = np.array(
        [np.bincount(pop.mineral[big], minlength=6), np.bincount(pop.mineral[~big], minlength=6)]
    )
    assert stats.chi2_contingency(table).pvalue > 1e-3


def test_user_mistakes_are_one_line_errors(capsys):
    assert main(["run", "--set", "density.eta=-3"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "density.eta" in err and "-3" in err
    assert main(["run", "--set", "phases.0.shape.kind=octagn"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "octagon" in err
    assert main(["run", "--set", "insertion.interference=fast"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "interference" in err and "exact" in err


def test_scene_analyses_take_parameters(tmp_path):
    scene = tmp_path / "sc.toml"
    scene.write_text(
        'name = "sc"\ncount = 200\n[domain]\nwidth = 90.0\nheight = 90.0\n'
        '[size]\nkind = "change5"\n[[phases]]\nname = "glass"\nfraction = 1.0\n'
        'shape = { kind = "octagon", psi = 1.0 }\n[insertion]\nkind = "available-arc"\n'
        '[density]\nkind = "eta"\n'
        '[outputs]\nanalyses = ["density", { kind = "contacts", tol = 0.1 }, "coordination"]\n'
    )
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["analyses"]["contacts"]["tol"] == 0.1
    assert summary["analyses"]["coordination"]["tol"] == 0.1
    resolved = resolve_scene(load_scene(str(scene)), default_registry(autoload=False))
    assert resolved.to_dict()["outputs"]["analyses"][1]["tol"] == 0.1
