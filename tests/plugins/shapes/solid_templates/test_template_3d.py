"""The template-3d shape: contract, exact volumes and shapes, rotations, paths, errors, packing."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pydantic
import pytest
from stl_helpers import (
    CUBE,
    ICOSAHEDRON,
    ICOSAHEDRON_VOLUME,
    TETRAHEDRON,
    hull_triangles,
    hull_volume_and_centroid,
    l_prism_triangles,
    write_ascii,
    write_binary,
)

import regopack
from regopack.base.errors import ConfigError
from regopack.cli import main
from regopack.geometry.solids import sphere_volume
from regopack.plugins.shapes.polyhedra.rotations import quaternion_matrices
from regopack.plugins.shapes.solid_templates import templates as templates_module
from regopack.plugins.shapes.solid_templates.shape import TemplateSolid, TemplateSolidConfig
from regopack.registry.manager import default_registry
from regopack.testing import check_solid_generator

# (points, volume, centroid) of the meshes written by the tests
SOLIDS = {
    "cube": (CUBE, 1.0, np.full(3, 0.5)),
    "tetrahedron": (TETRAHEDRON, 1.0 / 6.0, np.full(3, 0.25)),
    "icosahedron": (ICOSAHEDRON, ICOSAHEDRON_VOLUME, np.zeros(3)),
}


def template(path: Path | str, choice: str = "random") -> TemplateSolid:
    return TemplateSolid(TemplateSolidConfig(path=str(path), choice=choice))  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def grains(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of the three solids (binary), the L prism (ASCII) and a file of another type."""
    folder = tmp_path_factory.mktemp("grains")
    for name, (points, _, _) in SOLIDS.items():
        write_binary(folder / f"{name}.stl", hull_triangles(points))
    write_ascii(folder / "l-prism.STL", l_prism_triangles())
    (folder / "notes.txt").write_text("not a mesh\n")
    return folder


def test_the_contract_holds(grains: Path) -> None:
    check_solid_generator(template(grains))
    check_solid_generator(template(grains, "cycle"), seed=7)


@pytest.mark.parametrize("name", list(SOLIDS))
@pytest.mark.parametrize("fmt", ["binary", "ascii"])
def test_volumes_and_shapes_are_exact(tmp_path: Path, name: str, fmt: str) -> None:
    points, volume, centroid = SOLIDS[name]
    mesh = points * 3.0 + 11.0
    if fmt == "binary":  # the file holds float32 numbers: compare with those
        path = write_binary(tmp_path / f"{name}.stl", hull_triangles(mesh))
        mesh = mesh.astype(np.float32).astype(np.float64)
        volume, centroid = hull_volume_and_centroid(mesh)
    else:
        path = write_ascii(tmp_path / f"{name}.stl", hull_triangles(mesh))
        volume, centroid = volume * 27.0, centroid * 3.0 + 11.0
    qhull_volume, qhull_centroid = hull_volume_and_centroid(mesh)
    assert volume == pytest.approx(qhull_volume, rel=1e-12)
    assert np.allclose(centroid, qhull_centroid, rtol=1e-12, atol=1e-12)
    r = np.array([1e-6, 0.5, 1.0, 7.0, 1e6])
    batch = template(path).generate(r, np.random.default_rng(5))
    assert batch.volume == pytest.approx(sphere_volume(r), rel=1e-9)
    # turned back and scaled back, each particle is the mesh about its volume centroid
    rot = quaternion_matrices(batch.rotation)
    expected = mesh[np.lexsort(np.round(mesh, 6).T)]
    for j in range(len(r)):
        verts, _ = batch.solid(j)
        scale = r[j] * (4.0 / 3.0 * math.pi / volume) ** (1.0 / 3.0)
        back = verts @ rot[j] / scale + centroid
        assert np.allclose(back[np.lexsort(np.round(back, 6).T)], expected, rtol=1e-12, atol=0)


def test_a_non_convex_mesh_gives_its_hull(grains: Path) -> None:
    batch = template(grains / "l-prism.STL").generate(np.ones(3), np.random.default_rng(0))
    for j in range(3):
        verts, loops = batch.solid(j)
        assert len(verts) == 10 and len(loops) == 7  # the notch's two corners are gone
    assert batch.volume == pytest.approx(sphere_volume(np.ones(3)), rel=1e-12)


