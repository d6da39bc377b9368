"""Rigid motions of a packing's particles (:mod:`regopack.packing.motion`)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from packings3d import cube_packing
from scipy.spatial.transform import Rotation

from regopack.base.errors import PackingError
from regopack.geometry.domain import Box, PeriodicBox
from regopack.packing.core import Packing
from regopack.packing.motion import moved, quaternion_of
from regopack.testing import packing_from_polygons


def spheres() -> Packing:
    return Packing.of_spheres([[1.0, 1, 1], [3, 1, 1]], [1.0, 1.0], Box(0, 4, 0, 2, 0, 2))


def test_spheres_move_by_their_shift_and_keep_their_radius() -> None:
    p = spheres()
    q = moved(p, np.array([0, 1]), np.array([[0.5, 0, 0], [0, 0, -0.25]]), stats={"x": 1.0})
    assert q.centre.tolist() == [[1.5, 1.0, 1.0], [3.0, 1.0, 0.75]]
    assert q.solids.rounding_radius.tolist() == p.solids.rounding_radius.tolist()
    assert q.stats["x"] == 1.0 and p.centre.tolist() == [[1.0, 1, 1], [3, 1, 1]]  # a copy


def test_a_periodic_box_wraps_the_moved_centres() -> None:
    p = spheres()
    periodic = Packing.of_spheres(p.centre, [1.0, 1.0], PeriodicBox(0, 4, 0, 2, 0, 2))
    q = moved(periodic, np.array([1]), np.array([[2.5, -1.5, 0.0]]))
    np.testing.assert_allclose(q.centre[1], [1.5, 1.5, 1.0])


@settings(max_examples=40, deadline=None)
@given(
    angles=st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3),
    pivot=st.lists(st.floats(-0.4, 0.4), min_size=3, max_size=3),
)
def test_a_turned_polyhedron_is_the_turned_points_with_consistent_faces(angles, pivot) -> None:
    p = cube_packing([[3.0, 3, 3], [6, 6, 6]], half=0.5)
    first = Rotation.from_euler("zyx", [0.3, -1.1, 2.0]).as_matrix()
    p = moved(p, np.array([0]), np.zeros((1, 3)), first[None])  # some orientation already
    r = Rotation.from_euler("xyz", angles).as_matrix()
    g = np.array(pivot) * 0.5
    shift = np.array([[0.25, -0.5, 1.0]])
    q = moved(p, np.array([0]), shift, r[None], g[None])
    before, after = p.world_vertices(0), q.world_vertices(0)
    want = (before - p.centre[0] - g) @ r.T + p.centre[0] + g + shift[0]
    np.testing.assert_allclose(after, want, atol=1e-12)
    np.testing.assert_array_equal(q.world_vertices(1), p.world_vertices(1))  # the other stays
    # every face plane n·x = s passes through its loop and has the solid behind it
    local = q.vertices[q.offsets[0] : q.offsets[1]]
    for f in range(q.face_offsets[0], q.face_offsets[1]):
        loop = q.face_vertices[q.face_vertex_offsets[f] : q.face_vertex_offsets[f + 1]]
        n, s = q.normals[f], q.support[f]
        np.testing.assert_allclose(local[loop] @ n, s, atol=1e-12)
        assert (local @ n <= s + 1e-12).all()
    # the orientation is the turn composed with the old one
    old = Rotation.from_quat(p.rotation[0][[1, 2, 3, 0]])
    new = Rotation.from_quat(q.rotation[0][[1, 2, 3, 0]])
    np.testing.assert_allclose(new.as_matrix(), r @ old.as_matrix(), atol=1e-12)


def test_quaternions_of_rotation_matrices() -> None:
    r = Rotation.random(5, random_state=1)
    q = quaternion_of(r.as_matrix())
    np.testing.assert_allclose(np.abs(q), np.abs(r.as_quat()[:, [3, 0, 1, 2]]), atol=1e-15)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((np.array([0, 0]), np.zeros((2, 3))), "given twice"),
        ((np.array([2]), np.zeros((1, 3))), "not a placed particle"),
        ((np.array([0]), np.zeros((2, 3))), "shift has shape"),
        ((np.array([0]), np.full((1, 3), np.nan)), "not finite"),
        ((np.array([0]), np.zeros((1, 3)), np.diag([1.0, 1, -1])[None]), "not a rotation"),
        ((np.array([0]), np.zeros((1, 3)), 2 * np.eye(3)[None]), "not a rotation"),
    ],
)
def test_wrong_motions_are_refused_in_one_line(args, message) -> None:
    with pytest.raises(PackingError, match=message):
        moved(cube_packing([[3.0, 3, 3], [6, 6, 6]]), *args)


def test_a_turned_polygon_in_2d() -> None:
    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    p = packing_from_polygons([square, square + 3.0])
    quarter = np.array([[[0.0, -1], [1, 0]]])
    g = np.array([[0.25, 0.0]])
    q = moved(p, np.array([1]), np.array([[0.5, -0.5]]), quarter, g)
    before = p.polygon(1) - p.centre[1] - g[0]
    want = before @ quarter[0].T + p.centre[1] + g[0] + [0.5, -0.5]
    np.testing.assert_allclose(q.polygon(1), want, atol=1e-15)
    np.testing.assert_array_equal(q.polygon(0), p.polygon(0))
    assert q.orientation[1] == pytest.approx(np.mod(p.orientation[1] + np.pi / 2, 2 * np.pi))
    # three more quarter turns bring it back, within [0, 2 pi)
    r = q
    for _ in range(3):
        r = moved(r, np.array([1]), np.zeros((1, 2)), quarter)
    assert 0.0 <= r.orientation[1] < 2 * np.pi
    assert r.orientation[1] == pytest.approx(p.orientation[1], abs=1e-12) or abs(
        r.orientation[1] - p.orientation[1]
    ) == pytest.approx(2 * np.pi, abs=1e-12)
    with pytest.raises(PackingError, match="shift has shape"):
        moved(p, np.array([1]), np.zeros((1, 3)))


def test_a_shift_beyond_any_precision_is_refused() -> None:
    p = spheres()
    with pytest.raises(PackingError, match="beyond 1e12 times the domain's size"):
        moved(p, np.array([0]), np.array([[1e300, 0, 0]]))
