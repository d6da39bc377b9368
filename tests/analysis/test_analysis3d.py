"""Analyses of 3D runs and packings: scenes, ``regopack analyze``, and what is refused."""

from __future__ import annotations

import json

import pytest
from cli_helpers import one_error_line

import regopack
from regopack.base.errors import ConfigError, DeprecatedNameWarning
from regopack.cli import main
from regopack.plugins.analyzers.density import Density, DensityConfig
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import AnalyzerSpec
from regopack.testing import make_registry, packing_from_polygons

SCENE = {
    "name": "small3d",
    "seed": 2,
    "count": "auto",
    "domain": {"kind": "box", "width": 18.0, "height": 18.0, "depth": 18.0},
    "size": {"kind": "uniform", "d_min": 3.0, "d_max": 5.0},
    "phases": [
        {"name": "pyroxene", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 0.5}},
        {"name": "glass", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 2.0}},
    ],
    "insertion": {"kind": "available-surface"},
    "density": {"kind": "eta"},
    "outputs": {"analyses": ["density3d", {"kind": "coordination3d", "tols": [0.05, 0.2]}]},
}


pytestmark = pytest.mark.filterwarnings("ignore:the analysis kind:FutureWarning")
"""The scene and several tests ask for analyzers by their old 3D names, as scenes did."""

BOTH = ("contacts", "coordination", "density", "homogeneity", "network", "psd", "rdf")
"""The analyzers of 2D and 3D packings."""


@pytest.fixture(scope="module")
def run3d(tmp_path_factory):
    out = tmp_path_factory.mktemp("run3d") / "run"
    return regopack.pack_and_summarise(SCENE, out=out, verify=False)


@pytest.fixture(scope="module")
def packing3d(run3d):
    return run3d.packing


def test_a_3d_run_reports_its_analyses_as_a_2d_run(run3d) -> None:
    summary = json.loads(run3d.summary_path.read_text(encoding="utf-8"))
    assert list(summary["analyses"]) == ["density3d", "coordination3d"]
    coordination = summary["analyses"]["coordination3d"]
    # the sweep asked for, and the contact tolerance d_min / 40 (d_min = 3)
    assert coordination["tol_sweep"] == pytest.approx([0.05, 0.075, 0.2], rel=1e-12)
    assert coordination["rattler_min_contacts"] == 2
    assert summary["analyses"]["density3d"]["phi_domain"] == pytest.approx(summary["phi_domain"])
    files = run3d.analysis
    data = json.loads(files.results.read_text(encoding="utf-8"))
    assert data["dimension"] == 3
    assert data["analyses"] == ["density3d", "contacts3d", "coordination3d"]
    assert files.report.read_text(encoding="utf-8").count("Z interior") == 1
    assert (
        (files.out_dir / "particles.csv")
        .read_text()
        .startswith("particle,mineral,x,y,z,radius,interior,contacts,rattler,contacts_mechanical")
    )


def test_regopack_analyze_takes_a_3d_packing(run3d, tmp_path, capsys) -> None:
    out = tmp_path / "analysis"
    argv = ["analyze", str(run3d.packing_path), "--tol", "0.1", "--out", str(out)]
    assert main([*argv, "--no-figures"]) == 0
    text = capsys.readouterr().out
    for label in ("φ domain", "median contact volume V_c", "Z interior", "fabric anisotropy"):
        assert label in text
    data = json.loads((out / "analysis.json").read_text(encoding="utf-8"))
    assert data["analyses"] == ["density3d", "contacts3d", "coordination3d", "rdf3d", "network3d"]
    assert data["tol"] == 0.1 and data["contacts3d"]["tol"] == 0.1


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--only", "local_fraction"], "analyzer 'local_fraction' analyses 2D packings, not 3D "),
        (["--set", "contacts3d.tol=-1"], "contacts3d.tol = -1"),
        # tol_max defaults to d_min / 4 = 0.75 (d_min = 3)
        (["--set", "coordination3d.tols=[0.1, 0.9]"], "0.9 exceeds contacts3d.tol_max = 0.75"),
        (["--only", "rdf3d", "--set", "rdf3d.near=[5, 1]"], "rdf3d: near must be a range"),
        (["--set", "contacts3d"], "expected NAME.FIELD=VALUE"),
    ],
)
def test_mistakes_get_one_line(run3d, tmp_path, capsys, args, expected) -> None:
    path = str(run3d.packing_path)
    assert main(["analyze", path, "--no-figures", "--out", str(tmp_path / "a"), *args]) != 0
    line = one_error_line(capsys)
    assert expected in line
    if "'local_fraction'" in expected:
        assert line.startswith(f"regopack: error: {path}: ")
        assert line.endswith("analyzers of 3D packings: " + ", ".join(BOTH))


