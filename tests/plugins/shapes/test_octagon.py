"""Random convex polygons with shape coefficient psi."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon


def _generate(psi: float, a: float, m: int, radius: np.ndarray, seed: int = 0):
    return RandomPolygon(OctagonConfig(psi=psi, a=a, m=m)).generate(
        radius, np.random.default_rng(seed)
    )


def _edge_normal_angles(outline: np.ndarray) -> np.ndarray:
    e = np.roll(outline, -1, axis=0) - outline
    return np.arctan2(-e[:, 0], e[:, 1]), np.hypot(e[:, 0], e[:, 1])


@given(
    psi=st.floats(0.01, 1000.0),
    a=st.floats(0.05, 1.0),
    m=st.sampled_from([3, 4, 6, 8, 12, 16, 32]),
    r=st.floats(1e-6, 1e6),
    seed=st.integers(0, 2**32 - 1),
)
@settings(max_examples=150, deadline=None)
def test_area_convexity_and_edge_directions(
    psi: float, a: float, m: int, r: float, seed: int
) -> None:
    batch = _generate(psi, a, m, np.full(5, r), seed)
    assert batch.vertices.shape == (5 * m, 2)
    for j in range(5):
        outline = batch.outline(j)
        poly = shapely.Polygon(outline)
        assert poly.is_valid
        assert poly.area == pytest.approx(np.pi * r * r, rel=1e-9)
        assert poly.convex_hull.area == pytest.approx(poly.area, rel=1e-9)
        assert shapely.contains_xy(poly, 0.0, 0.0)
        # signed area positive: counter-clockwise
        x, y = outline[:, 0], outline[:, 1]
        assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
        # every proper edge lies along one of the m directions theta0 + 2 pi k / m
        ang, length = _edge_normal_angles(outline)
        proper = length > 1e-6 * r
        k = (ang[proper] - batch.orientation[j]) / (2 * np.pi / m)
        assert np.allclose(k, np.round(k), atol=1e-6)


def test_orientation_range() -> None:
    batch = _generate(1.0, 1 / 3, 8, np.ones(2000))
    assert batch.orientation.min() >= 0.0 and batch.orientation.max() < 2 * np.pi / 8


def test_large_psi_is_regular() -> None:
    batch = _generate(1e6, 1 / 3, 8, np.ones(50))
    for j in range(50):
        d = np.hypot(*batch.outline(j).T)
        assert d.max() / d.min() == pytest.approx(1.0, abs=1e-6)


def test_smaller_psi_is_more_irregular() -> None:
    def spread(psi: float) -> float:
        batch = _generate(psi, 1 / 3, 8, np.ones(500), seed=1)
        d = np.hypot(*batch.vertices.T).reshape(500, 8)
        return float(np.mean(d.max(axis=1) / d.min(axis=1)))

    assert spread(0.25) > spread(2.0) > spread(15.0)


def test_same_seed_same_shapes() -> None:
    a = _generate(0.5, 1 / 3, 8, np.linspace(1, 2, 100), seed=9)
    b = _generate(0.5, 1 / 3, 8, np.linspace(1, 2, 100), seed=9)
    assert np.array_equal(a.vertices, b.vertices)


def test_a_equal_one_keeps_centre_inside() -> None:
    batch = _generate(0.01, 1.0, 8, np.ones(500), seed=2)
    for j in range(500):
        assert shapely.contains_xy(shapely.Polygon(batch.outline(j)), 0.0, 0.0)


def test_empty_batch() -> None:
    batch = _generate(1.0, 0.5, 8, np.zeros(0))
    assert len(batch) == 0 and batch.vertices.shape == (0, 2)
