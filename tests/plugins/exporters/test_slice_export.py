"""The ``slice`` export: a section of a 3D packing is a 2D packing that 2D tools accept."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import shapely
from cli_helpers import one_error_line
from packings3d import cube_and_sphere, packing3d

from regopack.base.errors import ConfigError
from regopack.base.units import reference_diameter
from regopack.cli import main
from regopack.geometry.domain import Box
from regopack.packing.core import Packing, load, save
from regopack.plugins.exporters.slice_export import SliceConfig, slice_packing
from regopack.verification.polygons import verify


@pytest.fixture(scope="module")
def packing() -> Packing:
    return packing3d()


@pytest.fixture(scope="module")
def packing_file(packing, tmp_path_factory):  # type: ignore[no-untyped-def]
    path = tmp_path_factory.mktemp("slice") / "packing.npz"
    save(packing, path)
    return path


def exact_cut_area(packing: Packing, j: int, axis: int, at: float) -> float:
    """Area of the cut of solid ``j`` by ``x[axis] = at``, from shapely's hull of the crossings."""
    pts = packing.world_vertices(j)
    _, loops = packing.solids.solid(j)
    pairs = (zip(loop, np.roll(loop, -1), strict=True) for loop in loops)
    edges = {(min(a, b), max(a, b)) for pair in pairs for a, b in pair}
    cuts = []
    for a, b in edges:
        sa, sb = pts[a, axis] - at, pts[b, axis] - at
        if (sa < 0) != (sb < 0):
            cuts.append(pts[a] + sa / (sa - sb) * (pts[b] - pts[a]))
    keep = [k for k in range(3) if k != axis]
    return float(shapely.MultiPoint(np.array(cuts)[:, keep]).convex_hull.area) if cuts else 0.0


def test_the_section_is_a_valid_2d_packing_of_the_cuts(packing) -> None:  # type: ignore[no-untyped-def]
    section = slice_packing(packing)
    box = packing.domain
    at = 0.5 * (box.zmin + box.zmax)
    assert section.domain.bounds().tolist() == [box.xmin, box.xmax, box.ymin, box.ymax]
    assert section.n_placed == section.n_particles > 5
    assert verify(section).ok  # no overlap, nothing outside the rectangle
    solids = section.scene["slice"]["solids"]
    order = packing.insertion_index[solids]
    assert np.all(np.diff(order) > 0)  # in the order the solids were inserted
    np.testing.assert_array_equal(section.mineral, packing.mineral[solids])
    assert section.mineral_names == packing.mineral_names
    areas = section.area()
    np.testing.assert_allclose(np.pi * section.radius**2, areas, rtol=1e-12)
    for k, j in enumerate(solids):
        assert areas[k] == pytest.approx(exact_cut_area(packing, j, 2, at), rel=1e-9)
    cut = {
        int(j)
        for j in np.flatnonzero(packing.placed)
        if exact_cut_area(packing, int(j), 2, at) > 1e-12 * 400
    }
    assert set(solids) == cut
    assert section.stats["slice_phi"] == pytest.approx(areas.sum() / section.domain.area)
    assert section.stats["interior_margin"] == 12.0 and "size" not in section.scene
    # the 3D d_min, not the smallest cut, scales the section's default lengths
    assert section.stats["reference_diameter"] == reference_diameter(packing)
    assert reference_diameter(section) == reference_diameter(packing)


