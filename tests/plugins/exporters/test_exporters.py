"""The built-in exporters: exact round trips, well-formed files, real readers."""

from __future__ import annotations

import dataclasses
import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from regopack.analysis.pipeline import run_analyses
from regopack.base.colours import mineral_colours
from regopack.base.errors import ExportError
from regopack.exports.pipeline import build_exporter, export_packing, output_path
from regopack.packing.core import Packing, load, save
from regopack.plugins.exporters import (
    CsvExporter,
    JsonConfig,
    JsonExporter,
    SvgExporter,
    VtkExporter,
    companion_paths,
    polygon_moments,
    read_csv,
    read_json,
)
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

SVG = "{http://www.w3.org/2000/svg}"
ARRAYS = ("radius", "mineral", "vertices", "offsets", "orientation", "centre", "insertion_index")


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def packing(registry) -> Packing:
    """A small run with one particle marked as not placed and a NaN statistic."""
    scene = resolve_scene(load_scene("small", ["count=80"]), registry)
    p = run_scene(scene).packing
    centre = p.centre.copy()
    insertion_index = p.insertion_index.copy()
    last = int(np.argmax(insertion_index))
    centre[last] = np.nan
    insertion_index[last] = -1
    stats = {**p.stats, "undefined": math.nan}
    return dataclasses.replace(p, centre=centre, insertion_index=insertion_index, stats=stats)


def same_value(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def assert_identical(a: Packing, b: Packing) -> None:
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert np.array_equal(x, y, equal_nan=True), name
        assert np.array_equal(np.signbit(x), np.signbit(y)), name
    assert a.mineral_names == b.mineral_names
    assert a.domain == b.domain
    assert json.dumps(a.scene, sort_keys=True) == json.dumps(b.scene, sort_keys=True)
    assert (a.seed, a.version) == (b.seed, b.version)
    assert a.stats.keys() == b.stats.keys()
    assert all(same_value(a.stats[k], b.stats[k]) for k in a.stats), (a.stats, b.stats)


def test_the_fixture_has_placed_and_unplaced_particles(packing):
    assert 0 < packing.n_placed < packing.n_particles


# ---------------------------------------------------------------------------
# round trips


def test_csv_round_trip_is_exact(packing, tmp_path):
    path = CsvExporter().export(packing, tmp_path / "p.csv")
    vertices, meta = companion_paths(path)
    assert vertices.exists() and meta.exists()
    assert_identical(read_csv(path), packing)


def test_csv_tables(packing, tmp_path):
    path = CsvExporter().export(packing, tmp_path / "p.csv")
    lines = path.read_text().splitlines()
    assert lines[0] == "index,placed,insertion_index,mineral,radius,orientation,cx,cy,n_vertices"
    assert len(lines) == packing.n_particles + 1
    first = lines[1].split(",")
    assert first[3] == packing.mineral_names[packing.mineral[0]]
    assert float(first[4]) == packing.radius[0]
    vlines = companion_paths(path)[0].read_text().splitlines()
    assert vlines[0] == "particle,vertex,x,y"
    assert len(vlines) == packing.vertices.shape[0] + 1
    meta = json.loads(companion_paths(path)[1].read_text())
    assert {"domain", "scene", "seed", "version", "mineral_names"} <= set(meta)


def test_json_round_trip_is_exact(packing, tmp_path):
    path = JsonExporter().export(packing, tmp_path / "p.json")
    assert_identical(read_json(path), packing)
    assert len(path.read_text().splitlines()) == 1


def test_json_indent_and_contents(packing, tmp_path):
    path = JsonExporter(JsonConfig(indent=2)).export(packing, tmp_path / "p.json")
    doc = json.loads(path.read_text())
    assert len(doc["particles"]) == packing.n_particles
    unplaced = [p for p in doc["particles"] if not p["placed"]]
    assert len(unplaced) == 1 and unplaced[0]["centre"] == [None, None]
    assert_identical(read_json(path), packing)


def test_round_trip_through_the_packing_file(packing, tmp_path):
    save(packing, tmp_path / "p.npz")
    loaded = load(tmp_path / "p.npz")
    assert_identical(read_json(JsonExporter().export(loaded, tmp_path / "p.json")), loaded)


def test_readers_reject_other_files(tmp_path):
    other = tmp_path / "other.json"
    other.write_text('{"format": "something"}')
    with pytest.raises(ExportError, match="not a regopack json export"):
        read_json(other)
    with pytest.raises(ExportError, match="metadata"):
        read_csv(tmp_path / "missing.csv")


# ---------------------------------------------------------------------------
# SVG


def test_svg_is_well_formed_with_one_polygon_per_placed_particle(packing, tmp_path):
    path = SvgExporter().export(packing, tmp_path / "p.svg")
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG}svg"
    d = packing.domain
    assert [float(v) for v in root.attrib["viewBox"].split()] == pytest.approx(
        [d.xmin, -d.ymax, d.xmax - d.xmin, d.ymax - d.ymin]
    )
    polygons = root.findall(f".//{SVG}polygon")
    assert len(polygons) == packing.n_placed
    assert sorted(int(p.attrib["data-index"]) for p in polygons) == list(
        np.flatnonzero(packing.placed)
    )
    assert root.find(f".//{SVG}rect") is not None
    groups = root.findall(f".//{SVG}g[@class='mineral']")
    for g in groups:
        k = int(g.attrib["id"].removeprefix("mineral-"))
        assert g.attrib["fill"] == mineral_colours(packing.mineral_names)[k]
        assert g.attrib["data-mineral"] == packing.mineral_names[k]
    assert "scale(1,-1)" in root.find(f"{SVG}g").attrib["transform"]


