from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest
from fakes import RegularPolygon, ShapeConfig, SizeConfig, UniformDiameter

from regopack.base.errors import ConfigError, PluginError
from regopack.base.outdir import mark_folder
from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.geometry.population import ShapeBatch
from regopack.packing.core import load
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import ShapeSpec
from regopack.run.pipeline import (
    default_out_dir,
    draw_population,
    particle_count,
    phi_in_window,
    run_scene,
)
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import assert_valid_packing, packing_from_polygons


def resolved(registry, *overrides, name="small", seed=None):
    return resolve_scene(load_scene(name, list(overrides), seed=seed), registry)


def test_auto_count(registry):
    scene = resolved(registry)
    size = UniformDiameter(SizeConfig())
    assert particle_count(scene, size) == round(200 * 200 / size.mean_area)
    assert particle_count(resolved(registry, "count=17"), size) == 17


def test_draw_order(registry):
    scene = resolved(registry, "count=500")
    pop = draw_population(scene, np.random.default_rng(3))

    rng = np.random.default_rng(3)
    radii = UniformDiameter(SizeConfig()).sample(500, rng)
    minerals = rng.choice(6, size=500, p=scene.fractions)
    np.testing.assert_array_equal(pop.radius, radii)
    np.testing.assert_array_equal(pop.mineral, minerals)
    assert pop.mineral.dtype == np.int64
    assert pop.mineral_names == scene.phase_names
    for p in range(6):
        idx = np.flatnonzero(minerals == p)
        batch = RegularPolygon(ShapeConfig()).generate(radii[idx], rng)
        np.testing.assert_array_equal(pop.shapes.orientation[idx], batch.orientation)
        for k, j in enumerate(idx[:5]):
            np.testing.assert_array_equal(pop.shapes.outline(j), batch.outline(k))


def test_draw_is_reproducible(registry):
    scene = resolved(registry, "count=300")
    a = draw_population(scene, np.random.default_rng(1))
    b = draw_population(scene, np.random.default_rng(1))
    np.testing.assert_array_equal(a.shapes.vertices, b.shapes.vertices)


def test_shape_plugin_returning_too_few_outlines(registry):
    from fakes import fake_registry

    class Short(RegularPolygon):
        def generate(self, radius, rng):
            b = super().generate(radius, rng)
            return ShapeBatch(b.vertices[:-8], b.offsets[:-1], b.orientation[:-1])

    class Plugin:
        @hookimpl
        def regopack_shapes(self):
            return [ShapeSpec("short", ShapeConfig, Short)]

    reg = fake_registry(Plugin())
    scene = resolve_scene(load_scene("small", ["count=50", "phases.0.shape.kind=short"]), reg)
    with pytest.raises(PluginError, match=r"returned \d+ outlines for \d+ radii"):
        draw_population(scene, np.random.default_rng(0))


def test_run_scene_writes_nothing_without_out_dir(registry, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    outcome = run_scene(resolved(registry, "count=200"), None)
    assert outcome.packing_path is None
    assert list(tmp_path.iterdir()) == []
    assert outcome.packing.n_particles == 200


def test_run_scene(registry, tmp_path):
    calls = []
    scene = resolved(registry, "count=400", seed=4)
    outcome = run_scene(scene, tmp_path / "out", progress=lambda *a: calls.append(a))
    s = outcome.summary
    p = outcome.packing
    assert s["scene"] == "small"
    assert s["seed"] == 4
    assert s["tried"] == 400
    assert s["placed"] + s["not_placed"] == 400
    assert s["placed"] == p.n_placed > 0
    assert s["interior_margin"] == 40.0
    assert s["eta"] == 0.0
    assert s["cells"] > 0  # the fake inserter's stats are merged in
    assert s["phi_domain"] == pytest.approx(p.area()[p.placed].sum() / 200**2)
    assert 0 < s["phi_interior"] < 1
    assert s["wall_time_s"] > 0
    assert calls[-1] == (400, s["placed"], 400)
    assert_valid_packing(p)
    assert outcome.packing_path == tmp_path / "out" / "packing.npz"
    on_disk = json.loads(outcome.summary_path.read_text())
    classes = on_disk.pop("not_placed_by_class")
    assert classes == s["not_placed_by_class"]
    assert sum(c["not_placed"] for c in classes) == s["not_placed"]
    assert all(c["not_placed"] > 0 for c in classes)
    # the fake registry has no analyzers: the fabric block says so
    assert (
        on_disk.pop("fabric") == s["fabric"] == {"skipped": "no analyzer 'contacts' is registered"}
    )
    nested = ("not_placed_by_class", "fabric")
    assert on_disk == pytest.approx({k: v for k, v in s.items() if k not in nested})
    loaded = load(outcome.packing_path)
    assert loaded.scene == scene.to_dict()
    assert loaded.seed == 4
    np.testing.assert_array_equal(loaded.centre, p.centre)


def test_same_seed_same_packing(registry):
    a = run_scene(resolved(registry, "count=100"), None).packing
    b = run_scene(resolved(registry, "count=100"), None).packing
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.centre, b.centre)


