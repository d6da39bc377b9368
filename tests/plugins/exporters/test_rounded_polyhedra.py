"""Erosion of a polyhedron by a radius: the core of a rounded body that fits inside it."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.plugins.exporters.rounded_polyhedra import erode_polyhedron


def _tetrahedron() -> tuple[np.ndarray, np.ndarray]:
    normals = np.array([[1.0, 1, 1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1]]) / np.sqrt(3.0)
    return normals, np.ones(4)


def test_a_tetrahedron_erodes_into_a_smaller_similar_one() -> None:
    normals, support = _tetrahedron()
    core = erode_polyhedron(normals, support, 0.25)
    assert core is not None
    assert core.vertices.shape == (4, 3) and core.edges.shape == (6, 2) and len(core.loops) == 4
    np.testing.assert_allclose(np.abs(core.vertices), 0.75 * np.sqrt(3.0))  # inradius 0.75
    for n, s, loop in zip(normals, support, core.loops, strict=True):
        p = core.vertices[loop]
        np.testing.assert_allclose(p @ n, s - 0.25, atol=1e-12)
        assert np.cross(p[1] - p[0], p[2] - p[0]) @ n > 0  # outward


def test_a_radius_that_leaves_no_core_gives_none() -> None:
    normals, support = _tetrahedron()
    assert erode_polyhedron(normals, support, 1.0) is None
    assert erode_polyhedron(normals, support, 2.0) is None


def test_small_faces_vanish_and_the_core_stays_closed() -> None:
    """A cube with one corner cut off a little: the cut face disappears at a larger radius."""
    n = np.vstack([np.eye(3), -np.eye(3), np.ones((1, 3)) / np.sqrt(3.0)])
    s = np.array([1.0, 1, 1, 1, 1, 1, 2.9 / np.sqrt(3.0)])
    small = erode_polyhedron(n, s, 0.01)
    assert small is not None and len(small.loops) == 7
    large = erode_polyhedron(n, s, 0.2)
    assert large is not None and len(large.loops) == 6
    for core in (small, large):
        v, e, f = core.vertices.shape[0], core.edges.shape[0], len(core.loops)
        assert v - e + f == 2
    assert np.abs(large.vertices).max() == pytest.approx(0.8)
