"""The polyhedron representation and its builder from points."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from surface_helpers import box, check_closed_surface, random_points, rotation

from regopack.plugins.inserters.available_surface.polyhedron import (
    circumradius,
    face_area,
    polyhedron_from_points,
    reflect,
    volume,
)


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(4, 60), scale=st.sampled_from([1e-6, 1e6]))
@settings(max_examples=100, deadline=None)
def test_random_points(seed: int, n: int, scale: float) -> None:
    pts = random_points(np.random.default_rng(seed), n, scale)
    try:
        poly = polyhedron_from_points(pts)
    except ValueError:  # the origin is not strictly inside
        assert ConvexHull(pts).equations[:, 3].max() >= -1e-9 * scale
        return
    check_closed_surface(poly, 1e-9 * scale)
    hull = ConvexHull(pts)
    assert volume(poly) == pytest.approx(hull.volume, rel=1e-9)
    assert len(poly.vertices) == len(hull.vertices)
    assert circumradius(poly) == pytest.approx(np.max(np.linalg.norm(pts[hull.vertices], axis=1)))


def test_a_cube_has_six_square_faces() -> None:
    poly = box(1.0)
    assert len(poly.vertices) == 8 and len(poly.normals) == 6
    assert np.diff(poly.face_offsets).tolist() == [4] * 6
    assert np.allclose(poly.support, 1.0)
    assert volume(poly) == pytest.approx(8.0)
    assert [face_area(poly, f) for f in range(6)] == pytest.approx([4.0] * 6)
    check_closed_surface(poly, 1e-12)


def test_points_inside_faces_and_on_edges_are_dropped() -> None:
    grid = np.array(list(itertools.product([-1.0, 0.0, 1.0], repeat=3)))
    poly = polyhedron_from_points(grid @ rotation(np.random.default_rng(1)).T)
    assert len(poly.vertices) == 8 and len(poly.normals) == 6
    check_closed_surface(poly, 1e-12)


def test_reflect_keeps_the_loops_counter_clockwise() -> None:
    poly = polyhedron_from_points(random_points(np.random.default_rng(2), 30))
    minus = reflect(poly)
    check_closed_surface(minus, 1e-12)
    assert volume(minus) == pytest.approx(volume(poly))


@pytest.mark.parametrize(
    "points",
    [
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float),  # flat
        np.array([[1, 1, 1], [2, 1, 1], [1, 2, 1], [1, 1, 2]], dtype=float),  # origin outside
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float),  # origin on a corner
        np.zeros((3, 3)),
        np.full((5, 3), np.nan),
    ],
)
def test_bad_points_are_refused(points: np.ndarray) -> None:
    with pytest.raises(ValueError):
        polyhedron_from_points(points)
