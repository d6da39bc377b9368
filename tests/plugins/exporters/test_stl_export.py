"""The ``stl`` export, read back by trimesh: triangle count, outward faces, the solid volume."""

from __future__ import annotations

import numpy as np
import pytest
from packings3d import packing3d

from regopack.packing.core import Packing
from regopack.plugins.exporters.stl_export import STL_RECORD, StlExporter, stl_triangles

trimesh = pytest.importorskip("trimesh", reason="trimesh is not installed")


@pytest.fixture(scope="module")
def packing() -> Packing:
    return packing3d()


@pytest.fixture(scope="module")
def mesh(packing, tmp_path_factory):  # type: ignore[no-untyped-def]
    path = StlExporter().export(packing, tmp_path_factory.mktemp("stl") / "p.stl")
    return trimesh.load(path, file_type="stl")


def test_the_file_is_binary_stl_with_one_triangle_per_fan_piece(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = StlExporter().export(packing, tmp_path / "p.stl")
    data = path.read_bytes()
    count = int(np.frombuffer(data[80:84], dtype="<u4")[0])
    sizes = np.diff(packing.face_vertex_offsets)
    owner = np.repeat(np.arange(packing.n_particles), np.diff(packing.face_offsets))
    want = int((sizes - 2)[packing.placed[owner]].sum())
    assert count == want and len(data) == 84 + 50 * want
    assert not data.startswith(b"solid")  # some readers take such a file for ASCII STL


def test_trimesh_reads_the_solid_volume_and_outward_normals(packing, mesh) -> None:  # type: ignore[no-untyped-def]
    volume = float(packing.solids.volume[packing.placed].sum())
    sizes = np.diff(packing.face_vertex_offsets)
    owner = np.repeat(np.arange(packing.n_particles), np.diff(packing.face_offsets))
    assert len(mesh.faces) == int((sizes - 2)[packing.placed[owner]].sum())
    assert mesh.volume == pytest.approx(volume, rel=1e-5)  # single-precision coordinates
    assert mesh.is_winding_consistent and mesh.is_watertight


def test_every_particle_is_one_closed_outward_body(packing, mesh) -> None:  # type: ignore[no-untyped-def]
    bodies = mesh.split(only_watertight=False)
    assert len(bodies) == packing.n_placed
    volumes = np.sort([b.volume for b in bodies])
    want = np.sort(packing.solids.volume[packing.placed])
    np.testing.assert_allclose(volumes, want, rtol=1e-4)  # a flipped body has a negative volume


def test_triangles_follow_the_particles_in_draw_order(packing) -> None:  # type: ignore[no-untyped-def]
    tris, owner = stl_triangles(packing)
    assert np.all(np.diff(owner) >= 0)
    assert set(owner.tolist()) == set(np.flatnonzero(packing.placed).tolist())
    centre = packing.centre[owner]
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(np.einsum("ij,ij->i", normal, tris.mean(axis=1) - centre) > 0)


def test_the_header_names_the_unit_and_unit_mm_converts(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from regopack.plugins.exporters.stl_export import StlConfig

    plain = StlExporter().export(packing, tmp_path / "a.stl").read_bytes()
    assert b", unit um, " in plain[:80]
    mm = StlExporter(StlConfig(unit="mm")).export(packing, tmp_path / "b.stl").read_bytes()
    assert b", unit mm, " in mm[:80]
    a = np.frombuffer(plain[84:], dtype=STL_RECORD)["vertices"]
    b = np.frombuffer(mm[84:], dtype=STL_RECORD)["vertices"]
    np.testing.assert_allclose(b, a.astype(np.float64) * 1e-3, rtol=1e-6)  # 40 µm is 0.04 mm


def test_a_scene_in_millimetres_is_written_in_millimetres(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from dataclasses import replace

    from regopack.plugins.exporters.stl_export import StlConfig

    in_mm = replace(packing, scene={**packing.scene, "length_unit": "mm"})
    own = StlExporter().export(in_mm, tmp_path / "a.stl").read_bytes()
    same = StlExporter(StlConfig(unit="mm")).export(in_mm, tmp_path / "b.stl").read_bytes()
    assert b", unit mm, " in own[:80] and own == same
    with pytest.raises(ValueError, match="not a length unit"):
        StlConfig(unit="inch")
