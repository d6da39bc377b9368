"""``regopack export`` with the built-in exporters."""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

pytest.importorskip("regopack.plugins.inserters.available_arc")

from cli_helpers import one_error_line

from regopack.base.errors import DeprecatedNameWarning
from regopack.cli import main
from regopack.packing.core import load, save
from regopack.plugins.exporters import read_csv, read_json
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene


@pytest.fixture(scope="module")
def packing_file(tmp_path_factory):
    scene = resolve_scene(load_scene("small", ["count=60"]), default_registry(autoload=False))
    path = tmp_path_factory.mktemp("run") / "packing.npz"
    save(run_scene(scene).packing, path)
    return path


@pytest.mark.parametrize(
    ("fmt", "suffix"),
    [("csv", ".csv"), ("json", ".json"), ("svg", ".svg"), ("vtk", ".vtp"), ("lammps", ".data")],
)
def test_each_format_writes_its_file(packing_file, tmp_path, capsys, fmt, suffix):
    assert main(["export", str(packing_file), "--to", fmt, "--out", str(tmp_path)]) == 0
    path = tmp_path / f"packing{suffix}"
    assert path.exists()
    assert capsys.readouterr().out.strip() == f"wrote {path}"


def test_default_output_is_beside_the_packing(packing_file):
    assert main(["export", str(packing_file), "--to", "json"]) == 0
    packing = load(packing_file)
    back = read_json(packing_file.with_suffix(".json"))
    assert np.array_equal(back.vertices, packing.vertices)


def test_csv_round_trip_from_the_command_line(packing_file, tmp_path):
    out = tmp_path / "table.csv"
    assert main(["export", str(packing_file), "--to", "csv", "--out", str(out)]) == 0
    packing, back = load(packing_file), read_csv(out)
    for name in ("centre", "vertices", "radius", "orientation", "mineral", "offsets"):
        assert np.array_equal(getattr(back, name), getattr(packing, name), equal_nan=True)


def test_parameters_and_analyses(packing_file, tmp_path):
    out = tmp_path / "p.vtp"
    args = ["export", str(packing_file), "--to", "vtk", "--out", str(out)]
    assert main([*args, "--analyses", "coordination"]) == 0
    names = [a.attrib["Name"] for a in ET.parse(out).getroot().iter("DataArray")]
    assert "Z" in names
    svg = tmp_path / "p.svg"
    assert main(["export", str(packing_file), "--to", "svg", "--out", str(svg)]) == 0
    assert main([*args[:2], "--to", "svg", "--set", "width_px=300", "--out", str(svg)]) == 0
    assert ET.parse(svg).getroot().attrib["width"] == "300"


def test_a_companion_of_the_users_is_not_overwritten(packing_file, tmp_path, capsys):
    """mine_vertices.csv is the user's while mine.csv does not exist: one line, unless --force."""
    mine = tmp_path / "mine_vertices.csv"
    mine.write_text("the user's own table\n")
    args = ["export", str(packing_file), "--to", "csv", "--out", str(tmp_path / "mine.csv")]
    assert main(args) == 2
    line = one_error_line(capsys)
    assert "mine_vertices.csv: exists" in line and "--force" in line
    assert mine.read_text() == "the user's own table\n"
    assert not (tmp_path / "mine.csv").exists()
    assert main([*args, "--force"]) == 0
    capsys.readouterr()
    assert mine.read_text() != "the user's own table\n"
    assert main(args) == 0  # the earlier export's own files: written again
    assert "wrote" in capsys.readouterr().out


def test_unknown_format_is_one_line(packing_file, capsys):
    assert main(["export", str(packing_file), "--to", "xyz"]) == 2
    line = one_error_line(capsys)
    assert "unknown export kind 'xyz'" in line and "csv, gsd, image, json, lammps" in line


def test_unwritable_path_is_one_line(packing_file, tmp_path, capsys):
    out = tmp_path / "missing" / "dir" / "p.svg"
    assert main(["export", str(packing_file), "--to", "svg", "--out", str(out)]) == 2
    assert "cannot write" in one_error_line(capsys)


def test_bad_parameter_is_one_line(packing_file, capsys):
    assert main(["export", str(packing_file), "--to", "lammps", "--set", "density=-1"]) == 2
    assert "density" in one_error_line(capsys)


def test_missing_format_is_a_usage_error(packing_file, capsys):
    assert main(["export", str(packing_file)]) == 2
    assert "--to" in one_error_line(capsys)


def test_scene_exports_are_written_beside_the_packing(tmp_path, capsys):
    out = tmp_path / "run"
    args = ["run", "small", "--set", "count=40", "--out", str(out)]
    args += ["--set", 'outputs.analyses=["coordination"]']
    args += ["--set", 'outputs.exports=["vtk", {kind = "svg", width_px = 200}]']
    assert main(args) == 0
    assert "│ export " in capsys.readouterr().out
    names = [a.attrib["Name"] for a in ET.parse(out / "packing.vtp").getroot().iter("DataArray")]
    assert "Z" in names
    assert ET.parse(out / "packing.svg").getroot().attrib["width"] == "200"
    scene = load(out / "packing.npz").scene
    assert scene["outputs"]["exports"] == ["vtk", {"kind": "svg", **_svg_defaults(200)}]


def _svg_defaults(width_px: int) -> dict:
    from regopack.plugins.exporters import SvgConfig

    return SvgConfig(width_px=width_px).model_dump()


