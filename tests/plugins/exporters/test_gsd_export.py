"""The GSD exporter: frames read back with gsd, outlines rebuilt, freud reads the box."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from packings3d import packing3d, spheres3d

from regopack.base.errors import ConfigError, ExportError
from regopack.exports.pipeline import build_exporter, export_packing
from regopack.geometry.domain import PeriodicRectangle
from regopack.packing.core import ROUNDED_SEGMENTS, Packing, save
from regopack.plugins.exporters import polygon_moments
from regopack.plugins.exporters.gsd_export import (
    GsdConfig,
    GsdExporter,
    convex_outline,
    quaternion_from_matrix,
    shape_moments,
)
from regopack.plugins.exporters.solid_export_common import mass_properties
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons

gsd_hoomd = pytest.importorskip("gsd.hoomd", reason="the gsd package is not installed")

CENTER = (30.0, -20.0)


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def walled(registry) -> Packing:
    """A small run off the origin, with its last particle marked as not placed."""
    scene = resolve_scene(
        load_scene("small", ["count=80", f"domain.center=[{CENTER[0]}, {CENTER[1]}]"]), registry
    )
    p = run_scene(scene).packing
    centre = p.centre.copy()
    index = p.insertion_index.copy()
    last = int(np.argmax(index))
    centre[last] = np.nan
    index[last] = -1
    return Packing(**{**_fields(p), "centre": centre, "insertion_index": index})


@pytest.fixture(scope="module")
def periodic(registry) -> Packing:
    scene = resolve_scene(
        load_scene(
            "small",
            [
                "domain.kind=periodic",
                "domain.width=150",
                "domain.height=120",
                "domain.center=[10.0, -5.0]",
                "count=300",
            ],
        ),
        registry,
    )
    return run_scene(scene).packing


def _fields(p: Packing) -> dict:
    names = (
        "radius mineral mineral_names vertices offsets orientation centre insertion_index "
        "domain scene seed version stats rounding"
    ).split()
    return {n: getattr(p, n) for n in names}


def mixed_periodic() -> Packing:
    """Hand-made periodic packing: a square with a repeated and a collinear vertex whose
    centroid lies beyond the right side, a disk, a rounded triangle, a particle that
    is not placed and a hexagon whose centroid lies below the bottom side."""
    square = np.array([[-1, -2], [3, -2], [3, -2], [3, 0], [3, 2], [-1, 2]], dtype=float)
    disk = np.zeros((1, 2))
    tri = np.array([[-1.0, -1.0], [2.0, -0.5], [0.0, 1.5]])
    t = np.arange(6) * np.pi / 3
    hexagon = np.column_stack([2 * np.cos(t), 2 * np.sin(t) - 1.2])
    outlines = [square, disk, tri, square, hexagon]
    counts = [len(o) for o in outlines]
    offsets = np.concatenate([[0], np.cumsum(counts)])
    centre = np.array([[69.5, 10.0], [0.0, 0.0], [20.0, -30.0], [np.nan, np.nan], [-20.0, -39.5]])
    return Packing(
        radius=np.array([2.0, 3.0, 1.5, 2.0, 1.8]),
        mineral=np.array([0, 1, 1, 0, 0]),
        mineral_names=("ilmenite", "glass"),
        vertices=np.concatenate(outlines),
        offsets=offsets,
        orientation=np.array([0.3, 0.0, 1.0, 0.0, -2.0]),
        centre=centre,
        insertion_index=np.array([0, 1, 2, -1, 3]),
        domain=PeriodicRectangle(-50.0, 70.0, -40.0, 40.0),
        scene={"name": "mixed"},
        rounding=np.array([0.0, 3.0, 0.5, 0.0, 0.0]),
    )


def read(path):
    with gsd_hoomd.open(path) as traj:
        assert len(traj) == 1
        return traj[0]


def body_to_box(frame, i: int) -> tuple[np.ndarray, float]:
    """Absolute vertices of particle ``i`` in the domain's frame (unwrapped) and its rounding."""
    shape = frame.particles.type_shapes[frame.particles.typeid[i]]
    v = np.array(shape["vertices"], dtype=float).reshape(-1, 2)
    q = frame.particles.orientation[i].astype(float)
    theta = 2.0 * math.atan2(q[3], q[0])
    rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    box = frame.configuration.box.astype(float)
    centre = (
        frame.particles.position[i, :2].astype(float)
        + frame.particles.image[i, :2] * box[:2]
        + frame.log["regopack/origin"][:2]
    )
    return v @ rot.T + centre, float(shape["rounding_radius"])