# ---------------------------------------------------------------------------
# VTK


def vtk_cells(path: Path) -> dict:
    root = ET.parse(path).getroot()
    piece = root.find("PolyData/Piece")
    assert piece is not None
    arrays = {a.attrib["Name"]: a.text.split() for a in piece.iter("DataArray")}
    return {"piece": piece.attrib, "arrays": arrays}


def test_vtk_cell_counts_and_data(packing, tmp_path):
    path = VtkExporter().export(packing, tmp_path / "p.vtp")
    found = vtk_cells(path)
    placed = np.flatnonzero(packing.placed)
    assert int(found["piece"]["NumberOfPolys"]) == packing.n_placed
    assert int(found["piece"]["NumberOfPoints"]) == int(np.diff(packing.offsets)[placed].sum())
    arrays = found["arrays"]
    assert [int(v) for v in arrays["mineral"]] == packing.mineral[placed].tolist()
    assert [float(v) for v in arrays["radius"]] == packing.radius[placed].tolist()
    assert "Z" not in arrays


def test_vtk_adds_z_from_coordination(packing, registry, tmp_path):
    analyzers = run_analyses(packing, registry, [("coordination", {})])
    path = VtkExporter().export(packing, tmp_path / "p.vtp", analyses=analyzers)
    z = vtk_cells(path)["arrays"]["Z"]
    expected = analyzers["coordination"].per_particle[packing.placed]  # type: ignore[attr-defined]
    assert [int(v) for v in z] == expected.tolist()


def test_vtk_read_by_vtk(packing, tmp_path):
    xml = pytest.importorskip("vtkmodules.vtkIOXML", reason="the vtk package is not installed")
    support = pytest.importorskip("vtkmodules.util.numpy_support")
    path = VtkExporter().export(packing, tmp_path / "p.vtp")
    reader = xml.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    poly = reader.GetOutput()
    placed = np.flatnonzero(packing.placed)
    assert poly.GetNumberOfCells() == packing.n_placed
    points = support.vtk_to_numpy(poly.GetPoints().GetData())
    expected = np.concatenate(packing.polygons(placed))
    np.testing.assert_allclose(points[:, :2], expected, rtol=1e-12, atol=0)
    assert not points[:, 2].any()
    cells = poly.GetCellData()
    mineral = support.vtk_to_numpy(cells.GetArray("mineral"))
    radius = support.vtk_to_numpy(cells.GetArray("radius"))
    order = support.vtk_to_numpy(cells.GetArray("insertion_index"))
    assert mineral.tolist() == packing.mineral[placed].tolist()
    assert radius.tolist() == packing.radius[placed].tolist()
    assert order.tolist() == packing.insertion_index[placed].tolist()
    counts = [poly.GetCell(i).GetNumberOfPoints() for i in range(poly.GetNumberOfCells())]
    assert counts == np.diff(packing.offsets)[placed].tolist()