def test_a_3d_analyzer_is_refused_on_a_2d_packing() -> None:
    class Solid3D:
        @hookimpl
        def regopack_analyzers(self):
            spec = AnalyzerSpec("solid", DensityConfig, Density, dimensions=(3,))
            return [spec]

    square = [[(0, 0), (1, 0), (1, 1), (0, 1)]]
    packing = packing_from_polygons(square, domain=(0, 2, 0, 2))
    with pytest.raises(ConfigError, match="analyses 3D packings, not 2D ones; analyzers of 2D"):
        regopack.analyze(packing, "solid", registry=make_registry(Solid3D()))


# ---------------------------------------------------------------------------
# one analyzer per quantity, and the old 3D names


def test_the_analyzers_of_both_dimensions_give_3d_results_under_their_names(packing3d) -> None:
    res = regopack.analyze(packing3d, ["network", "psd"])
    assert list(res) == ["contacts", "network", "psd"]
    assert res["contacts"]["median_volume"] > 0 and len(res["network"]["fabric"]) == 3


def test_an_old_name_warns_once_and_files_its_results_and_requirements_under_old_names(
    packing3d,
) -> None:
    with pytest.warns(DeprecatedNameWarning) as caught:
        old = regopack.analyze(packing3d, "network3d", contacts3d__tol=0.1)
    messages = [str(w.message) for w in caught if w.category is DeprecatedNameWarning]
    assert messages == [
        "the analysis kind 'network3d' is deprecated and will be removed in the next release; "
        "use 'network'",
        "the analysis kind 'contacts3d' is deprecated and will be removed in the next release; "
        "use 'contacts'",
    ]
    new = regopack.analyze(packing3d, "network", contacts__tol=0.1)
    assert list(old) == ["contacts3d", "network3d"] and list(new) == ["contacts", "network"]
    for a, b in (("contacts3d", "contacts"), ("network3d", "network")):
        assert old[a].scalars == new[b].scalars
        assert old[a].tables.keys() == new[b].tables.keys()
        for table in old[a].tables:
            assert old[a].tables[table].tobytes() == new[b].tables[table].tobytes()


def test_the_default_3d_analyses_keep_their_old_names_without_a_warning(packing3d) -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = regopack.analyze(packing3d)
    assert list(res) == ["density3d", "contacts3d", "coordination3d", "rdf3d", "network3d"]


def test_an_analyzer_asked_for_by_both_names_is_refused_in_one_line(packing3d) -> None:
    with pytest.warns(DeprecatedNameWarning):
        with pytest.raises(ConfigError) as err:
            regopack.analyze(packing3d, ["rdf", "rdf3d"])
    assert str(err.value) == "analyzers 'rdf' and 'rdf3d' are one analyzer ('rdf'); ask for it once"


def test_what_has_no_meaning_in_3d_is_one_line(packing3d) -> None:
    with pytest.raises(ConfigError) as err:
        regopack.analyze(packing3d, "homogeneity", homogeneity__tiles=[2, 2])
    assert str(err.value) == (
        "homogeneity.tiles = (2, 2): has no meaning for a 3D packing, only for 2D ones; "
        "its 3D parameters: layers, shells"
    )
    with pytest.raises(ConfigError, match=r"^analyzer 'local_fraction' analyses 2D packings, not"):
        regopack.analyze(packing3d, "local_fraction")


