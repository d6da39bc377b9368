"""Cores and moments of rounded bodies, against shapely."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

from regopack.plugins.exporters import polygon_moments
from regopack.plugins.exporters.rounded_bodies import clean_outline, erode_convex, rounded_moments


def convex(seed: int, scale: float = 1.0, n: int = 12) -> np.ndarray:
    """A random convex counter-clockwise polygon (the hull of random points)."""
    pts = np.random.default_rng(seed).normal(size=(n, 2)) * scale
    ring = np.asarray(shapely.convex_hull(shapely.multipoints(pts)).exterior.coords)[:-1]
    return ring if shapely.LinearRing(ring).is_ccw else ring[::-1].copy()


def with_defects(v: np.ndarray, seed: int) -> np.ndarray:
    """``v`` with repeated vertices and mid-edge (collinear) vertices inserted."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(len(v)):
        out.append(v[i])
        roll = rng.integers(3)
        if roll == 1:
            out.append(v[i].copy())
        elif roll == 2:
            out.append(0.5 * (v[i] + v[(i + 1) % len(v)]))
    return np.array(out)


def min_edge(v: np.ndarray) -> float:
    return float(np.min(np.hypot(*(np.roll(v, -1, axis=0) - v).T)))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), exponent=st.sampled_from([-6, 0, 6]))
def test_clean_outline_removes_defects_and_stays_inside(seed, exponent):
    scale = 10.0**exponent
    v = convex(seed, scale)
    messy = with_defects(v, seed)
    clean = clean_outline(messy)
    assert len(clean) <= len(v)
    assert min_edge(clean) > 1e-6 * scale
    poly, orig = shapely.Polygon(clean), shapely.Polygon(v)
    assert poly.is_valid and shapely.LinearRing(clean).is_ccw
    assert poly.area <= orig.area * (1 + 1e-12)
    assert orig.area - poly.area <= 1e-5 * orig.area  # only slivers went
    a, b = clean - np.roll(clean, 1, axis=0), np.roll(clean, -1, axis=0) - clean
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    assert np.all(cross > 0)  # strictly convex: no collinear vertex left


def test_clean_outline_of_octagon_with_inactive_supports():
    square = np.array([[0, 0], [1, 0], [1, 0], [1, 1], [1, 1], [0, 1], [0, 1], [0, 0]], float)
    assert clean_outline(square).tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]
    assert clean_outline(np.array([[2.0, 3.0]])).tolist() == [[2.0, 3.0]]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), frac=st.one_of(st.just(0.0), st.floats(1e-6, 0.3)))
@example(seed=117, frac=0.1121652312576953)
def test_erosion_is_shapely_inward_offset(seed, frac):
    v = convex(seed)
    orig = shapely.Polygon(v)
    r = frac * math.sqrt(orig.area / math.pi)
    core = erode_convex(v, r)
    expect = orig.buffer(-r, join_style="mitre", mitre_limit=1e6)
    if expect.is_empty or expect.area < 1e-12:
        assert len(core) < 3 or shapely.Polygon(core).area < 1e-9
        return
    got = shapely.Polygon(core)
    # the same polygon: equal areas, and every vertex of each on the other. (Not their
    # symmetric difference: GEOS's overlay found 4.4 for two equal quadrilaterals with a
    # nearly straight corner, seed 117, frac 0.1121652312576953.)
    assert abs(got.area - expect.area) <= 1e-9 * orig.area
    assert got.hausdorff_distance(expect) <= 1e-9 * math.sqrt(orig.area)
    # the rounded body fills the particle but never reaches past it
    body = got.buffer(r, quad_segs=64)
    assert body.difference(orig).area <= 1e-9 * orig.area
    a, b = v - np.roll(v, 1, axis=0), np.roll(v, -1, axis=0) - v
    turn = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(axis=1))
    corners = r * r * np.sum(1.0 / np.tan(0.5 * (math.pi - turn)))  # r² cot(θ/2) per corner
    assert orig.difference(body).area <= corners + 1e-12 * orig.area  # the corners only


def test_erosion_past_the_inradius_is_empty():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    assert erode_convex(square, 1.0).shape[0] < 3
    assert erode_convex(square, 0.0).tolist() == square.tolist()


@pytest.mark.parametrize("n", [1, 2, 3, 8])
@pytest.mark.parametrize("r", [0.0, 0.05, 0.7])
def test_rounded_moments_match_a_fine_polygon(n, r):
    if n < 3 and r == 0.0:
        return
    v = convex(n, 1.0) if n >= 3 else np.random.default_rng(n).normal(size=(n, 2))
    shape = (
        shapely.Polygon(v) if n >= 3 else shapely.LineString(v) if n == 2 else shapely.Point(v[0])
    )
    fine = shape.buffer(r, quad_segs=1024) if r > 0 else shape
    ring = np.asarray(fine.exterior.coords)[:-1]
    ring = ring if shapely.LinearRing(ring).is_ccw else ring[::-1].copy()
    area, c, ixx, iyy, ixy = rounded_moments(v, r)
    a2, c2, ixx2, iyy2, ixy2 = polygon_moments(ring)
    assert area == pytest.approx(a2, rel=1e-5)
    np.testing.assert_allclose(c, c2, atol=1e-6)
    scale = max(ixx2, iyy2)
    for got, want in ((ixx, ixx2), (iyy, iyy2), (ixy, ixy2)):
        assert got == pytest.approx(want, abs=2e-5 * scale)


def test_rounded_moments_of_a_disk_and_a_stadium_are_exact():
    area, c, ixx, iyy, ixy = rounded_moments(np.array([[0.0, 0.0]]), 2.0)
    assert area == pytest.approx(4 * math.pi) and ixx == pytest.approx(4 * math.pi)
    assert iyy == pytest.approx(ixx) and ixy == pytest.approx(0.0, abs=1e-12)
    # a stadium: a 2 x 2r rectangle and a disk of radius r
    r, length = 0.5, 2.0
    area, c, ixx, iyy, ixy = rounded_moments(np.array([[-1.0, 0.0], [1.0, 0.0]]), r)
    assert area == pytest.approx(length * 2 * r + math.pi * r * r)
    assert c.tolist() == pytest.approx([0.0, 0.0], abs=1e-12)