@pytest.mark.parametrize(("axis", "keep"), [("x", (1, 2)), ("y", (0, 2)), ("z", (0, 1))])
def test_every_axis_uses_the_two_other_coordinates(packing, axis, keep) -> None:  # type: ignore[no-untyped-def]
    b = packing.domain.bounds() + [-1.0, 2.0, -3.0, 4.0, -5.0, 6.0]  # a box of three sides
    wide = dataclasses.replace(packing, domain=Box(*b))
    section = slice_packing(wide, SliceConfig(axis=axis, at=3.0))
    b = b.reshape(3, 2)
    assert section.domain.bounds().tolist() == [*b[keep[0]], *b[keep[1]]]
    assert verify(section).ok
    a = "xyz".index(axis)
    for k, j in enumerate(section.scene["slice"]["solids"]):
        want = exact_cut_area(wide, j, a, 3.0)
        assert section.area()[k] == pytest.approx(want, rel=1e-9)
        centroid = shapely.Polygon(section.polygon(k)).centroid
        cut = packing.world_vertices(j)[:, keep]
        assert cut.min(axis=0)[0] <= centroid.x <= cut.max(axis=0)[0]
        assert cut.min(axis=0)[1] <= centroid.y <= cut.max(axis=0)[1]


def test_a_plane_outside_the_box_is_one_error(packing, packing_file, capsys) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match=r"^exporter 'slice': at = 30: outside the box along z"):
        slice_packing(packing, SliceConfig(at=30.0))
    assert main(["export", str(packing_file), "--to", "slice", "--set", "at=30"]) != 0
    assert one_error_line(capsys) == (
        "regopack: error: --set: exporter 'slice': at = 30: outside the box along z, which "
        "spans -10 to 10; give a value between them"
    )
    assert main(["export", str(packing_file), "--to", "slice", "--set", "axis=w"]) != 0
    assert "--set: exporter 'slice': axis = \"w\": Input should be 'x', 'y' or 'z'" in (
        one_error_line(capsys)
    )


def test_a_sphere_is_cut_as_a_circle() -> None:
    section = slice_packing(cube_and_sphere(), SliceConfig(axis="z", at=3.5))
    assert section.n_particles == 2
    assert section.area()[0] == pytest.approx(4.0)
    assert section.area()[1] == pytest.approx(np.pi * 0.75, rel=2e-3)  # a 64-gon


def test_the_command_writes_a_section_that_analyze_and_2d_exports_read(  # type: ignore[no-untyped-def]
    packing_file, tmp_path, capsys
) -> None:
    out = tmp_path / "cut.npz"
    assert main(["export", str(packing_file), "--to", "slice", "--set", "fraction=0.4"]) == 0
    default = packing_file.with_name("packing.slice.npz")
    assert capsys.readouterr().out.strip() == f"wrote {default}"
    assert default.with_suffix(".png").stat().st_size > 10_000
    assert main(["export", str(packing_file), "--to", "slice", "--out", str(out)]) == 0
    section = load(out)
    assert section.stats["slice_at"] == 0.0 and section.scene["slice"]["axis"] == "z"
    capsys.readouterr()
    folder = tmp_path / "analysis"
    assert main(["analyze", str(out), "--out", str(folder), "--no-figures"]) == 0
    report = json.loads((folder / "analysis.json").read_text())
    assert report["n_placed"] == section.n_placed
    assert {"density", "contacts", "coordination", "rdf", "network"} <= set(report)
    assert main(["export", str(out), "--to", "svg", "--out", str(tmp_path / "cut.svg")]) == 0
    assert (tmp_path / "cut.svg").read_text().count("<polygon") == section.n_placed


def test_a_2d_exporter_is_refused_in_one_line(packing_file, capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["export", str(packing_file), "--to", "svg"]) != 0
    line = one_error_line(capsys)
    assert line == (
        f"regopack: error: {packing_file}: exporter 'svg' writes 2D packings, and this is a "
        "3D packing; 3D exporters: gsd, image, lammps, liggghts, slice, stl, vtk, yade"
    )


def test_a_2d_packing_is_refused_by_a_3d_exporter(packing_file, tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "cut.npz"
    assert main(["export", str(packing_file), "--to", "slice", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["export", str(out), "--to", "stl"]) != 0
    line = one_error_line(capsys)
    assert line.startswith(f"regopack: error: {out}: exporter 'stl' writes 3D packings, and this")
    assert line.endswith("2D exporters: csv, gsd, image, json, lammps, svg, vtk")
    assert not out.with_suffix(".stl").exists()
