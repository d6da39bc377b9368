"""The Python API (regopack.scene, pack, analyze, verify, export, sweep) against the commands."""

from __future__ import annotations

import json

import numpy as np
import pytest

import regopack
from regopack.base.errors import ConfigError, RegopackError
from regopack.cli import main
from regopack.scenes.model import ResolvedScene, load_scene, resolve_scene
from regopack.testing import packing_from_polygons

TINY = {"domain__width": 60, "domain__height": 60, "count": 40}


def _same_arrays(a: regopack.Packing, b: regopack.Packing) -> None:
    for name in ("radius", "mineral", "vertices", "offsets", "orientation", "insertion_index"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(a.centre, b.centre)  # NaN where not placed, in both


# -- scene ---------------------------------------------------------------------------


def test_scene_overrides_by_double_underscore_and_by_dotted_name():
    s = regopack.scene("small", domain__width=120, **{"density.eta": 5}, seed=9)
    assert isinstance(s, ResolvedScene)
    assert s.scene.domain.width == 120.0
    assert s.density.config.eta == 5.0
    assert s.seed == 9
    cli = resolve_scene(
        load_scene("small", ["domain.width=120", "density.eta=5"], seed=9), s.registry
    )
    assert s.to_dict() == cli.to_dict()


def test_scene_from_a_file_a_dict_and_a_scene(tmp_path):
    text = regopack.scene("small").to_toml()
    path = tmp_path / "mine.toml"
    path.write_text(text)
    from_file = regopack.scene(path)
    from_str = regopack.scene(str(path))
    from_dict = regopack.scene(regopack.scene("small").to_dict())
    again = regopack.scene(from_dict)
    assert from_file.to_dict() == from_str.to_dict() == from_dict.to_dict() == again.to_dict()
    assert regopack.scene().name == "table1"


def test_with_changes_a_copy():
    base = regopack.scene("small")
    changed = base.with_(phases__0__shape__psi=3.0, count=50)
    assert changed.phases[0].shape.config.psi == 3.0
    assert changed.scene.count == 50
    assert base.phases[0].shape.config.psi == 0.25
    assert base.scene.count == "auto"


def test_scene_repr_is_one_line():
    text = repr(regopack.scene("small"))
    assert "\n" not in text
    assert "'small'" in text and "200 × 200 µm rectangle" in text


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"domain__width": -3}, "scene(domain__width=...): domain.width = -3"),
        ({"count": "many"}, 'scene(count=...): count = "many"'),
        ({"phases__9__name": "x"}, "scene(phases__9__name=...): phases.9 is not an item"),
        ({"density__eta": "x"}, "scene(density__eta=...)"),
    ],
)
def test_scene_errors_name_the_keyword(kwargs, expected):
    with pytest.raises(ConfigError) as err:
        regopack.scene("small", **kwargs)
    assert expected in str(err.value)
    assert "\n" not in str(err.value)


def test_scene_refuses_other_types():
    with pytest.raises(ConfigError, match="not int"):
        regopack.scene(3)  # type: ignore[arg-type]


def test_scene_errors_in_a_file_name_the_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(regopack.scene("small").to_toml().replace("width = 200.0", "width = -1.0"))
    with pytest.raises(ConfigError, match=r"bad\.toml: domain\.width = -1"):
        regopack.scene(path)


# -- pack ----------------------------------------------------------------------------


def test_pack_is_the_packing_of_regopack_run(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "small", "--quiet", "--out", str(out), "--set", "count=60"]) == 0
    from_cli = regopack.load(out / "packing.npz")
    from_api = regopack.pack("small", count=60)
    _same_arrays(from_cli, from_api)
    assert from_api.seed == from_cli.seed == 1


def test_pack_same_seed_same_packing_other_seed_other():
    a = regopack.pack("small", seed=3, **TINY)
    b = regopack.pack(regopack.scene("small", **TINY), seed=3)
    c = regopack.pack("small", seed=4, **TINY)
    _same_arrays(a, b)
    assert not np.array_equal(a.radius, c.radius)


