"""Convex-polygon primitives of the available-surface kernels, against shapely."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.inserters.available_surface.polygon import (
    bounding_box,
    clip_polygon,
    convex_hull_2d,
    is_thin,
    plane_frame,
    polygon_area,
    polygon_perimeter,
    split_polygon,
    thickness,
)


def rows_of(*polys: np.ndarray, width: int = 64) -> np.ndarray:
    """A scratch array holding the polygons as row pairs 0-1, 2-3, ..."""
    rows = np.zeros((max(8, 2 * len(polys) + 1), width))
    for i, p in enumerate(polys):
        rows[2 * i, : len(p)] = p[:, 0]
        rows[2 * i + 1, : len(p)] = p[:, 1]
    return rows


def random_convex(rng: np.random.Generator, n: int = 12) -> np.ndarray:
    """A random convex polygon, counter-clockwise, without its closing vertex."""
    hull = shapely.MultiPoint(rng.normal(size=(n, 2))).convex_hull
    ring = shapely.geometry.polygon.orient(hull, 1.0).exterior
    return np.array(ring.coords)[:-1]


def half_plane(a: float, b: float, c: float, size: float = 100.0) -> shapely.Polygon:
    """A large rectangle standing for the half-plane ``c - a x - b y >= 0``."""
    norm = np.hypot(a, b)
    base = np.array([a, b]) * c / norm**2  # on the line
    along = np.array([-b, a]) / norm
    inward = -np.array([a, b]) / norm
    return shapely.Polygon(
        [base - size * along, base + size * along,
         base + size * along + size * inward, base - size * along + size * inward]
    )  # fmt: skip


@pytest.mark.parametrize("n", [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.6, 0.0, 0.8)])
def test_plane_frame_is_right_handed(n: tuple[float, float, float]) -> None:
    e = np.array(plane_frame(*n))
    e1, e2 = e[:3], e[3:]
    assert np.allclose(np.cross(e1, e2), n)
    assert np.isclose(e1 @ e1, 1.0) and np.isclose(e2 @ e2, 1.0) and abs(e1 @ e2) < 1e-15


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 60), scale=st.sampled_from([1e-6, 1e6]))
@settings(max_examples=200, deadline=None)
def test_convex_hull_matches_shapely(seed: int, n: int, scale: float) -> None:
    rng = np.random.default_rng(seed)
    unit = rng.normal(size=(n, 2))
    if n > 3 and rng.random() < 0.5:  # points on a lattice: many collinear and duplicates
        unit = np.round(rng.uniform(-3, 3, size=(n, 2)))
    pts = unit * scale
    out = np.empty(2 * n + 1, dtype=np.int64)
    k = convex_hull_2d(pts[:, 0].copy(), pts[:, 1].copy(), n, 1e-9 * scale, out)
    # the corners are counted on the unscaled points: scaled by 1e-6 or 1e6, points
    # of the lattice that lie on one line may leave it by a rounding error, which
    # the hull's tolerance ignores and the reference would count as a corner
    ref_unit = shapely.MultiPoint(unit).convex_hull
    if ref_unit.geom_type != "Polygon":
        assert k <= 2
        return
    ref = shapely.MultiPoint(pts).convex_hull
    corners = pts[out[:k]]
    poly = shapely.Polygon(corners)
    assert poly.exterior.is_ccw
    assert poly.area == pytest.approx(ref.area, rel=1e-12)
    # only true corners: as many as the reference polygon without its collinear points
    assert k == len(shapely.Polygon(ref_unit.exterior.coords).simplify(0).exterior.coords) - 1


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_a_corner_is_a_point_farther_than_the_tolerance_from_its_neighbours_line(
    scale: float,
) -> None:
    # a square with a point near the middle of its bottom side, pushed out by a
    # multiple of the tolerance, and collinear points along the other sides
    tol = 1e-9 * scale
    for push, corners in ((3.0, 5), (0.3, 4)):
        x = np.array([0.0, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 0.0, 0.0]) * scale
        y = np.array([0.0, -push * 1e-9, 0.0, 0.5, 1.5, 2.0, 2.0, 2.0, 1.0]) * scale
        out = np.empty(2 * len(x) + 1, dtype=np.int64)
        k = convex_hull_2d(x, y, len(x), tol, out)
        assert k == corners, (scale, push)
        assert (1 in out[:k]) == (corners == 5)


def test_collinear_points_are_not_corners() -> None:
    x = np.array([0.0, 1.0, 2.0, 2.0, 2.0, 1.0, 0.0, 0.0, 1.0, 1.0])
    y = np.array([0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 1.0, 1.0, 0.0])
    out = np.empty(21, dtype=np.int64)
    k = convex_hull_2d(x, y, 10, 1e-12, out)
    assert k == 4
    assert sorted(zip(x[out[:k]], y[out[:k]], strict=True)) == [(0, 0), (0, 2), (2, 0), (2, 2)]
    # all on a line: no polygon
    k = convex_hull_2d(x[:3].copy(), y[:3].copy(), 3, 1e-12, out)
    assert k == 2


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=200, deadline=None)
def test_split_and_clip_match_shapely(seed: int) -> None:
    rng = np.random.default_rng(seed)
    poly = random_convex(rng)
    n = len(poly)
    a, b = rng.normal(size=2)
    c = rng.normal()
    rows = rows_of(poly)
    rows[6, :n] = c - a * poly[:, 0] - b * poly[:, 1]  # g >= 0 inside
    nin, nout = split_polygon(rows, 0, 1, n, 6, 2, 3, 4, 5)
    shape = shapely.Polygon(poly)
    inside = shape.intersection(half_plane(a, b, c))
    got_in = polygon_area(rows, 2, 3, 0, nin) if nin >= 3 else 0.0
    got_out = polygon_area(rows, 4, 5, 0, nout) if nout >= 3 else 0.0
    assert got_in + got_out == pytest.approx(shape.area, rel=1e-12)
    assert got_in == pytest.approx(inside.area, rel=1e-9, abs=1e-12)
    k = clip_polygon(rows, 0, 1, n, 6, 2, 3)
    assert k == nin
    assert polygon_area(rows, 2, 3, 0, k) == pytest.approx(got_in, rel=1e-12, abs=1e-300)


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=50, deadline=None)
def test_the_two_parts_of_a_split_share_their_cut_points_exactly(seed: int) -> None:
    rng = np.random.default_rng(seed)
    poly = random_convex(rng) * 10.0 ** rng.uniform(-6, 6)
    n = len(poly)
    rows = rows_of(poly)
    a, b = rng.normal(size=2)
    rows[6, :n] = a * poly[:, 0] + b * poly[:, 1] - rng.normal() * np.abs(poly).max()
    nin, nout = split_polygon(rows, 0, 1, n, 6, 2, 3, 4, 5)
    inside = {(x, y) for x, y in zip(rows[2, :nin], rows[3, :nin], strict=True)}
    outside = {(x, y) for x, y in zip(rows[4, :nout], rows[5, :nout], strict=True)}
    corners = {(x, y) for x, y in poly}
    g = rows[6, :n]
    crossings = int(np.sum(g * np.roll(g, -1) < 0.0))  # edges whose ends lie strictly apart
    # the cut points (not corners of the polygon) stand in both parts, bit for bit
    assert len(inside - corners) == crossings
    assert inside - corners == outside - corners


def test_split_keeps_vertices_on_the_line_on_both_sides() -> None:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    rows = rows_of(square)
    rows[6, :4] = 0.5 - square[:, 0]  # inside: x <= 0.5
    nin, nout = split_polygon(rows, 0, 1, 4, 6, 2, 3, 4, 5)
    assert nin == 4 and nout == 4
    assert polygon_area(rows, 2, 3, 0, nin) == pytest.approx(0.5)
    rows[6, :4] = 1.0 - square[:, 0]  # the line through an edge: nothing outside
    nin, nout = split_polygon(rows, 0, 1, 4, 6, 2, 3, 4, 5)
    assert nin == 4 and polygon_area(rows, 4, 5, 0, nout) == 0.0


def test_measures_of_a_rectangle() -> None:
    rect = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1e-3], [0.0, 1e-3]])
    rows = rows_of(rect)
    assert polygon_area(rows, 0, 1, 0, 4) == pytest.approx(4e-3)
    assert polygon_perimeter(rows, 0, 1, 4) == pytest.approx(8.002)
    assert thickness(rows, 0, 1, 4) == pytest.approx(2 * 4e-3 / 8.002)
    assert is_thin(rows, 0, 1, 4, 1.1e-3) and not is_thin(rows, 0, 1, 4, 0.9e-3)
    assert is_thin(rows, 0, 1, 2, 1.0)  # fewer than 3 vertices
    assert bounding_box(rows, 0, 1, 4) == pytest.approx((2.0, 5e-4, 2.0, 5e-4))
    # clockwise: negative area
    rows = rows_of(rect[::-1].copy())
    assert polygon_area(rows, 0, 1, 0, 4) == pytest.approx(-4e-3)