def grown(v: np.ndarray, rho: float, quad_segs: int = ROUNDED_SEGMENTS // 4):
    core = shapely.Polygon(v) if len(v) >= 3 else shapely.convex_hull(shapely.MultiPoint(v))
    return shapely.buffer(core, rho, quad_segs=quad_segs) if rho > 0 else core


def assert_same_particles(packing: Packing, frame) -> None:
    """Every placed particle, rebuilt from the frame, covers its packing outline."""
    idx = np.flatnonzero(packing.placed)
    assert frame.particles.N == len(idx)
    assert list(frame.log["particles/regopack/index"]) == idx.tolist()
    targets = packing.to_shapely(idx)
    for i, j in enumerate(idx.tolist()):
        v, rho = body_to_box(frame, i)
        assert rho == packing.rounding_radius[j]
        got = grown(v, rho)
        want = targets[i]
        # single-precision positions and orientations: ~1e-6 of the particle's size
        assert shapely.area(shapely.symmetric_difference(got, want)) < 1e-5 * want.area, j


# ---------------------------------------------------------------------------
# layout


def test_registered(registry):
    assert "gsd" in registry.names("export")
    assert build_exporter(registry, "gsd").suffix == ".gsd"


def test_frame_layout(walled, registry, tmp_path):
    path = export_packing(walled, "gsd", tmp_path / "p.gsd", registry=registry)
    frame = read(path)
    idx = np.flatnonzero(walled.placed)
    n = len(idx)
    assert 0 < n < walled.n_particles
    assert frame.configuration.dimensions == 2
    np.testing.assert_array_equal(frame.configuration.box, [200, 200, 0, 0, 0, 0])
    assert frame.particles.N == n
    np.testing.assert_array_equal(frame.particles.typeid, np.arange(n))
    names = walled.mineral_names
    assert frame.particles.types == [f"{names[walled.mineral[j]]}_{j}" for j in idx]
    assert len(frame.particles.type_shapes) == n
    assert {s["type"] for s in frame.particles.type_shapes} == {"Polygon"}
    assert {s["rounding_radius"] for s in frame.particles.type_shapes} == {0.0}
    np.testing.assert_array_equal(frame.log["particles/regopack/mineral"], walled.mineral[idx])
    np.testing.assert_array_equal(
        frame.log["particles/regopack/insertion_index"], walled.insertion_index[idx]
    )
    np.testing.assert_array_equal(frame.log["regopack/origin"], [*CENTER, 0.0])
    assert frame.log["regopack/periodic"][0] == 0
    np.testing.assert_array_equal(frame.particles.image, 0)
    half = frame.configuration.box[:2] / 2
    assert np.all(np.abs(frame.particles.position[:, :2]) < half)
    np.testing.assert_array_equal(frame.particles.position[:, 2], 0)


def test_positions_are_centroids_and_outlines_rebuild(walled, registry, tmp_path):
    frame = read(export_packing(walled, "gsd", tmp_path / "p.gsd", registry=registry))
    assert_same_particles(walled, frame)
    origin = np.array(CENTER)
    for i, j in enumerate(np.flatnonzero(walled.placed).tolist()):
        _, c, *_ = polygon_moments(walled.polygon(j))
        np.testing.assert_allclose(frame.particles.position[i, :2] + origin, c, atol=1e-4)
        # the shape's centre of mass is at the origin of its body frame
        _, c0, *_ = polygon_moments(np.array(frame.particles.type_shapes[i]["vertices"]))
        np.testing.assert_allclose(c0, 0.0, atol=1e-12)


def test_orientation_is_the_packing_angle(walled, registry, tmp_path):
    frame = read(export_packing(walled, "gsd", tmp_path / "p.gsd", registry=registry))
    q = frame.particles.orientation.astype(float)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    np.testing.assert_array_equal(q[:, 1:3], 0.0)
    theta = walled.orientation[walled.placed]
    np.testing.assert_allclose(np.cos(2 * np.arctan2(q[:, 3], q[:, 0]) - theta), 1.0, atol=1e-10)


def test_vertices_are_distinct_convex_and_counter_clockwise(walled, registry, tmp_path):
    frame = read(export_packing(walled, "gsd", tmp_path / "p.gsd", registry=registry))
    removed = 0
    for i, j in enumerate(np.flatnonzero(walled.placed).tolist()):
        v = np.array(frame.particles.type_shapes[i]["vertices"])
        edges = np.roll(v, -1, axis=0) - v
        turn = (
            edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1]
            - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        )
        length = np.hypot(*edges.T)
        assert np.all(length > 1e-9 * np.abs(v).max()), j
        assert np.all(turn > 1e-9 * length * np.roll(length, -1)), j
        removed += (walled.offsets[j + 1] - walled.offsets[j]) - len(v)
    assert removed > 0  # the octagons of the scene do have repeated vertices