# ---------------------------------------------------------------------------
# LAMMPS


def test_polygon_moments_of_a_rectangle():
    rect = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]])
    area, c, ixx, iyy, ixy = polygon_moments(rect)
    assert area == 8.0 and c.tolist() == [2.0, 1.0]
    assert ixx == pytest.approx(4 * 2**3 / 12)
    assert iyy == pytest.approx(2 * 4**3 / 12)
    assert ixy == pytest.approx(0.0, abs=1e-12)
    sheared = rect @ np.array([[1.0, 0.5], [0.0, 1.0]])  # x y correlated
    assert polygon_moments(sheared)[4] > 0


# ---------------------------------------------------------------------------
# the core helpers


def test_export_packing_and_default_paths(packing, registry, tmp_path):
    exporter = build_exporter(registry, "vtk")
    assert output_path(exporter, tmp_path / "run" / "packing.npz").name == "packing.vtp"
    assert output_path(exporter, tmp_path / "x.npz", tmp_path) == tmp_path / "x.vtp"
    path = export_packing(packing, "json", tmp_path / "p.json", registry=registry)
    assert_identical(read_json(path), packing)


def test_unwritable_path_is_one_error(packing, registry, tmp_path):
    with pytest.raises(ExportError, match="cannot write"):
        export_packing(packing, "svg", tmp_path / "no" / "dir" / "p.svg", registry=registry)


@pytest.mark.parametrize("kind", ["csv", "json", "svg", "vtk", "lammps"])
def test_a_packing_with_nothing_placed(kind, registry, tmp_path):
    from regopack.testing import packing_from_polygons

    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    empty = packing_from_polygons([square, square], placed=[False, False])
    path = export_packing(empty, kind, tmp_path / f"p.{kind}", registry=registry)
    assert path.exists()
    if kind == "csv":
        assert_identical(read_csv(path), empty)
    if kind == "json":
        assert_identical(read_json(path), empty)
    if kind == "svg":
        assert ET.parse(path).getroot().findall(f".//{SVG}polygon") == []
    if kind == "vtk":
        assert vtk_cells(path)["piece"]["NumberOfPolys"] == "0"


def test_the_plugin_registers_each_format_module_under_its_name():
    from regopack.plugins import exporters
    from regopack.plugins.exporters import (
        csv_export,
        json_export,
        lammps_export,
        liggghts_export,
        slice_export,
        stl_export,
        svg_export,
        vtk_export,
        yade_export,
    )

    specs = list(exporters.regopack_exporters())
    assert [(s.name, s.config_model, s.factory, s.dimensions, s.aliases) for s in specs] == [
        ("csv", csv_export.CsvConfig, csv_export.CsvExporter, (2,), ()),
        ("json", json_export.JsonConfig, json_export.JsonExporter, (2,), ()),
        ("svg", svg_export.SvgConfig, svg_export.SvgExporter, (2,), ()),
        ("vtk", vtk_export.VtkConfig, vtk_export.VtkExporter, (2, 3), ("vtk3d",)),
        ("lammps", lammps_export.LammpsConfig, lammps_export.LammpsExporter, (2, 3), ("lammps3d",)),
        (
            "liggghts",
            liggghts_export.LiggghtsConfig,
            liggghts_export.LiggghtsExporter,
            (3,),
            (),
        ),
        ("yade", yade_export.YadeConfig, yade_export.YadeExporter, (3,), ()),
        ("stl", stl_export.StlConfig, stl_export.StlExporter, (3,), ()),
        ("slice", slice_export.SliceConfig, slice_export.SliceExporter, (3,), ()),
    ]


def test_vtk_records_the_length_unit_as_field_data(packing, tmp_path):
    from dataclasses import replace

    path = VtkExporter().export(packing, tmp_path / "p.vtp")
    assert "lengths in µm" in path.read_text()
    in_nm = replace(packing, scene={**packing.scene, "length_unit": "nm"})
    text = VtkExporter().export(in_nm, tmp_path / "q.vtp").read_text()
    assert "lengths in nm" in text
    assert (
        '<Array type="String" Name="length_unit" NumberOfTuples="1" format="ascii">\n110 109 0'
        in text
    )