def test_empty_interior_window(registry):
    outcome = run_scene(resolved(registry, "count=5", "domain.width=60"), None)
    assert math.isnan(outcome.summary["phi_interior"])
    assert "empty" in outcome.summary["phi_interior_note"]


def test_interrupted_run_keeps_previous_files(registry, tmp_path):
    out = tmp_path / "out"
    run_scene(resolved(registry, "count=100"), out)
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    with pytest.raises(KeyboardInterrupt):
        run_scene(resolved(registry, "count=100", "insertion.fail_after=10", seed=9), out)
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before


def test_default_out_dir(registry):
    assert str(default_out_dir(resolved(registry, seed=3))) == "runs/small-seed3"


def test_phi_in_window():
    sq = [(0, 0), (2, 0), (2, 2), (0, 2)]
    p = packing_from_polygons([sq], domain=(0, 4, 0, 4))
    assert phi_in_window(p, (0, 4, 0, 4)) == pytest.approx(4 / 16)
    assert phi_in_window(p, (1, 3, 1, 3)) == pytest.approx(1 / 4)
    assert phi_in_window(p, (2, 4, 2, 4)) == 0.0
    assert math.isnan(phi_in_window(p, (2, 2, 0, 4)))


def _scattered_triangles(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-12.0, 12.0, (n, 2))
    return [c + rng.uniform(-1.5, 1.5, (3, 2)) for c in centres]


@pytest.mark.parametrize(
    "window",
    [
        Rectangle(-6.0, 7.0, -5.0, 4.0),
        Circle(0.5, -0.5, 6.5),
        ConvexPolygon(((-8.0, -6.0), (9.0, -7.0), (1.0, 8.0))),
        PeriodicRectangle(-10.0, 10.0, -10.0, 10.0),
    ],
)
def test_phi_in_window_batch_by_batch_is_the_whole_at_once_exactly(
    window: Domain, monkeypatch: pytest.MonkeyPatch
) -> None:
    import regopack.packing.solid_fraction as fraction_module

    p = packing_from_polygons(_scattered_triangles(300, 4), domain=(-15, 15, -15, 15))
    whole = window.covered_area(p.to_shapely()) / window.area
    assert 0.05 < whole < 1.0
    for batch in (1, 7, 299, 10**6):
        monkeypatch.setattr(fraction_module, "SHAPELY_BATCH", batch)
        assert phi_in_window(p, window) == whole


def test_phi_in_window_of_a_domain_with_its_own_covered_area() -> None:
    @dataclass(frozen=True)
    class Halved(Rectangle):
        def covered_area(self, geoms: np.ndarray) -> float:
            return 0.5 * super().covered_area(geoms)

    p = packing_from_polygons(_scattered_triangles(50, 5), domain=(-15, 15, -15, 15))
    window = Halved(-6.0, 7.0, -5.0, 4.0)
    assert phi_in_window(p, window) == 0.5 * phi_in_window(p, Rectangle(-6.0, 7.0, -5.0, 4.0))


def test_analyses_run_with_their_requirements(tmp_path):
    from fakes import fake_registry
    from pydantic import BaseModel, ConfigDict

    from regopack.registry.interfaces import Analyzer
    from regopack.registry.plugin_types import AnalyzerSpec

    class NoConfig(BaseModel):
        model_config = ConfigDict(extra="forbid")

    class Count(Analyzer):
        name = "count"

        def compute(self, packing, context):
            self.n = packing.n_placed
            return self

        def results(self):
            return {"n": self.n}

    class Twice(Analyzer):
        name = "twice"
        requires = ("count",)

        def compute(self, packing, context):
            self.n2 = 2 * context["count"].n
            return self

        def results(self):
            return {"n2": self.n2}

    class Plugin:
        @hookimpl
        def regopack_analyzers(self):
            return [
                AnalyzerSpec("count", NoConfig, lambda c: Count()),
                AnalyzerSpec("twice", NoConfig, lambda c: Twice()),
            ]

    reg = fake_registry(Plugin())
    scene = resolve_scene(load_scene("small", ["count=50", 'outputs.analyses=["twice"]']), reg)
    outcome = run_scene(scene, tmp_path)
    placed = outcome.packing.n_placed
    assert outcome.summary["analyses"] == {"twice": {"n2": 2 * placed}}
    assert json.loads(outcome.summary_path.read_text())["analyses"]["twice"]["n2"] == 2 * placed


def output_registry():
    """The fake plugins with the built-in exporters and analyzers."""
    from fakes import fake_registry

    import regopack.plugins.analyzers
    import regopack.plugins.exporters

    return fake_registry(regopack.plugins.exporters, regopack.plugins.analyzers)


def listing(folder):
    return sorted(p.name for p in folder.iterdir())