def test_masses_and_moments_of_inertia(walled, registry, tmp_path):
    path = export_packing(
        walled, "gsd", tmp_path / "p.gsd", registry=registry, params={"density": 2.5}
    )
    frame = read(path)
    idx = np.flatnonzero(walled.placed)
    np.testing.assert_allclose(frame.particles.mass, 2.5 * walled.area()[idx], rtol=1e-6)
    izz = [2.5 * sum(polygon_moments(walled.polygon(j))[2:4]) for j in idx]
    np.testing.assert_allclose(frame.particles.moment_inertia[:, 2], izz, rtol=1e-6)
    np.testing.assert_array_equal(frame.particles.moment_inertia[:, :2], 0.0)
    assert frame.log["regopack/density"][0] == 2.5


# ---------------------------------------------------------------------------
# disks, rounded polygons, periodic domains


def test_disks_and_rounded_polygons_are_spheropolygons(tmp_path):
    p = mixed_periodic()
    frame = read(GsdExporter().export(p, tmp_path / "m.gsd"))
    shapes = frame.particles.type_shapes
    assert frame.particles.types == ["ilmenite_0", "glass_1", "glass_2", "ilmenite_4"]
    assert shapes[1] == {"type": "Polygon", "rounding_radius": 3.0, "vertices": [[0.0, 0.0]]}
    assert shapes[2]["rounding_radius"] == 0.5 and len(shapes[2]["vertices"]) == 3
    assert len(shapes[0]["vertices"]) == 4  # the repeated and the collinear vertex are gone
    assert_same_particles(p, frame)
    np.testing.assert_allclose(frame.particles.mass, p.area()[p.placed], rtol=1e-6)
    assert frame.particles.mass[1] == pytest.approx(9 * math.pi, rel=1e-7)
    assert frame.particles.moment_inertia[1, 2] == pytest.approx(9 * math.pi * 9 / 2, rel=1e-6)
    # the rounded triangle: centre of mass and moment of a finely drawn outline
    fine = shapely.geometry.polygon.orient(grown(p.polygon(2), 0.5, quad_segs=2048), 1.0)
    area, c, ixx, iyy, _ = polygon_moments(np.asarray(fine.exterior.coords)[:-1])
    assert frame.particles.mass[2] == pytest.approx(area, rel=1e-5)
    assert frame.particles.moment_inertia[2, 2] == pytest.approx(ixx + iyy, rel=1e-5)
    origin = frame.log["regopack/origin"][:2]
    np.testing.assert_allclose(frame.particles.position[2, :2] + origin, c, atol=1e-5)


def test_shape_moments_of_a_stadium():
    a, c, j = shape_moments(np.array([[-1.0, 0.0], [1.0, 0.0]]), 0.5)
    # a 2 x 1 rectangle and a disk of radius 0.5 split at its two ends
    assert a == pytest.approx(2.0 + math.pi / 4)
    np.testing.assert_allclose(c, 0.0, atol=1e-15)
    rect = 2.0 * (4.0 + 1.0) / 12.0
    d = 4 * 0.5 / (3 * math.pi)  # centroid of a half disk from its diameter
    half = math.pi / 8
    ends = 2 * (half * 0.25 / 2 - half * d * d + half * (1.0 + d) ** 2)
    assert j == pytest.approx(rect + ends, rel=1e-12)


def test_convex_outline_refuses_a_reflex_vertex():
    with pytest.raises(ValueError, match="not convex"):
        convex_outline(np.array([[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]], dtype=float))
    assert convex_outline(np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])).tolist() == [
        [0.0, 0.0],
        [2.0, 2.0],
    ]


