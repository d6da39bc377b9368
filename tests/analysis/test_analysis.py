"""regopack.analysis.pipeline: running analyzers with their requirements, writing their files."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from pydantic import BaseModel, ConfigDict

from regopack.analysis.pipeline import (
    DEFAULT_ANALYSES,
    AnalysisFiles,
    main_numbers,
    run_analyses,
    write_analysis,
)
from regopack.base.errors import ConfigError, PluginError
from regopack.plugins.analyzers import Contacts, Coordination, Density, Rdf
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Analyzer
from regopack.registry.manager import default_registry
from regopack.registry.plugin_types import AnalyzerSpec
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import make_registry, packing_from_polygons

pytest.importorskip("regopack.plugins.inserters.available_arc")


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def packing(registry):
    return run_scene(resolve_scene(load_scene("small", ["count=300"]), registry)).packing


@pytest.fixture(scope="module")
def written(packing, registry, tmp_path_factory) -> AnalysisFiles:
    analyzers = run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES])
    out = tmp_path_factory.mktemp("analysis")
    return write_analysis(out, packing, analyzers, figures=False, packing_path="p.npz")


def _forbid(monkeypatch, cls: type) -> None:
    def boom(self, *args, **kwargs):
        raise AssertionError(f"{cls.__name__} was built or computed")

    monkeypatch.setattr(cls, "__init__", boom)
    monkeypatch.setattr(cls, "compute", boom)


# ---------------------------------------------------------------------------
# run_analyses


def test_rdf_alone_never_builds_contacts(packing, registry, monkeypatch, tmp_path):
    _forbid(monkeypatch, Contacts)
    _forbid(monkeypatch, Coordination)
    done = run_analyses(packing, registry, [("rdf", {})])
    assert list(done) == ["rdf"]
    assert isinstance(done["rdf"], Rdf)
    files = write_analysis(tmp_path, packing, done, figures=False)
    assert sorted(files.tables) == ["rdf_far", "rdf_far_pairs", "rdf_near", "rdf_near_pairs"]
    assert not (tmp_path / "contacts.csv").exists()
    assert files.summary["tol"] is None


def test_a_scene_asking_for_rdf_never_builds_contacts(registry, monkeypatch, tmp_path):
    _forbid(monkeypatch, Contacts)
    # the run summary's fabric block searches contacts unless it is switched off
    overrides = ["count=100", 'outputs.analyses=["rdf"]', "outputs.fabric=false"]
    scene = resolve_scene(load_scene("small", overrides), registry)
    outcome = run_scene(scene, tmp_path, figures=False)
    assert list(outcome.summary["analyses"]) == ["rdf"]
    assert outcome.analysis is not None
    assert json.loads(outcome.analysis.results.read_text())["analyses"] == ["rdf"]


def test_computed_analyzers_are_reused_not_computed_again(packing, registry, monkeypatch):
    contacts = run_analyses(packing, registry, [("contacts", {"tol": 0.1})])["contacts"]
    monkeypatch.setattr(Contacts, "compute", _forbid_compute)
    done = run_analyses(
        packing, registry, [("coordination", {})], computed={"contacts3d": contacts}
    )
    assert done["contacts"] is contacts and done["coordination"].results()["tol"] == 0.1


def _forbid_compute(self, *args):
    raise AssertionError("computed again")


def test_requirements_come_first_and_keep_requested_parameters(packing, registry):
    done = run_analyses(packing, registry, [("coordination", {}), ("contacts", {"tol": 0.1})])
    assert list(done) == ["contacts", "coordination"]
    assert done["contacts"].config.tol == 0.1
    assert done["coordination"].results()["tol"] == 0.1


def test_a_requirement_not_requested_uses_its_defaults(packing, registry):
    done = run_analyses(packing, registry, [("network", {})])
    assert list(done) == ["contacts", "network"]
    assert done["contacts"].config.tol == 0.05


def test_params_reach_analyzers_run_only_as_requirements(packing, registry):
    done = run_analyses(
        packing, registry, [("coordination", {})], params={"contacts": {"tol": 0.08}}
    )
    assert done["contacts"].config.tol == 0.08


def test_params_for_an_analyzer_that_is_not_run(packing, registry):
    with pytest.raises(ConfigError, match=r"^parameters given for analyzer 'contacts', which"):
        run_analyses(packing, registry, [("rdf", {})], params={"contacts": {"tol": 0.1}})


def test_unknown_analyzer_is_one_line_listing_the_known_ones(packing, registry):
    with pytest.raises(ConfigError) as info:
        run_analyses(packing, registry, [("rdff", {})])
    assert str(info.value) == (
        "unknown analyzer 'rdff'; known analyzers: contacts, coordination, density, "
        "homogeneity, local_fraction, network, psd, rdf"
    )


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"tol": -1}, "contacts.tol = -1: Input should be greater than 0"),
        ({"bogus": 1}, "contacts.bogus = 1: unknown field; allowed: tol, tol_max, margin"),
        (
            {"tol": 1.0, "tol_max": 0.5},
            "contacts: tol_max (0.5) must be at least tol (1.0)",
        ),
    ],
)
def test_bad_parameters_name_the_field(packing, registry, params, message):
    with pytest.raises(ConfigError) as info:
        run_analyses(packing, registry, [("contacts", params)])
    assert str(info.value) == message


def test_everything_is_validated_before_anything_is_computed(packing, registry, monkeypatch):
    def boom(self, *args):
        raise AssertionError("density was computed")

    monkeypatch.setattr(Density, "compute", boom)
    with pytest.raises(ConfigError, match=r"contacts\.tol"):
        run_analyses(packing, registry, [("density", {}), ("contacts", {"tol": -1})])


def test_sweep_beyond_tol_max(packing, registry):
    done = run_analyses(
        packing, registry, [("coordination", {})], params={"contacts": {"tol_max": 0.2}}
    )
    assert max(done["coordination"].results()["tol_sweep"]) <= 0.2  # default sweep is cut
    with pytest.raises(ConfigError, match=r"coordination.tols: 0.3 exceeds contacts.tol_max"):
        run_analyses(
            packing,
            registry,
            [("coordination", {"tols": [0.1, 0.3]})],
            params={"contacts": {"tol_max": 0.2}},
        )


class _NoConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")


def _analyzer(name: str, requires: tuple[str, ...]) -> type[Analyzer]:
    class Fake(Analyzer):
        def compute(self, packing, context):
            self.seen = sorted(context)
            return self

        def results(self):
            return {"seen": self.seen}

    Fake.name = name
    Fake.requires = requires
    return Fake


def _registry_of(*classes: type[Analyzer]):
    class Plugin:
        @hookimpl
        def regopack_analyzers(self):
            return [AnalyzerSpec(c.name, _NoConfig, lambda cfg, c=c: c()) for c in classes]

    return make_registry(Plugin(), builtins=())


def test_cycles_are_detected():
    reg = _registry_of(_analyzer("a", ("b",)), _analyzer("b", ("c",)), _analyzer("c", ("a",)))
    p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    with pytest.raises(PluginError, match=r"cycle: a -> b -> c -> a$"):
        run_analyses(p, reg, [("a", {})])


def test_unregistered_requirement_names_both():
    reg = _registry_of(_analyzer("a", ("missing",)))
    p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    with pytest.raises(PluginError, match=r"analyzer 'a' requires 'missing', which is not"):
        run_analyses(p, reg, [("a", {})])


def test_shared_requirement_is_computed_once():
    base = _analyzer("base", ())
    calls = []
    original = base.compute

    def counting(self, packing, context):
        calls.append(1)
        return original(self, packing, context)

    base.compute = counting  # type: ignore[method-assign]
    reg = _registry_of(base, _analyzer("x", ("base",)), _analyzer("y", ("base", "x")))
    p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    done = run_analyses(p, reg, [("y", {}), ("x", {})])
    assert list(done) == ["base", "x", "y"]
    assert done["y"].results() == {"seen": ["base", "x"]}
    assert len(calls) == 1


# ---------------------------------------------------------------------------
# write_analysis


def test_json_has_context_and_every_analyzer(written, packing):
    data = json.loads(written.results.read_text(encoding="utf-8"))
    for key in ("tol", "eta", "interior_margin", "regopack_version", "packing"):
        assert key in data
    assert data["tol"] == 0.05
    assert data["eta"] == 0.0
    assert data["interior_margin"] == 40.0
    assert data["packing"] == "p.npz"
    assert data["analyses"] == list(DEFAULT_ANALYSES)
    for name in DEFAULT_ANALYSES:
        assert isinstance(data[name], dict)
    assert data["density"]["n_placed"] == packing.n_placed
    assert data["mineral_names"] == list(packing.mineral_names)


def test_csv_tables_have_a_header_and_numeric_columns(written, packing):
    expected = {
        "contacts": ["i", "j", "area", "width", "radius", "depth", "theta"],
        "particles": ["particle", "mineral", "x", "y", "radius", "interior", "z"],
        "z_tol": ["tol", "z_domain", "z_interior"],
        "network": ["i", "j", "area"],
        "rdf_near": ["r", "total"],
        "rdf_near_pairs": ["mineral_a", "mineral_b", "r_lo", "r_hi", "r", "g"],
    }
    for table, columns in expected.items():
        path = written.tables[table]
        assert path.name == f"{table}.csv"
        header = path.read_text(encoding="utf-8").splitlines()[0].split(",")
        assert header[: len(columns)] == columns
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        assert data.shape[1] == len(header)
    particles = np.loadtxt(written.tables["particles"], delimiter=",", skiprows=1)
    assert len(particles) == packing.n_placed
    assert set(np.unique(particles[:, 5])) <= {0.0, 1.0}


def test_report_shows_the_numbers_and_its_links_exist(written):
    text = written.report.read_text(encoding="utf-8")
    assert "| φ domain |" in text
    assert "| Z domain |" in text
    links = re.findall(r"\]\(([^)]+)\)", text)
    assert "contacts.csv" in links
    for link in links:
        assert (written.out_dir / link).exists(), link


def test_npz_tables(packing, registry, tmp_path):
    done = run_analyses(packing, registry, [("network", {})])
    files = write_analysis(tmp_path, packing, done, figures=False, table_format="npz")
    with np.load(files.tables["network"]) as npz:
        assert sorted(npz.files) == ["area", "i", "j"]
        assert np.array_equal(npz["area"], done["network"].weight)


def test_rewriting_leaves_no_temporary_files(packing, registry, tmp_path):
    done = run_analyses(packing, registry, [("density", {})])
    write_analysis(tmp_path, packing, done, figures=False)
    write_analysis(tmp_path, packing, done, figures=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == [".regopack", "analysis.json", "report.md"]


def test_main_numbers_skip_what_was_not_run():
    rows = dict(main_numbers({"tol": None, "rdf": {"first_peak_r": 4.5, "far_mean": 1.1}}))
    assert rows == {"first g(r) peak": "4.5 µm", "far-field mean g(r)": "1.1"}
    peak = {"first_peak_r": 4.434, "first_peak_r_err": 0.2287}
    assert dict(main_numbers({"tol": None, "rdf": peak}))["first g(r) peak"] == "4.43 ± 0.23 µm"


def test_main_numbers_give_the_fabric_anisotropy_with_its_error():
    net = {"anisotropy": 0.17893, "anisotropy_error": 0.005778}
    assert dict(main_numbers({"network": net}))["fabric anisotropy"] == "0.1789 ± 0.0058"
    net["anisotropy_error"] = None
    assert dict(main_numbers({"network3d": net}))["fabric anisotropy"] == "0.1789"


def test_main_numbers_give_a_plateau_where_g_has_no_distinct_peak():
    """A top that is no peak is reported as the range it spans, without a position."""
    top = {"first_peak_r": None, "first_peak_r_err": None, "first_plateau": [3.85, 5.35]}
    row = dict(main_numbers({"tol": None, "rdf": top}))["first g(r) peak"]
    assert row == "no distinct peak (plateau 3.85–5.35 µm)"


def test_run_scene_writes_the_analysis_beside_the_packing(registry, tmp_path):
    scene = resolve_scene(
        load_scene("small", ["count=80", 'outputs.analyses=["coordination"]']), registry
    )
    outcome = run_scene(scene, tmp_path, figures=False)
    assert list(outcome.summary["analyses"]) == ["coordination"]
    assert outcome.analysis is not None
    assert outcome.analysis.out_dir == tmp_path / "analysis"
    data = json.loads((tmp_path / "analysis" / "analysis.json").read_text())
    assert data["analyses"] == ["contacts", "coordination"]
    assert data["packing"] == str(tmp_path / "packing.npz")


def test_importing_does_not_load_matplotlib():
    code = (
        "import sys, regopack, regopack.analysis.pipeline, regopack.run.pipeline; "
        "import regopack.cli.commands; "
        "print('matplotlib' in sys.modules)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"


# ---------------------------------------------------------------------------
# figures come from the registry's figure specs


class _StemFigure:
    """A plugin that adds one figure to the ``density`` analyzer."""

    def __init__(self) -> None:
        self.calls: list[list[str]] = []

    @hookimpl
    def regopack_analysis_figures(self):
        from regopack.registry.plugin_types import FigureSpec

        def draw(packing, analyzers, out_dir):
            self.calls.append(list(analyzers))
            out_dir.mkdir(parents=True, exist_ok=True)
            path = out_dir / "extra-density.png"
            path.write_bytes(b"png")
            return [path]

        return [FigureSpec("density", draw, {"extra-density": "An added figure"})]


def test_figures_are_drawn_by_the_registry_figure_specs(packing, tmp_path):
    plugin = _StemFigure()
    registry = make_registry(plugin, builtins=("regopack.plugins.analyzers",))
    done = run_analyses(packing, registry, [("density", {"margin": 0.0})])
    files = write_analysis(tmp_path, packing, done, registry=registry)
    assert plugin.calls == [["density"]]
    stems = [p.stem for p in files.figures]
    assert stems[:2] == ["packing", "packing"]  # built-in figures first (PNG and SVG)
    assert stems[-1] == "extra-density"
    report = files.report.read_text(encoding="utf-8")
    assert "### An added figure" in report
    assert "](figures/extra-density.png)" in report


def test_a_figure_spec_is_skipped_when_its_analyzer_was_not_computed(packing, tmp_path):
    plugin = _StemFigure()
    registry = make_registry(plugin, builtins=("regopack.plugins.analyzers",))
    done = run_analyses(packing, registry, [("rdf", {})])
    files = write_analysis(tmp_path, packing, done, registry=registry)
    assert plugin.calls == []
    assert [p.stem for p in files.figures] == ["rdf", "rdf"]


def test_a_registry_without_figure_specs_draws_none(packing, registry, tmp_path):
    done = run_analyses(packing, registry, [("density", {"margin": 0.0})])
    files = write_analysis(tmp_path, packing, done, registry=make_registry(builtins=()))
    assert files.figures == ()
    assert not (tmp_path / "figures").exists()


class _BrokenFigure:
    """A plugin whose figure fails in one of several ways."""

    def __init__(self, how: str) -> None:
        self.how = how

    @hookimpl
    def regopack_analysis_figures(self):
        from regopack.registry.plugin_types import FigureSpec

        def draw(packing, analyzers, out_dir):
            if self.how == "raises":
                raise RuntimeError("draw failed")
            if self.how == "none":
                return None
            if self.how == "text":
                return "x.png"
            if self.how == "outside":
                return [out_dir.parent.parent / "elsewhere.png"]
            return []

        return [FigureSpec("density", draw, {"packing": "HIJACKED"})]


@pytest.mark.parametrize("how", ["raises", "none", "text", "outside"])
def test_a_failing_plugin_figure_loses_only_itself(packing, tmp_path, how):
    registry = make_registry(_BrokenFigure(how), builtins=("regopack.plugins.analyzers",))
    done = run_analyses(packing, registry, [("density", {"margin": 0.0})])
    from regopack.analysis.pipeline import FigureWarning

    with pytest.warns(FigureWarning):
        files = write_analysis(tmp_path / "a", packing, done, registry=registry)
    assert files.results.is_file()
    assert [p.stem for p in files.figures] == ["packing", "packing"]
    report = files.report.read_text(encoding="utf-8")
    assert "HIJACKED" not in report


def test_captions_that_are_not_texts_are_refused_when_the_registry_is_built():
    from regopack.registry.plugin_types import FigureSpec

    class _BadCaptions:
        @hookimpl
        def regopack_analysis_figures(self):
            return [FigureSpec("density", lambda p, a, o: [], ["a"])]

    with pytest.raises(PluginError, match="captions"):
        make_registry(_BadCaptions(), builtins=())


def test_the_command_prints_a_failing_figure_as_one_warning_line(tmp_path, capsys, monkeypatch):
    import regopack
    from regopack.cli import commands as cli

    registry = make_registry(_BrokenFigure("raises"))
    monkeypatch.setattr("regopack.registry.manager.default_registry", lambda **kw: registry)
    p = regopack.pack("small", domain__width=60, domain__height=60, count=30, registry=registry)
    regopack.save(p, tmp_path / "p.npz")
    code = cli.main(["analyze", str(tmp_path / "p.npz"), "--only", "density"])
    err = capsys.readouterr().err
    assert code == 0
    assert "regopack: warning: the figures of 'density'" in err and "draw failed" in err
    assert (tmp_path / "analysis" / "analysis.json").is_file()
