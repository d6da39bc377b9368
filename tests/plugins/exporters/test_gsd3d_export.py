"""The ``gsd3d`` export, read back by gsd: positions, shapes after the quaternion, box, mass."""

from __future__ import annotations

import numpy as np
import pytest
from packings3d import packing3d, spheres3d

from regopack.packing.core import Packing
from regopack.plugins.exporters.gsd3d_export import (
    Gsd3dConfig,
    Gsd3dExporter,
    quaternion_from_matrix,
)
from regopack.plugins.exporters.solid_export_common import mass_properties

gsd_hoomd = pytest.importorskip("gsd.hoomd", reason="the gsd package is not installed")


@pytest.fixture(scope="module")
def packing() -> Packing:
    return packing3d()


@pytest.fixture(scope="module")
def frame(packing, tmp_path_factory):  # type: ignore[no-untyped-def]
    path = tmp_path_factory.mktemp("gsd3d") / "p.gsd"
    Gsd3dExporter(Gsd3dConfig(density=3.1)).export(packing, path)
    with gsd_hoomd.open(path, "r") as traj:
        assert len(traj) == 1
        return traj[0]


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate the rows of ``v`` by the unit quaternion ``q = (w, x, y, z)`` (HOOMD's order)."""
    w, u = q[0], q[1:]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def test_box_types_and_one_shape_per_particle(packing, frame) -> None:  # type: ignore[no-untyped-def]
    idx = np.flatnonzero(packing.placed)
    lo, hi = packing.domain.bounds().reshape(3, 2).T
    assert frame.configuration.dimensions == 3
    np.testing.assert_allclose(frame.configuration.box, [*(hi - lo), 0, 0, 0])
    np.testing.assert_allclose(frame.log["regopack/origin"], 0.5 * (lo + hi))
    assert frame.particles.N == idx.size
    np.testing.assert_array_equal(frame.particles.typeid, np.arange(idx.size))
    names = [f"{packing.mineral_names[packing.mineral[j]]}_{j}" for j in idx]
    assert list(frame.particles.types) == names
    assert {s["type"] for s in frame.particles.type_shapes} == {"ConvexPolyhedron"}
    np.testing.assert_array_equal(frame.log["particles/regopack/index"], idx)
    np.testing.assert_array_equal(frame.log["particles/regopack/mineral"], packing.mineral[idx])


def test_shapes_rotated_by_the_quaternion_give_each_particle(packing, frame) -> None:  # type: ignore[no-untyped-def]
    idx = np.flatnonzero(packing.placed)
    origin = np.asarray(frame.log["regopack/origin"])
    for i, j in enumerate(idx.tolist()):
        body = np.array(frame.particles.type_shapes[i]["vertices"])
        q = np.asarray(frame.particles.orientation[i], dtype=np.float64)
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-6)
        world = rotate(q / np.linalg.norm(q), body) + frame.particles.position[i] + origin
        want = packing.world_vertices(j)
        np.testing.assert_allclose(world, want, atol=2e-6 * packing.domain.size[0])


def test_positions_are_centroids_and_masses_volumes(packing, frame) -> None:  # type: ignore[no-untyped-def]
    idx = np.flatnonzero(packing.placed)
    origin = np.asarray(frame.log["regopack/origin"])
    solids = packing.solids
    for i, j in enumerate(idx.tolist()):
        local, loops = solids.solid(j)
        volume, c, moments = mass_properties(local, loops)
        pos = frame.particles.position[i] + origin
        np.testing.assert_allclose(pos, packing.centre[j] + c, atol=1e-5)
        assert frame.particles.mass[i] == pytest.approx(3.1 * volume, rel=1e-6)
        inertia = 3.1 * (np.trace(moments) * np.eye(3) - moments)
        assert np.sort(frame.particles.moment_inertia[i]) == pytest.approx(
            np.linalg.eigvalsh(inertia), rel=1e-5
        )


def test_the_body_frame_is_the_principal_frame(packing, frame) -> None:  # type: ignore[no-untyped-def]
    """The type's vertices have a diagonal inertia tensor: HOOMD-blue needs principal axes."""
    for i in range(frame.particles.N):
        body = np.array(frame.particles.type_shapes[i]["vertices"])
        j = int(frame.log["particles/regopack/index"][i])
        _, loops = packing.solids.solid(j)
        _, c, moments = mass_properties(body, loops)
        np.testing.assert_allclose(c, 0.0, atol=1e-9 * packing.radius[j])
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


def test_spheres_are_sphere_shapes_at_their_centres(tmp_path) -> None:  # type: ignore[no-untyped-def]
    spheres = spheres3d()
    path = Gsd3dExporter().export(spheres, tmp_path / "s.gsd")
    with gsd_hoomd.open(path, "r") as traj:
        frame = traj[0]
    idx = np.flatnonzero(spheres.placed)
    origin = np.asarray(frame.log["regopack/origin"])
    want = [{"type": "Sphere", "diameter": 2 * spheres.radius[j]} for j in idx]
    assert list(frame.particles.type_shapes) == want
    np.testing.assert_allclose(frame.particles.position + origin, spheres.centre[idx], atol=1e-5)
    np.testing.assert_array_equal(frame.particles.orientation, [[1, 0, 0, 0]] * idx.size)