def test_periodic_positions_are_wrapped_with_images(tmp_path):
    p = mixed_periodic()
    frame = read(GsdExporter().export(p, tmp_path / "m.gsd"))
    np.testing.assert_array_equal(frame.configuration.box, [120, 80, 0, 0, 0, 0])
    np.testing.assert_array_equal(frame.log["regopack/origin"], [10.0, 0.0, 0.0])
    assert frame.log["regopack/periodic"][0] == 1
    pos = frame.particles.position[:, :2]
    assert np.all(pos >= -frame.configuration.box[:2] / 2)
    assert np.all(pos < frame.configuration.box[:2] / 2)
    # the square's centroid lies beyond x = 70 and the hexagon's below y = -40
    np.testing.assert_array_equal(frame.particles.image[:, :2], [[1, 0], [0, 0], [0, 0], [0, -1]])
    assert pos[0, 0] == pytest.approx(70.5 - 10.0 - 120.0, abs=1e-5)


def test_periodic_run(periodic, registry, tmp_path):
    frame = read(export_packing(periodic, "gsd", tmp_path / "p.gsd", registry=registry))
    assert_same_particles(periodic, frame)
    pos = frame.particles.position[:, :2]
    half = frame.configuration.box[:2] / 2
    assert np.all((pos >= -half) & (pos < half))


def test_freud_reads_the_box_and_finds_the_neighbours(periodic, registry, tmp_path):
    freud = pytest.importorskip("freud", reason="freud-analysis is not installed")
    frame = read(export_packing(periodic, "gsd", tmp_path / "p.gsd", registry=registry))
    box = freud.box.Box.from_box(frame.configuration.box)
    assert box.is2D and (box.Lx, box.Ly) == (150.0, 120.0)
    r_max = 12.0
    nlist = (
        freud.locality.AABBQuery(box, frame.particles.position)
        .query(frame.particles.position, {"r_max": r_max, "exclude_ii": True})
        .toNeighborList()
    )
    got = {(int(i), int(j)) for i, j in nlist[:]}
    # the same pairs by brute force, from the packing's centroids and minimum images
    idx = np.flatnonzero(periodic.placed)
    c = np.array(
        [
            periodic.centre[j]
            + polygon_moments(periodic.vertices[periodic.offsets[j] : periodic.offsets[j + 1]])[1]
            for j in idx
        ]
    )
    d = periodic.domain.minimum_image((c[:, None, :] - c[None, :, :]).reshape(-1, 2))
    dist = np.hypot(*d.T).reshape(len(idx), len(idx))
    near = (dist < r_max) & ~np.eye(len(idx), dtype=bool)
    sure = np.abs(dist - r_max) > 1e-3  # leave out pairs at r_max to single precision
    want = {(int(i), int(j)) for i, j in zip(*np.nonzero(near & sure), strict=True)}
    assert len(want) > 5 * len(idx)
    assert want <= got
    assert all(not sure[i, j] for i, j in got - want)


# ---------------------------------------------------------------------------
# errors, edge cases, the command line


def test_a_packing_with_nothing_placed(registry, tmp_path):
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    empty = packing_from_polygons([square, square], placed=[False, False])
    frame = read(export_packing(empty, "gsd", tmp_path / "e.gsd", registry=registry))
    assert frame.particles.N == 0
    assert frame.particles.position.shape == (0, 3)


def test_a_concave_outline_is_one_error(registry, tmp_path):
    dart = [(0, 0), (2, 0), (1, 0.5), (2, 2), (0, 2)]
    p = packing_from_polygons([dart])
    with pytest.raises(ExportError, match=r"^particle 0: .*not convex") as err:
        export_packing(p, "gsd", tmp_path / "d.gsd", registry=registry)
    assert "\n" not in str(err.value)
    assert not list(tmp_path.iterdir())


def test_missing_gsd_is_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "gsd", None)
    monkeypatch.setitem(sys.modules, "gsd.hoomd", None)
    with pytest.raises(ExportError) as err:
        GsdExporter()
    # regopack[gsd] needs regopack on an index: the hint also works from a clone
    assert str(err.value) == (
        "the gsd export needs the gsd package: pip install 'gsd>=3.0', or "
        "pip install '.[gsd]' in regopack's source folder"
    )


def test_unwritable_path_is_one_error(walled, registry, tmp_path):
    with pytest.raises(ExportError, match=r"^cannot write .*p\.gsd: No such file"):
        export_packing(walled, "gsd", tmp_path / "no" / "p.gsd", registry=registry)