def test_pack_writes_only_with_out(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    regopack.pack("small", **TINY)
    assert list(tmp_path.iterdir()) == []
    outcome = regopack.pack_and_summarise("small", out=tmp_path / "r", **TINY)
    assert outcome.packing_path == tmp_path / "r" / "packing.npz"
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["placed"] == outcome.packing.n_placed == outcome.summary["placed"]


def test_pack_calls_a_progress_callable():
    calls: list[tuple[int, int, int]] = []
    p = regopack.pack("small", progress=lambda *a: calls.append(a), **TINY)
    assert calls
    done, placed, total = calls[-1]
    assert total == p.n_particles and placed <= done <= total


def test_pack_refuses_a_bad_progress_and_an_occupied_folder(tmp_path):
    with pytest.raises(ConfigError, match="progress"):
        regopack.pack("small", progress="yes", **TINY)  # type: ignore[arg-type]
    (tmp_path / "mine.txt").write_text("keep me")
    with pytest.raises(ConfigError):
        regopack.pack("small", out=tmp_path, **TINY)
    assert (tmp_path / "mine.txt").read_text() == "keep me"


def test_pack_refuses_to_replace_the_folder_of_its_scene_file(tmp_path):
    regopack.pack("small", out=tmp_path / "run", **TINY)
    scene_file = tmp_path / "run" / "mine.toml"
    scene_file.write_text(regopack.scene("small", **TINY).to_toml())
    with pytest.raises(ConfigError, match="holds the scene file"):
        regopack.pack(scene_file, out=tmp_path / "run")
    assert scene_file.is_file()


@pytest.mark.parametrize("out", ["", " ", 5])
def test_blank_or_wrong_output_paths_are_refused(tmp_path, monkeypatch, tiny, out):
    monkeypatch.chdir(tmp_path)
    regopack.save(tiny, tmp_path / "p.npz")
    exp = tmp_path / "exp.toml"
    exp.write_text('name = "x"\nbase = "small"\n[sweep]\nseed = [1]\n')
    calls = [
        lambda: regopack.pack("small", out=out, **TINY),
        lambda: regopack.analyze(tiny, "density", out=out),
        lambda: regopack.export(tiny, "csv", out),
        lambda: regopack.sweep(exp, out=out, workers=1),
    ]
    for call in calls:
        with pytest.raises(ConfigError, match=r"empty path|expected a path"):
            call()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exp.toml", "p.npz"]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda p: regopack.analyze(5), "packing: expected a Packing"),
        (lambda p: regopack.analyze(p, 5), "only: expected an analyzer name"),
        (lambda p: regopack.analyze(p, [1]), "only: expected analyzer names"),
        (lambda p: regopack.analyze(p, []), "only: no analyzer named"),
        (lambda p: regopack.analyze(p, params=5), "params: expected a dictionary"),
        (lambda p: regopack.analyze(p, "density", figures="no"), "figures: expected True"),
        (lambda p: regopack.analyze(p, "density", tables="xls"), "tables"),
        (lambda p: regopack.analyze(p, "density", registry=5), "registry: expected"),
        (lambda p: regopack.analyze(p, __x=1), "empty part"),
        (lambda p: regopack.verify(p, rel_tol="x"), "rel_tol"),
        (lambda p: regopack.export(p, 5, "x.csv"), "to: expected the name"),
        (lambda p: regopack.export(p, "csv", "x.csv", params=5), "params: expected"),
        (lambda p: regopack.export(p, "csv", "x.csv", analyses=5), "analyses: expected"),
        (lambda p: regopack.sweep(5), "experiment: expected"),
        (lambda p: regopack.sweep("x.toml", workers="2"), "workers"),
        (lambda p: regopack.sweep("x.toml", workers=1.5), "workers"),
        (lambda p: regopack.sweep("x.toml", scheduler=5), "scheduler"),
        (lambda p: regopack.scene("small", registry=5), "registry: expected"),
        (lambda p: regopack.scene("small", domain____width=5), "empty part"),
        (lambda p: regopack.scene("small", a__=5), "empty part"),
        (lambda p: regopack.pack("small", verify="no"), "verify: expected"),
    ],
)
def test_wrong_types_are_one_line_errors(tiny, tmp_path, monkeypatch, call, match):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=match) as err:
        call(tiny)
    assert "\n" not in str(err.value)
    assert list(tmp_path.iterdir()) == []