def test_scaling_over_twelve_decades(grains: Path) -> None:
    r = np.geomspace(1e-6, 1e6, 61)
    gen = template(grains)
    batch = check_solid_generator(gen, radii=r, rtol=1e-9)
    circum = batch.circumradius / r
    assert np.all((circum > 1.0) & (circum < 3.0))  # the shape does not depend on the size


def test_same_seed_same_solids_bit_for_bit(grains: Path) -> None:
    r = np.random.default_rng(1).uniform(0.1, 10.0, 300)
    a = template(grains).generate(r, np.random.default_rng(42))
    b = template(grains).generate(r, np.random.default_rng(42))
    c = template(grains).generate(r, np.random.default_rng(43))
    for field in ("vertices", "offsets", "face_vertices", "face_vertex_offsets", "face_offsets",
                  "normals", "support", "rotation"):  # fmt: skip
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert not np.array_equal(a.rotation, c.rotation)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_rotations_are_uniform(tmp_path: Path, seed: int) -> None:
    # a tetrahedron's vertex direction, turned, must be uniform on the sphere
    path = write_binary(tmp_path / "t.stl", hull_triangles(TETRAHEDRON))
    n = 20_000
    batch = template(path).generate(np.ones(n), np.random.default_rng(seed))
    rot = quaternion_matrices(batch.rotation)
    for axis in np.eye(3):
        d = rot @ axis  # R e
        assert np.all(np.abs(d.mean(axis=0)) < 0.03)  # 7 standard errors
        # z-component uniform on [-1, 1] (Archimedes): chi-square over 20 bins, 19 dof
        counts = np.histogram(d[:, 2], bins=20, range=(-1.0, 1.0))[0]
        chi2 = float(np.sum((counts - n / 20) ** 2 / (n / 20)))
        assert chi2 < 60.0  # p < 1e-5 for a uniform sample
    # the vertices are turned by the stored rotation (not only the quaternion is random)
    v0 = batch.vertices[batch.offsets[:-1]]  # each particle's first vertex
    ref = batch.solid(0)[0][0] @ rot[0]  # in the template's frame
    assert np.allclose(v0, rot @ ref, atol=1e-12)


def test_choice_cycle_and_random(grains: Path) -> None:
    counts = {8: "cube", 4: "tetrahedron", 12: "icosahedron", 10: "l-prism"}
    cycle = template(grains, "cycle").generate(np.ones(9), np.random.default_rng(0))
    names = [counts[int(k)] for k in np.diff(cycle.offsets)]
    # sorted paths: cube, icosahedron, l-prism.STL, tetrahedron (notes.txt is not a mesh)
    assert names == ["cube", "icosahedron", "l-prism", "tetrahedron"] * 2 + ["cube"]
    rand = template(grains).generate(np.ones(4000), np.random.default_rng(0))
    seen = np.unique(np.diff(rand.offsets), return_counts=True)[1]
    assert len(seen) == 4 and np.all(np.abs(seen - 1000) < 150)