def test_unknown_scene_export_is_one_line(tmp_path, capsys):
    args = ["run", "small", "--set", 'outputs.exports=["xyz"]', "--out", str(tmp_path)]
    assert main(args) == 2
    assert "outputs.exports.0: unknown export kind 'xyz'" in one_error_line(capsys)


def test_the_schema_lists_the_exporters():
    from regopack.scenes.schema import scene_schema

    registry = default_registry(autoload=False)
    exports = scene_schema(registry)["$defs"]["Outputs"]["properties"]["exports"]
    by_name, by_table = exports["items"]["anyOf"]
    old = ["gsd3d", "lammps3d", "vtk3d"]  # deprecated names still accepted
    assert by_name["enum"] == [*registry.names("export"), *old]
    assert by_table["properties"]["kind"]["enum"] == [*registry.names("export"), *old]


# ---------------------------------------------------------------------------
# exporters of both dimensions


@pytest.fixture(scope="module")
def packing3d_file(tmp_path_factory):
    from packings3d import packing3d

    path = tmp_path_factory.mktemp("run3d") / "packing.npz"
    save(packing3d(), path)
    return path


@pytest.mark.parametrize(("fmt", "suffix"), [("vtk", ".vtu"), ("lammps", ".data"), ("gsd", ".gsd")])
def test_an_exporter_of_both_dimensions_names_the_3d_file_by_its_suffix(
    packing3d_file, tmp_path, capsys, fmt, suffix
):
    if fmt == "gsd":
        pytest.importorskip("gsd.hoomd", reason="the gsd package is not installed")
    assert main(["export", str(packing3d_file), "--to", fmt, "--out", str(tmp_path)]) == 0
    path = tmp_path / f"packing{suffix}"
    assert capsys.readouterr().out.strip() == f"wrote {path}"
    assert [p.name for p in tmp_path.iterdir() if p.suffix != ".in"] == [path.name]


def test_vtk_writes_beside_a_3d_packing_an_unstructured_grid(packing3d_file, capsys):
    assert main(["export", str(packing3d_file), "--to", "vtk"]) == 0
    path = packing3d_file.with_suffix(".vtu")
    assert capsys.readouterr().out.strip() == f"wrote {path}"
    assert 'type="UnstructuredGrid"' in path.read_text()
    assert not packing3d_file.with_suffix(".vtp").exists()


@pytest.mark.parametrize("fmt", ["lammps", "lammps3d"])
def test_a_2d_parameter_for_a_3d_packing_is_one_line(packing3d_file, tmp_path, capsys, fmt):
    args = ["export", str(packing3d_file), "--to", fmt, "--out", str(tmp_path)]
    assert main([*args, "--set", "thickness=2"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[-1] == (
        f"regopack: error: --set: exporter {fmt!r}: thickness = 2.0: has no meaning for a 3D "
        "packing, only for 2D ones; its 3D parameters: spheres, youngs_modulus, poisson_ratio"
    )
    said = [line.split(" is deprecated")[0] for line in lines[:-1]]
    assert said == ([] if fmt == "lammps" else ["regopack: warning: the export kind 'lammps3d'"])
    assert not list(tmp_path.iterdir())


def test_an_old_3d_name_keeps_its_dimension(packing_file, tmp_path, capsys):
    out = tmp_path / "p.vtp"
    assert main(["export", str(packing_file), "--to", "vtk3d", "--out", str(out)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[-1] == (
        f"regopack: error: {packing_file}: exporter 'vtk3d' writes 3D packings, and this is a "
        "2D packing; 2D exporters: csv, gsd, image, json, lammps, svg, vtk"
    )
    assert not out.exists()


@pytest.mark.parametrize(
    ("old", "new"), [("vtk3d", "vtk"), ("gsd3d", "gsd"), ("lammps3d", "lammps")]
)
def test_an_old_3d_name_warns_and_writes_the_same_files(packing3d_file, tmp_path, old, new):
    import regopack

    if new == "gsd":
        pytest.importorskip("gsd.hoomd", reason="the gsd package is not installed")
    params = {} if new == "vtk" else {"density": 2.5}  # the old name's parameters
    for name in (old, new):
        (tmp_path / name).mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecatedNameWarning)
        regopack.export(packing3d_file, new, tmp_path / new, **params)
    with pytest.warns(DeprecatedNameWarning, match=rf"kind '{old}' is deprecated.*use '{new}'"):
        regopack.export(packing3d_file, old, tmp_path / old, **params)
    files = {p.name: p.read_bytes() for p in (tmp_path / new).iterdir()}
    assert len(files) == (2 if new == "lammps" else 1)
    assert {p.name: p.read_bytes() for p in (tmp_path / old).iterdir()} == files


def test_the_exporter_name_as_a_prefix_is_accepted_once(packing_file, tmp_path, capsys):
    # as analyze takes psd.tolerance: lammps.steps is lammps' steps
    out = tmp_path / "p.data"
    args = ["export", str(packing_file), "--to", "lammps", "--out", str(out)]
    assert main([*args, "--set", "lammps.steps=5"]) == 0
    assert "variable steps index 5" in out.with_suffix(".in").read_text()
    capsys.readouterr()
    assert main([*args, "--force", "--set", "lammps.steps=5", "--set", "steps=6"]) == 2
    assert "steps given twice, as lammps.steps and as steps" in one_error_line(capsys)
    assert main([*args, "--force", "--set", "lammps.stepz=5"]) == 2
    assert "stepz = 5: unknown field; did you mean 'steps'?" in one_error_line(capsys)