def test_numpy_scalars_count_as_numbers():
    s = regopack.scene("small", count=np.int64(50), seed=np.int64(2), density__eta=np.float64(5))
    assert (s.scene.count, s.seed, s.density.config.eta) == (50, 2, 5.0)


# -- analyze -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny():
    return regopack.pack("small", **TINY)


def test_analyze_scalars_and_tables(tiny):
    res = regopack.analyze(tiny, ["density", "coordination"], density={"margin": 0.0})
    assert list(res) == ["density", "contacts", "coordination"]
    assert res["density"]["phi_domain"] == pytest.approx(tiny.phi)
    table = res["coordination"].tables["z_tol"]
    assert isinstance(table, np.ndarray) and table.dtype.names == ("tol", "z_domain", "z_interior")
    particles = res["coordination"].tables["particles"]
    assert len(particles) == tiny.n_placed
    assert res.files is None
    with pytest.raises(KeyError, match="no analysis 'rdf'"):
        res["rdf"]
    with pytest.raises(KeyError, match="has no scalar"):
        res["density"]["nope"]


def test_analyze_takes_names_as_text_and_params_as_keywords(tiny):
    a = regopack.analyze(tiny, "coordination", contacts__tol=0.5)
    b = regopack.analyze(tiny, ["coordination"], params={"contacts": {"tol": 0.5}})
    c = regopack.analyze(tiny, "density,coordination", contacts={"tol": 0.5})
    assert list(a) == ["contacts", "coordination"]
    same = {json.dumps(r["coordination"].scalars, sort_keys=True) for r in (a, b, c)}
    assert len(same) == 1
    assert a["contacts"]["tol"] == 0.5


def test_analyze_defaults_are_those_of_the_command(tiny):
    from regopack.analysis.pipeline import DEFAULT_ANALYSES

    res = regopack.analyze(tiny)
    assert set(DEFAULT_ANALYSES) <= set(res)


def test_analyze_errors_are_one_line(tiny):
    with pytest.raises(ConfigError, match="unknown analyzer 'nope'"):
        regopack.analyze(tiny, "nope")
    with pytest.raises(ConfigError, match=r"contacts\.tol = -1"):
        regopack.analyze(tiny, "contacts", contacts__tol=-1)
    with pytest.raises(ConfigError, match="rdf"):
        regopack.analyze(tiny, "density", rdf__dr=1.0)
    with pytest.raises(ConfigError, match="expected a dictionary"):
        regopack.analyze(tiny, "contacts", contacts=0.1)


def test_analyze_writes_like_the_command(tmp_path, tiny):
    regopack.save(tiny, tmp_path / "p.npz")
    res = regopack.analyze(tmp_path / "p.npz", "density", out=tmp_path / "a", figures=False)
    assert res.files is not None and res.files.results.is_file()
    assert (
        main(
            [
                "analyze",
                str(tmp_path / "p.npz"),
                "--only",
                "density",
                "--no-figures",
                "--out",
                str(tmp_path / "b"),
            ]
        )
        == 0
    )
    api = json.loads((tmp_path / "a" / "analysis.json").read_text())
    cli = json.loads((tmp_path / "b" / "analysis.json").read_text())
    assert api["density"] == cli["density"]


def test_analyze_refuses_to_replace_the_folder_of_its_packing(tmp_path, tiny):
    regopack.save(tiny, tmp_path / "p.npz")
    with pytest.raises(ConfigError, match="holds the packing file"):
        regopack.analyze(tmp_path / "p.npz", "density", out=tmp_path)
    assert (tmp_path / "p.npz").is_file()


def test_to_pandas(tiny):
    pd = pytest.importorskip("pandas")
    res = regopack.analyze(tiny, "contacts")
    frame = res["contacts"].to_pandas()
    assert isinstance(frame, pd.DataFrame) and len(frame) == len(res["contacts"].tables["contacts"])


# -- verify and export --------------------------------------------------------------