def _square_packing():  # type: ignore[no-untyped-def]
    return packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 2, 0, 2))


def test_an_old_name_is_shown_to_users_by_default(run3d) -> None:
    # a FutureWarning: Python shows it outside __main__, where a DeprecationWarning is hidden
    import subprocess
    import sys

    code = "import regopack, sys; regopack.analyze(regopack.load(sys.argv[1]), 'density3d')"
    done = subprocess.run(
        [sys.executable, "-c", code, str(run3d.packing_path)],
        capture_output=True,
        text=True,
        check=True,
        env={k: v for k, v in __import__("os").environ.items() if k != "PYTHONWARNINGS"},
    )
    assert "the analysis kind 'density3d' is deprecated" in done.stderr
    assert "use 'density'" in done.stderr


def test_an_old_3d_name_is_refused_on_a_2d_packing() -> None:
    with pytest.raises(ConfigError, match=r"^analyzer 'density3d' analyses 3D packings, not 2D"):
        regopack.analyze(_square_packing(), "density3d")


def test_a_3d_parameter_of_a_2d_scene_is_refused_by_config(tmp_path, capsys) -> None:
    argv = ["config", "small", "--set", 'outputs.analyses=[{kind = "homogeneity", shells = 3}]']
    assert main(argv) == 2
    assert one_error_line(capsys) == (
        "regopack: error: --set: outputs.analyses.0.shells = 3: has no meaning for a 2D "
        "packing, only for 3D ones; its 2D parameters: ring_width, rings, tiles, layers"
    )


def test_one_analyzer_under_two_names_in_a_scene_is_refused_before_packing(capsys) -> None:
    argv = ["config", "table1-3d", "--set", 'outputs.analyses=["density", "density3d"]']
    assert main(argv) == 2
    assert one_error_line(capsys) == (
        "regopack: error: --set: outputs.analyses: analyzers 'density' and 'density3d' are "
        "one analyzer ('density'); ask for it once"
    )


def test_parameters_under_both_names_are_refused(packing3d) -> None:
    with pytest.raises(ConfigError) as err:
        regopack.analyze(packing3d, "contacts3d", contacts__tol=0.1, contacts3d__tol=0.3)
    assert "parameters given for 'contacts' and for 'contacts3d'" in str(err.value)


class _NeedsOldName(Density):
    name = "mine"  # type: ignore[assignment]
    requires = ("coordination3d",)

    def compute(self, packing, context):  # type: ignore[no-untyped-def]
        self.z = context["coordination3d"].results()["z_domain"]
        return self

    def results(self):  # type: ignore[no-untyped-def]
        return {"z": self.z}


def test_a_requirement_named_by_its_old_name_is_filed_under_it(packing3d) -> None:
    class Plugin:
        @hookimpl
        def regopack_analyzers(self):  # type: ignore[no-untyped-def]
            return [AnalyzerSpec("mine", DensityConfig, _NeedsOldName, dimensions=(3,))]

    with pytest.warns(DeprecatedNameWarning, match="'coordination3d' is deprecated"):
        done = regopack.analyze(packing3d, "mine", registry=make_registry(Plugin()))
    assert list(done) == ["contacts3d", "coordination3d", "mine"]


class _ReadOnlyName(Density):
    @property
    def name(self) -> str:  # type: ignore[override]
        return "mine"


def test_an_analyzer_with_a_read_only_name_runs() -> None:
    class Plugin:
        @hookimpl
        def regopack_analyzers(self):  # type: ignore[no-untyped-def]
            return [AnalyzerSpec("mine", DensityConfig, _ReadOnlyName)]

    done = regopack.analyze(_square_packing(), "mine", registry=make_registry(Plugin()))
    assert list(done) == ["mine"]
