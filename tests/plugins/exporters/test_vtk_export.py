"""The ``vtk`` export of 3D packings, read back by VTK: cells, data arrays, volumes, normals.

The 2D PolyData is tested with the other 2D formats in ``test_exporters.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from packings3d import packing3d

from regopack.packing.core import Packing
from regopack.plugins.exporters.vtk_export import VTK_POLYHEDRON, VtkExporter

vtk = pytest.importorskip("vtk", reason="the vtk package is not installed")
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402


@pytest.fixture(scope="module")
def packing() -> Packing:
    return packing3d()


@pytest.fixture(scope="module")
def grid(packing, tmp_path_factory):  # type: ignore[no-untyped-def]
    path = VtkExporter().export(packing, tmp_path_factory.mktemp("vtk") / "p.vtu")
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def _surface(grid):  # type: ignore[no-untyped-def]
    """The outer faces of every cell as VTK extracts them, in triangles, with their cell."""
    surface = vtk.vtkGeometryFilter()
    surface.SetInputData(grid)
    surface.PassThroughCellIdsOn()
    triangles = vtk.vtkTriangleFilter()
    triangles.SetInputConnection(surface.GetOutputPort())
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputConnection(triangles.GetOutputPort())
    normals.ComputeCellNormalsOn()
    normals.ConsistencyOff()
    normals.AutoOrientNormalsOff()
    normals.SplittingOff()
    normals.Update()
    return normals.GetOutput()


def test_one_polyhedron_cell_per_placed_particle_with_its_data(packing, grid) -> None:  # type: ignore[no-untyped-def]
    idx = np.flatnonzero(packing.placed)
    assert grid.GetNumberOfCells() == packing.n_placed > 30
    assert {grid.GetCellType(i) for i in range(grid.GetNumberOfCells())} == {VTK_POLYHEDRON}
    data = grid.GetCellData()
    names = [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
    assert names == ["index", "mineral", "equivalent_diameter", "volume", "insertion_index"]
    column = {name: vtk_to_numpy(data.GetArray(name)) for name in names}
    np.testing.assert_array_equal(column["index"], idx)
    np.testing.assert_array_equal(column["mineral"], packing.mineral[idx])
    np.testing.assert_array_equal(column["insertion_index"], packing.insertion_index[idx])
    np.testing.assert_allclose(column["equivalent_diameter"], 2 * packing.radius[idx], rtol=1e-15)
    np.testing.assert_allclose(column["volume"], packing.solids.volume[idx], rtol=1e-12)
    names_array = grid.GetFieldData().GetAbstractArray("mineral_names")
    read = [names_array.GetValue(i) for i in range(names_array.GetNumberOfValues())]
    assert read == list(packing.mineral_names)


def test_vtk_computes_every_particle_volume(packing, grid) -> None:  # type: ignore[no-untyped-def]
    sizes = vtk.vtkCellSizeFilter()
    sizes.SetInputData(grid)
    sizes.ComputeVolumeOn()
    sizes.Update()
    volume = vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Volume"))
    want = packing.solids.volume[packing.placed]
    np.testing.assert_allclose(volume, want, rtol=1e-9)
    assert abs(want - 4 / 3 * np.pi * packing.radius[packing.placed] ** 3).max() < 1e-9 * want.max()


def test_every_face_is_outward_and_every_cell_closed(packing, grid) -> None:  # type: ignore[no-untyped-def]
    idx = np.flatnonzero(packing.placed)
    surface = _surface(grid)
    mass = vtk.vtkMassProperties()
    mass.SetInputData(surface)
    mass.Update()
    assert mass.GetVolume() == pytest.approx(packing.solids.volume[idx].sum(), rel=1e-9)
    n = vtk_to_numpy(surface.GetCellData().GetNormals())
    cell = vtk_to_numpy(surface.GetCellData().GetArray("vtkOriginalCellIds"))
    points = vtk_to_numpy(surface.GetPoints().GetData())
    tri = vtk_to_numpy(surface.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    away = points[tri].mean(axis=1) - packing.centre[idx[cell]]
    inward = np.einsum("ij,ij->i", n, away) <= 0
    assert not inward.any(), f"inward faces on particles {sorted(set(idx[cell[inward]]))}"
    assert set(cell.tolist()) == set(range(idx.size))
    edges = vtk.vtkFeatureEdges()
    edges.SetInputData(surface)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    assert edges.GetOutput().GetNumberOfCells() == 0  # closed: no open or repeated edge


def test_points_are_the_world_vertices(packing, grid) -> None:  # type: ignore[no-untyped-def]
    points = vtk_to_numpy(grid.GetPoints().GetData())
    want = np.concatenate([packing.world_vertices(int(j)) for j in np.flatnonzero(packing.placed)])
    np.testing.assert_array_equal(points, want)