def test_a_rerun_replaces_the_whole_run_folder(tmp_path):
    registry, out = output_registry(), tmp_path / "out"
    extras = ['outputs.analyses=["density"]', 'outputs.exports=["vtk", "csv"]']
    run_scene(resolved(registry, "count=30", *extras, seed=1), out, figures=False)
    assert "analysis" in listing(out) and "packing.vtp" in listing(out)
    (out / ".packing.npz.abcd1234.tmp").write_bytes(b"what a killed write left")
    (out / "notes.txt").write_text("added by hand")

    outcome = run_scene(resolved(registry, "count=30", seed=2), out)
    assert listing(out) == [".regopack", "packing.npz", "summary.json"]
    assert json.loads(outcome.summary_path.read_text())["seed"] == 2
    assert load(outcome.packing_path).seed == 2
    assert listing(tmp_path) == ["out"]


def test_the_paths_of_a_run_are_in_its_folder(tmp_path):
    extras = ['outputs.analyses=["density"]', 'outputs.exports=["vtk"]']
    outcome = run_scene(
        resolved(output_registry(), "count=30", *extras), tmp_path / "o", figures=False
    )
    assert outcome.analysis is not None
    assert outcome.analysis.out_dir == tmp_path / "o" / "analysis"
    assert outcome.analysis.report == tmp_path / "o" / "analysis" / "report.md"
    assert outcome.analysis.report.is_file()
    assert outcome.exports == (tmp_path / "o" / "packing.vtp",)
    assert outcome.exports[0].is_file()
    results = json.loads(outcome.analysis.results.read_text())
    assert results["packing"] == str(tmp_path / "o" / "packing.npz")
    assert listing(tmp_path) == ["o"]


def test_leftovers_of_a_killed_run_are_removed_by_the_next_run(registry, tmp_path):
    for name in ("out.tmp-abcd_123", "out.old-0123abcd", "out.tmp-keep", "other.tmp-abcd1234"):
        (tmp_path / name).mkdir()
    (tmp_path / "out.tmp-abcd_123" / "packing.npz").write_bytes(b"half a packing")
    mark_folder(tmp_path / "out.tmp-abcd_123", "run")  # as a run marks it when it starts
    (tmp_path / "out.old-users001").mkdir()  # the user's, with files: kept
    (tmp_path / "out.old-users001" / "notes.txt").write_text("mine")
    run_scene(resolved(registry, "count=20"), tmp_path / "out")
    assert listing(tmp_path) == ["other.tmp-abcd1234", "out", "out.old-users001", "out.tmp-keep"]


def test_a_folder_that_holds_no_run_is_refused_and_kept(registry, tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("precious")
    with pytest.raises(ConfigError, match="exists and was not written by regopack") as info:
        run_scene(resolved(registry, "count=20"), mine)
    assert "\n" not in str(info.value)
    assert listing(mine) == ["notes.txt"]
    assert listing(tmp_path) == ["mine"]
    empty = tmp_path / "empty"
    empty.mkdir()
    assert run_scene(resolved(registry, "count=20"), empty).packing_path.is_file()


def test_an_analysis_folder_is_not_replaced_by_a_run(registry, tmp_path):
    from regopack.analysis.pipeline import run_analyses, write_analysis

    packing = run_scene(resolved(output_registry(), "count=20")).packing
    analyzers = run_analyses(packing, output_registry(), [("density", {})])
    write_analysis(tmp_path / "a", packing, analyzers, figures=False)
    with pytest.raises(ConfigError, match="holds a regopack analysis, not a run"):
        run_scene(resolved(registry, "count=20"), tmp_path / "a")


@pytest.mark.parametrize("out", [".", "..", "sub/.."])
def test_the_current_directory_is_never_an_output_folder(registry, tmp_path, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    with pytest.raises(ConfigError, match="is the current directory or contains it"):
        run_scene(resolved(registry, "count=20"), out)
    assert listing(tmp_path) == ["sub"]


def test_extra_files_are_written_into_the_run_folder(registry, tmp_path):
    outcome = run_scene(resolved(registry, "count=20"), tmp_path, extra_files={"scene.json": "{}"})
    assert (tmp_path / "scene.json").read_text() == "{}"
    assert outcome.summary_path == tmp_path / "summary.json"
    with pytest.raises(ConfigError, match=r"'summary\.json': the same file as outputs\.summary"):
        run_scene(resolved(registry, "count=20"), tmp_path, extra_files={"summary.json": "x"})
    with pytest.raises(ConfigError, match="contains '/'"):
        run_scene(resolved(registry, "count=20"), tmp_path, extra_files={"../x": "x"})


def test_summary_extras_are_in_the_written_summary(registry, tmp_path):
    outcome = run_scene(
        resolved(registry, "count=20"),
        tmp_path,
        summary_extras=lambda packing: {"extra": {"placed": packing.n_placed}},
    )
    on_disk = json.loads(outcome.summary_path.read_text())
    assert on_disk["extra"] == {"placed": outcome.packing.n_placed} == outcome.summary["extra"]


def test_unwritable_output_is_a_config_error(registry, tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="cannot create the output directory"):
        run_scene(resolved(registry, "count=20"), tmp_path / "file" / "out")
