"""``outputs.exports`` of 3D scenes: 3D exporters write beside the packing, 2D ones are refused."""

from __future__ import annotations

import pytest
from cli_helpers import one_error_line
from packings3d import scene3d

import regopack
from regopack.base.errors import ConfigError, DeprecatedNameWarning
from regopack.cli import main
from regopack.packing.core import load

SCENE_TOML = """\
name = "box3d"
seed = 1
count = "auto"

[domain]
kind = "box"
width = 15.0
height = 15.0
depth = 15.0

[size]
kind = "change5"
d_min = 2.0
d_max = 12.0

[[phases]]
name = "plagioclase"
fraction = 1.0
shape = { kind = "polyhedron", psi = 1.0 }

[insertion]
kind = "available-surface"

[density]
kind = "eta"

[outputs]
exports = ["stl", { kind = "svg", width_px = 300 }]
"""


def test_a_3d_run_writes_every_3d_export_beside_its_packing(tmp_path) -> None:  # type: ignore[no-untyped-def]
    exports = ["vtk", "stl", "gsd", "lammps", {"kind": "slice", "axis": "x"}]
    scene = {**scene3d(15.0), "outputs": {"exports": exports}}
    outcome = regopack.pack_and_summarise(scene, out=tmp_path / "run", verify=False)
    run = tmp_path / "run"
    names = ["packing.vtu", "packing.stl", "packing.gsd", "packing.data", "packing.slice.npz"]
    assert [p.name for p in outcome.exports] == names
    assert all(p.parent == run and p.stat().st_size > 0 for p in outcome.exports)
    assert (run / "packing.in").exists() and (run / "packing.slice.png").exists()
    section = load(run / "packing.slice.npz")
    assert section.scene["slice"]["axis"] == "x" and section.n_placed > 0
    assert not list(tmp_path.glob("run.tmp*"))


def test_a_2d_exporter_in_a_3d_scene_file_is_one_line(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "box.toml"
    path.write_text(SCENE_TOML, encoding="utf-8")
    assert main(["run", str(path), "--out", str(tmp_path / "run")]) != 0
    assert one_error_line(capsys) == (
        f"regopack: error: {path}: outputs.exports.1.kind = 'svg' is a 2D exporter, but "
        "domain.kind = 'box' makes the scene 3D; 3D exporters: gsd, image, lammps, liggghts, "
        "slice, stl, vtk, yade"
    )
    assert not (tmp_path / "run").exists()


def test_a_2d_exporter_set_on_the_command_line_is_blamed_on_it(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "box.toml"
    path.write_text(SCENE_TOML.replace('"stl", { kind = "svg", width_px = 300 }', ""), "utf-8")
    args = ["run", str(path), "--set", 'outputs.exports=["csv"]', "--out", str(tmp_path / "r")]
    assert main(args) != 0
    line = one_error_line(capsys)
    assert line.startswith("regopack: error: --set: outputs.exports.0 = 'csv' is a 2D exporter")


def test_a_3d_exporter_in_a_2d_scene_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"outputs\.exports\.0 = 'stl' is a 3D exporter, but "):
        regopack.scene("small", outputs__exports=["stl"])


def test_the_files_of_an_exporter_of_both_dimensions_follow_the_scene() -> None:
    from regopack.scenes.model import output_files

    for source, name in ((scene3d(15.0), "packing.vtu"), ("small", "packing.vtp")):
        files = output_files(regopack.scene(source, outputs__exports=["vtk", "lammps"]))
        assert files["outputs.exports.0"] == [name]
        assert files["outputs.exports.1"] == ["packing.data", "packing.in"]


def test_a_3d_run_takes_the_old_exporter_names_with_their_parameters(tmp_path) -> None:
    exports = ["vtk3d", {"kind": "lammps3d", "density": 2.0}]
    scene = {**scene3d(15.0), "outputs": {"exports": exports}}
    with pytest.warns(DeprecatedNameWarning) as caught:
        outcome = regopack.pack_and_summarise(scene, out=tmp_path / "run", verify=False)
    said = {str(w.message).split(" is deprecated")[0] for w in caught}
    assert said == {"the export kind 'vtk3d'", "the export kind 'lammps3d'"}
    assert [p.name for p in outcome.exports] == ["packing.vtu", "packing.data"]
    assert "x 2.0; walls on all six sides" in outcome.exports[1].read_text()


def test_a_2d_parameter_of_a_3d_scene_is_refused_before_packing(tmp_path) -> None:
    exports = [{"kind": "lammps", "thickness": 2.0}]
    with pytest.raises(ConfigError) as err:
        regopack.pack_and_summarise(
            {**scene3d(15.0), "outputs": {"exports": exports}}, out=tmp_path / "run"
        )
    assert str(err.value).endswith(
        "outputs.exports.0.thickness = 2.0: has no meaning for a 3D packing, only for 2D ones; "
        "its 3D parameters: spheres, youngs_modulus, poisson_ratio"
    )
    assert not (tmp_path / "run").exists()


def test_an_old_3d_exporter_name_in_a_2d_scene_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"outputs\.exports\.0 = 'gsd3d' is a 3D exporter, but "):
        with pytest.warns(DeprecatedNameWarning):
            regopack.scene("small", outputs__exports=["gsd3d"])


def test_an_old_3d_exporter_without_analyses_runs_in_a_scene_with_analyses(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # written against SolidExporter, whose runs never passed the analyses
    from pathlib import Path

    from pydantic import BaseModel

    from regopack.registry.hookspecs import hookimpl
    from regopack.registry.interfaces import Exporter
    from regopack.registry.plugin_types import ExporterSpec
    from regopack.testing import make_registry

    class NoConfig(BaseModel):
        pass

    class Counts(Exporter):  # type: ignore[type-arg]
        suffix = ".count"

        def __init__(self, config: NoConfig) -> None:
            pass

        def export(self, packing, path):  # type: ignore[no-untyped-def, override]
            Path(path).write_text(f"{packing.n_placed}\n")
            return Path(path)

    class Plugin:
        @hookimpl
        def regopack_exporters(self):  # type: ignore[no-untyped-def]
            return [ExporterSpec("counts", NoConfig, Counts, dimensions=(3,))]

    outputs = {"exports": ["counts"], "analyses": ["coordination"]}
    scene = regopack.scene({**scene3d(15.0), "outputs": outputs}, registry=make_registry(Plugin()))
    outcome = regopack.pack_and_summarise(scene, out=tmp_path / "run", verify=False)
    assert [p.name for p in outcome.exports] == ["packing.count"]
    assert int(outcome.exports[0].read_text()) == outcome.packing.n_placed


def test_the_old_3d_exporter_names_of_the_flat_layout_still_import() -> None:
    import importlib

    from regopack.plugins.exporters.gsd_export import GsdExporter
    from regopack.plugins.exporters.lammps_export import LammpsExporter, polyhedron_bodies
    from regopack.plugins.exporters.vtk_export import VtkExporter

    with pytest.warns(DeprecationWarning):
        old = importlib.import_module("regopack.plugins.lammps3d_export")
    for name, new in (("Lammps3dExporter", LammpsExporter), ("lammps3d_bodies", polyhedron_bodies)):
        with pytest.warns(DeprecationWarning, match=f"{name} is deprecated"):
            assert getattr(old, name) is new
    package = importlib.import_module("regopack.plugins.exporters")
    for name, new in (("Vtk3dExporter", VtkExporter), ("Gsd3dExporter", GsdExporter)):
        with pytest.warns(DeprecationWarning, match=f"{name} is deprecated"):
            assert getattr(package, name) is new