def test_verify_is_bool_like_with_the_worst_case(tiny):
    assert regopack.verify(tiny)
    squares = [[(0, 0), (2, 0), (2, 2), (0, 2)], [(1, 1), (3, 1), (3, 3), (1, 3)]]
    bad = packing_from_polygons(squares, domain=(0, 4, 0, 4))
    report = regopack.verify(bad)
    assert not report
    i, j, frac = report.worst_overlap
    assert (i, j) == (0, 1) and frac == pytest.approx(0.25)


def test_export_needs_a_path_for_a_packing_object(tmp_path, tiny):
    with pytest.raises(ConfigError, match="give the path"):
        regopack.export(tiny, "csv")
    written = regopack.export(tiny, "csv", tmp_path / "p.csv")
    assert written == tmp_path / "p.csv" and written.is_file()
    regopack.save(tiny, tmp_path / "p.npz")
    beside = regopack.export(tmp_path / "p.npz", "vtk", analyses=["coordination"])
    assert beside == tmp_path / "p.vtp" and beside.is_file()
    into_folder = regopack.export(tmp_path / "p.npz", "json", tmp_path)
    assert into_folder == tmp_path / "p.json"


def test_export_parameters_are_one_line_errors_naming_the_exporter(tmp_path, tiny):
    with pytest.raises(RegopackError) as err:
        regopack.export(tiny, "lammps", tmp_path / "p.data", stiffnes=1.0)
    assert "lammps" in str(err.value) and "stiffnes" in str(err.value)
    assert "\n" not in str(err.value)
    assert list(tmp_path.iterdir()) == []


def test_export_never_overwrites_its_packing_file(tmp_path, tiny):
    regopack.save(tiny, tmp_path / "p.npz")
    with pytest.raises(ConfigError, match="is the packing file itself"):
        regopack.export(tmp_path / "p.npz", "json", tmp_path / "p.npz")
    assert regopack.load(tmp_path / "p.npz").n_particles == tiny.n_particles


def test_export_analyses_may_be_a_comma_separated_text(tmp_path, tiny):
    regopack.export(tiny, "vtk", tmp_path / "a.vtp", analyses="coordination,contacts")
    assert (tmp_path / "a.vtp").is_file()


# -- sweep ---------------------------------------------------------------------------


def test_sweep_returns_the_results_table(tmp_path):
    exp = tmp_path / "exp.toml"
    exp.write_text(
        'name = "tiny"\nbase = "small"\n'
        '[set]\ncount = 30\n"domain.width" = 60.0\n"domain.height" = 60.0\n'
        '[sweep]\n"density.eta" = [0, 5]\n'
    )
    table = regopack.sweep(exp, out=tmp_path / "out", workers=1, plots=False)
    assert table.ok and len(table) == 2
    assert table.columns[:2] == ("run_id", "density.eta")
    np.testing.assert_array_equal(table.column("density.eta"), [0.0, 5.0])
    assert np.all(table.column("placed") > 0)
    with pytest.raises(KeyError):
        table.column("nope")
    rows = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert len(rows) == 3


# -- the package root ----------------------------------------------------------------


def test_root_exports_the_api_lazily():
    import subprocess
    import sys

    code = (
        "import sys, regopack; print('regopack.api.functions' in sys.modules); print(regopack.pack)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split("\n")
    assert out[0] == "False"
    assert "function pack" in out[1]
    assert {"scene", "pack", "analyze", "verify", "export", "sweep"} <= set(dir(regopack))
    with pytest.raises(AttributeError):
        regopack.nope  # noqa: B018


def test_no_sub_package_hides_a_function_of_the_root():
    """Importing every module leaves ``regopack.scene``, ``export``, ... the API's functions.

    A sub-package named like one of them would replace it as an attribute of the root.
    """
    import importlib
    import pkgutil

    for info in pkgutil.walk_packages(regopack.__path__, "regopack."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)
    for name in ("analyze", "export", "pack", "pack_and_summarise", "scene", "sweep", "verify"):
        assert callable(getattr(regopack, name)), name
    assert callable(regopack.load) and callable(regopack.save)