def test_a_failed_write_keeps_the_previous_file(walled, registry, tmp_path, monkeypatch):
    path = export_packing(walled, "gsd", tmp_path / "p.gsd", registry=registry)
    before = path.read_bytes()

    def broken(name, mode="r"):
        Path(name).write_bytes(b"partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(gsd_hoomd, "open", broken)
    with pytest.raises(ExportError, match="No space left on device"):
        export_packing(walled, "gsd", path, registry=registry)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["p.gsd"]


def test_config_refuses_unknown_and_bad_fields(registry):
    with pytest.raises(ConfigError, match=r"exporter 'gsd': densty = 1\.0: unknown field; did"):
        build_exporter(registry, "gsd", {"densty": 1.0})
    with pytest.raises(ConfigError, match=r"exporter 'gsd': density = 0\.0: "):
        build_exporter(registry, "gsd", {"density": 0.0})


def test_command_line_export(walled, tmp_path, monkeypatch, capsys):
    from regopack.cli import main

    monkeypatch.chdir(tmp_path)
    save(walled, tmp_path / "packing.npz")
    assert main(["export", "packing.npz", "--to", "gsd", "--set", "density=3"]) == 0
    assert "wrote packing.gsd" in capsys.readouterr().out
    frame = read(tmp_path / "packing.gsd")
    assert frame.particles.N == walled.n_placed
    shapes = [json.dumps(s) for s in frame.particles.type_shapes]
    assert len(set(shapes)) == walled.n_placed


def test_the_length_unit_is_logged_in_metres(walled, registry, tmp_path):
    from dataclasses import replace

    for unit, metres in (("µm", 1e-6), ("mm", 1e-3)):
        p = replace(walled, scene={**walled.scene, "length_unit": unit})
        path = export_packing(p, "gsd", tmp_path / f"{metres}.gsd", registry=registry)
        frame = read(path)
        assert frame.log["regopack/length_unit_m"][0] == metres
        assert "regopack/length_scale" not in frame.log  # 2D: the scene's unit


# ---------------------------------------------------------------------------
# 3D packings: convex polyhedra and spheres


@pytest.fixture(scope="module")
def polyhedra() -> Packing:
    return packing3d()


@pytest.fixture(scope="module")
def solid_frame(polyhedra, tmp_path_factory):
    path = tmp_path_factory.mktemp("gsd") / "p.gsd"
    GsdExporter(GsdConfig(density=3.1)).export(polyhedra, path)
    with gsd_hoomd.open(path, "r") as traj:
        assert len(traj) == 1
        return traj[0]


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate the rows of ``v`` by the unit quaternion ``q = (w, x, y, z)`` (HOOMD's order)."""
    w, u = q[0], q[1:]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def test_box_types_and_one_shape_per_particle(polyhedra, solid_frame) -> None:
    idx = np.flatnonzero(polyhedra.placed)
    lo, hi = polyhedra.domain.bounds().reshape(3, 2).T
    assert solid_frame.configuration.dimensions == 3
    scale = solid_frame.log["regopack/length_scale"][0]
    np.testing.assert_allclose(solid_frame.configuration.box * scale, [*(hi - lo), 0, 0, 0])
    np.testing.assert_allclose(solid_frame.log["regopack/origin"] * scale, 0.5 * (lo + hi))
    assert solid_frame.particles.N == idx.size
    np.testing.assert_array_equal(solid_frame.particles.typeid, np.arange(idx.size))
    names = [f"{polyhedra.mineral_names[polyhedra.mineral[j]]}_{j}" for j in idx]
    assert list(solid_frame.particles.types) == names
    assert {s["type"] for s in solid_frame.particles.type_shapes} == {"ConvexPolyhedron"}
    np.testing.assert_array_equal(solid_frame.log["particles/regopack/index"], idx)
    np.testing.assert_array_equal(
        solid_frame.log["particles/regopack/mineral"], polyhedra.mineral[idx]
    )


def test_shapes_rotated_by_the_quaternion_give_each_particle(polyhedra, solid_frame) -> None:
    idx = np.flatnonzero(polyhedra.placed)
    origin = np.asarray(solid_frame.log["regopack/origin"])
    for i, j in enumerate(idx.tolist()):
        body = np.array(solid_frame.particles.type_shapes[i]["vertices"])
        q = np.asarray(solid_frame.particles.orientation[i], dtype=np.float64)
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-6)
        world = rotate(q / np.linalg.norm(q), body) + solid_frame.particles.position[i] + origin
        want = polyhedra.world_vertices(j) / solid_frame.log["regopack/length_scale"][0]
        np.testing.assert_allclose(world, want, atol=2e-6 * polyhedra.domain.size[0])


def test_positions_are_centroids_and_masses_volumes(polyhedra, solid_frame) -> None:
    idx = np.flatnonzero(polyhedra.placed)
    origin = np.asarray(solid_frame.log["regopack/origin"])
    scale = solid_frame.log["regopack/length_scale"][0]
    solids = polyhedra.solids
    for i, j in enumerate(idx.tolist()):
        local, loops = solids.solid(j)
        volume, c, moments = mass_properties(local, loops)
        pos = (solid_frame.particles.position[i] + origin) * scale
        np.testing.assert_allclose(pos, polyhedra.centre[j] + c, atol=1e-5)
        assert solid_frame.particles.mass[i] == pytest.approx(3.1 * volume, rel=1e-6)
        inertia = 3.1 * (np.trace(moments) * np.eye(3) - moments)
        moment = solid_frame.particles.moment_inertia[i] * scale**2  # mass x (file length)²
        assert np.sort(moment) == pytest.approx(np.linalg.eigvalsh(inertia), rel=1e-5)


def test_the_body_frame_is_the_principal_frame(polyhedra, solid_frame) -> None:
    """The type's vertices have a diagonal inertia tensor: HOOMD-blue needs principal axes."""
    for i in range(solid_frame.particles.N):
        body = np.array(solid_frame.particles.type_shapes[i]["vertices"])
        j = int(solid_frame.log["particles/regopack/index"][i])
        _, loops = polyhedra.solids.solid(j)
        _, c, moments = mass_properties(body, loops)
        np.testing.assert_allclose(c, 0.0, atol=1e-9 * polyhedra.radius[j])
        off = moments - np.diag(np.diag(moments))
        assert np.abs(off).max() < 1e-9 * np.abs(moments).max()


def test_quaternion_from_matrix_round_trips() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        m = np.column_stack([rotate(q, e) for e in np.eye(3)])
        got = quaternion_from_matrix(m)
        assert np.allclose(got, q * np.sign(q[0]), atol=1e-12)


def test_spheres_are_sphere_shapes_at_their_centres(tmp_path) -> None:
    spheres = spheres3d()
    path = GsdExporter().export(spheres, tmp_path / "s.gsd")
    with gsd_hoomd.open(path, "r") as traj:
        frame = traj[0]
    idx = np.flatnonzero(spheres.placed)
    origin = np.asarray(frame.log["regopack/origin"])
    scale = frame.log["regopack/length_scale"][0]
    assert scale == 10.0  # spheres up to 12 µm across
    shapes = frame.particles.type_shapes
    assert {s["type"] for s in shapes} == {"Sphere"} and all(len(s) == 2 for s in shapes)
    got = np.array([s["diameter"] for s in shapes])
    np.testing.assert_allclose(got * scale, 2 * spheres.radius[idx], rtol=1e-14)
    np.testing.assert_allclose(
        (frame.particles.position + origin) * scale, spheres.centre[idx], atol=1e-5
    )
    np.testing.assert_array_equal(frame.particles.orientation, [[1, 0, 0, 0]] * idx.size)


OVITO_MESHES = """
import json, sys
from ovito.io import import_file
from ovito.vis import ParticlesVis

types = import_file(sys.argv[1]).compute().particles.particle_types.types
mesh = ParticlesVis.Shape.Mesh
print(json.dumps({t.name: t.shape == mesh and t.mesh is not None for t in types}))
"""
"""Print, for each particle type of a GSD file that OVITO reads, whether it got a mesh."""


def test_ovito_draws_every_polyhedron_as_its_mesh(polyhedra, solid_frame, tmp_path) -> None:
    """OVITO builds each type's mesh as a convex hull, which fails (and draws a sphere)
    for shapes some units across: the frame's lengths keep every shape below 1."""
    import importlib.util
    import json
    import subprocess
    import sys

    if importlib.util.find_spec("ovito") is None:
        pytest.skip("the ovito package is not installed")
    scale = solid_frame.log["regopack/length_scale"][0]
    radius = [
        np.linalg.norm(s["vertices"], axis=1).max() for s in solid_frame.particles.type_shapes
    ]
    assert scale == 10.0 and 0.1 < max(radius) <= 1.0  # grains up to 12 µm across
    assert solid_frame.log["regopack/length_unit_m"][0] == pytest.approx(1e-5)
    path = GsdExporter().export(polyhedra, tmp_path / "p.gsd")
    done = subprocess.run(
        [sys.executable, "-c", OVITO_MESHES, str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    meshes = json.loads(done.stdout.strip().splitlines()[-1])
    assert len(meshes) == polyhedra.n_placed and all(meshes.values()), done.stderr[-2000:]