def test_paths_file_folder_and_pattern(grains: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(grains.parent)
    rel = grains.name
    assert len(template(f"{rel}/cube.stl").templates) == 1
    assert len(template(rel).templates) == 4
    assert len(template(f"{rel}/*").templates) == 4  # notes.txt is not taken
    assert template(f"{rel}/[ct]*.stl").templates.names == (
        f"{rel}/cube.stl",
        f"{rel}/tetrahedron.stl",
    )


@pytest.mark.parametrize(
    ("path", "message"),
    [
        ("missing.stl", r"missing\.stl: no such STL file or folder \(relative to the current"),
        ("empty", r"empty: the folder holds no \.stl file"),
        ("grains/*.obj", r"grains/\*\.obj: the pattern matches no \.stl file"),
        ("grains/notes.txt", r"unsupported solid template file type \(use \.stl files"),
    ],
)
def test_paths_that_name_no_mesh_are_refused(
    grains: Path, monkeypatch: pytest.MonkeyPatch, path: str, message: str
) -> None:
    monkeypatch.chdir(grains.parent)
    (grains.parent / "empty").mkdir(exist_ok=True)
    if not (grains.parent / "grains").exists():
        (grains.parent / "grains").symlink_to(grains)
    with pytest.raises(pydantic.ValidationError, match=message):
        TemplateSolidConfig(path=path)


def test_the_file_is_read_once_and_again_when_it_changes(tmp_path: Path) -> None:
    path = write_binary(tmp_path / "g.stl", hull_triangles(CUBE))
    cache = templates_module._hull_of_file
    misses = cache.cache_info().misses
    gen = template(path)  # validating the path reads the file
    assert cache.cache_info().misses == misses + 1
    hits = cache.cache_info().hits
    assert len(gen.templates.vertices) == 8  # the generator uses the hull kept
    assert cache.cache_info()[:2] == (hits + 1, misses + 1)
    write_binary(path, hull_triangles(TETRAHEDRON))
    os.utime(path, ns=(1, 1))  # a different time, whatever the clock's resolution
    assert len(template(path).templates.vertices) == 4


SCENE = """\
name = "grains3d"
seed = 3
count = 40

[domain]
kind = "box"
width = 15.0
height = 15.0
depth = 15.0

[size]
kind = "uniform"
d_min = 2.0
d_max = 4.0

[[phases]]
name = "measured"
fraction = 0.7
shape = {{ kind = "template-3d", path = {path}, choice = "random" }}

[[phases]]
name = "polyhedra"
fraction = 0.3
shape = {{ kind = "polyhedron" }}

[insertion]
kind = "available-surface"

[density]
kind = "eta"
"""


def test_a_small_box_of_measured_grains_packs_and_verifies(grains: Path, tmp_path: Path) -> None:
    scene = tmp_path / "grains3d.toml"
    scene.write_text(SCENE.format(path=json.dumps(str(grains))), encoding="utf-8")
    outcome = regopack.pack_and_summarise(regopack.scene(scene), out=tmp_path / "run")
    packing = outcome.packing
    assert outcome.summary["verify"]["ok"]
    assert packing.n_placed >= 20
    assert regopack.verify(tmp_path / "run" / "packing.npz")
    # the same scene and seed give the same packing, bit for bit
    again = regopack.pack(regopack.scene(scene))
    assert np.array_equal(again.centre, packing.centre, equal_nan=True)
    assert np.array_equal(again.vertices, packing.vertices)


def test_a_bad_mesh_stops_the_run_in_one_line_naming_the_field(
    grains: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.stl"
    bad.write_bytes((grains / "cube.stl").read_bytes()[:500])
    scene = tmp_path / "grains3d.toml"
    scene.write_text(SCENE.format(path=json.dumps(str(bad))), encoding="utf-8")
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"regopack: error: {scene}: phases.0.shape.path = ")
    assert f"{bad}: truncated or damaged binary STL" in err
    # the same file given with --set names --set
    scene.write_text(SCENE.format(path=json.dumps(str(grains))), encoding="utf-8")
    argv = ["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]
    assert main([*argv, "--set", f"phases.0.shape.path={bad}"]) == 2
    assert capsys.readouterr().err.startswith("regopack: error: --set: phases.0.shape.path = ")


def test_the_shape_is_registered_as_3d_and_refused_in_2d(grains: Path) -> None:
    spec = default_registry(autoload=False).get("shape", "template-3d")
    assert spec.dimension == 3
    scene = {
        "name": "flat",
        "count": 5,
        "domain": {"width": 50.0, "height": 50.0},
        "size": {"kind": "monodisperse", "d": 2.0},
        "phases": [{"name": "g", "fraction": 1.0,
                    "shape": {"kind": "template-3d", "path": str(grains)}}],
        "insertion": {"kind": "available-arc"},
        "density": {"kind": "eta"},
    }  # fmt: skip
    with pytest.raises(ConfigError, match=r"'template-3d' is a 3D shape"):
        regopack.scene(scene)


def test_the_example_scene_reads_the_example_mesh(monkeypatch: pytest.MonkeyPatch) -> None:
    root = Path(__file__).resolve().parents[4]
    monkeypatch.chdir(root)  # the scene's mesh path is relative to the repository root
    scene = regopack.scene(root / "docs" / "examples" / "grains3d.toml")
    assert scene.scene.domain.dimension == 3
    gen = template("docs/examples/grain.stl")
    assert len(gen.templates.vertices) == 15 and len(gen.templates.normals) == 26
    check_solid_generator(gen, radii=np.geomspace(0.5, 2.0, 5))
