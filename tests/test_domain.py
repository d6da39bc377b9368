"""Domain geometry: areas, windows, containment, exact clipping and the file record."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

from regopack.domain import (
    Circle,
    ConvexPolygon,
    PeriodicRectangle,
    Rectangle,
    domain_from_dict,
    polygon_disk_area,
)
from regopack.errors import GeometryError

TRIANGLE = ((0.0, 0.0), (4.0, 0.0), (0.0, 3.0))


def test_polygon_area_centroid_and_orientation() -> None:
    clockwise = ConvexPolygon(TRIANGLE[::-1])
    assert clockwise.area == pytest.approx(6.0)
    assert clockwise.center == pytest.approx((4 / 3, 1.0))
    assert shapely.Polygon(clockwise.outline()).exterior.is_ccw


@pytest.mark.parametrize(
    "corners",
    [
        ((0, 0), (1, 0)),
        ((0, 0), (1, 0), (2, 0)),
        ((0, 0), (2, 0), (1, 0.5), (2, 2), (0, 2)),
        ((0, 0), (1, 0), (1, 0), (0, 1)),
        ((0, 0), (1, 0), (0, 1), (1, 1)),
        ((0, 0), (math.nan, 0), (0, 1)),
    ],
)
def test_bad_polygons_are_refused(corners) -> None:
    with pytest.raises(GeometryError):
        ConvexPolygon(tuple(corners))


def test_star_pentagon_is_refused() -> None:
    t = np.arange(5) * 4 * np.pi / 5
    with pytest.raises(GeometryError, match="simple convex"):
        ConvexPolygon(tuple(zip(np.cos(t), np.sin(t), strict=True)))


def test_interior_windows() -> None:
    rect = Rectangle.centred(10.0, 6.0)
    assert rect.interior(1.0) == Rectangle(-4.0, 4.0, -2.0, 2.0)
    assert Circle(1.0, 2.0, 5.0).interior(2.0) == Circle(1.0, 2.0, 3.0)
    assert Circle(1.0, 2.0, 5.0).interior(7.0).area == 0.0
    tri = ConvexPolygon(TRIANGLE)
    inset = tri.interior(0.5)
    normal, offset = tri.halfplanes()
    # every corner of the inset lies 0.5 inside every wall it is on, and no closer to any
    dist = offset[None, :] - np.asarray(inset.outline()) @ normal.T
    assert dist.min() == pytest.approx(0.5)
    assert tri.interior(10.0).area == 0.0
    periodic = PeriodicRectangle.centred(10.0, 10.0)
    assert periodic.interior(3.0) is periodic


def test_contains_is_strict_and_nan_is_outside() -> None:
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [math.nan, 0.0]])
    tri = ConvexPolygon(((0.0, -1.0), (2.0, 1.0), (0.0, 1.0)))
    assert Circle(0.0, 0.0, 1.0).contains(pts).tolist() == [True, False, True, False]
    assert tri.contains(pts).tolist() == [False, False, True, False]
    assert PeriodicRectangle(0, 1, 0, 1).contains(pts + 5).tolist() == [True, True, True, False]


def test_periodic_wrap_and_minimum_image() -> None:
    d = PeriodicRectangle(0.0, 10.0, -5.0, 5.0)
    wrapped = d.wrap([[10.0, 5.0], [-0.5, -5.5], [23.0, 1.0]])
    np.testing.assert_allclose(wrapped, [[0.0, -5.0], [9.5, 4.5], [3.0, 1.0]])
    np.testing.assert_allclose(
        d.minimum_image([[9.0, 0.0], [-6.0, 9.0]]), [[-1.0, 0.0], [4.0, -1.0]]
    )


@pytest.mark.parametrize(
    "domain",
    [
        Rectangle(-1.0, 2.0, -3.0, 4.0),
        PeriodicRectangle(0.0, 1.0, 0.0, 2.0),
        ConvexPolygon(TRIANGLE),
        Circle(1.5, -2.0, 3.25),
    ],
)
def test_file_record_round_trips(domain) -> None:
    again = domain_from_dict(domain.to_dict())
    assert again == domain
    assert type(again) is type(domain)


@settings(max_examples=200, deadline=None)
@given(
    cx=st.floats(-3, 3),
    cy=st.floats(-3, 3),
    r=st.floats(0.05, 5),
    k=st.integers(3, 9),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
@example(cx=1.9375, cy=1.9375, r=1.9375, k=4, scale=1e-6)  # a sliver the 8192-gon misses
def test_polygon_disk_area_matches_a_fine_shapely_disk(cx, cy, r, k, scale) -> None:
    t = np.linspace(0, 2 * np.pi, k, endpoint=False) + 0.1
    ring = np.column_stack([np.cos(t), 1.3 * np.sin(t)])
    exact = polygon_disk_area(ring * scale, (cx * scale, cy * scale), r * scale)
    disk = shapely.Point(cx, cy).buffer(r, quad_segs=2048)
    approx = shapely.Polygon(ring).intersection(disk).area
    # the 8192-gon misses a segment of r^2 (2 pi / 8192)^3 / 12 per side, so up to about
    # 3e-7 r^2 along a whole arc (4e-8 r^2 was seen on a sliver); the exact value does not
    # move with scale
    assert exact / scale**2 == pytest.approx(approx, rel=1e-5, abs=3e-7 * r * r)


def test_circle_covered_area_is_exact_for_a_square_inside_and_across() -> None:
    c = Circle(0.0, 0.0, 1.0)
    inside = shapely.box(-0.5, -0.5, 0.5, 0.5)
    across = shapely.box(0.0, -2.0, 4.0, 2.0)  # covers the right half disk
    total = c.covered_area(np.array([inside, across], dtype=object))
    assert total == pytest.approx(1.0 + math.pi / 2, rel=1e-12)


def test_polygon_disk_area_with_edges_tangent_to_the_circle() -> None:
    import math

    from regopack.domain import polygon_disk_area

    square = [(-60.0, -60.0), (60.0, -60.0), (60.0, 60.0), (-60.0, 60.0)]
    assert polygon_disk_area(square, (0.0, 0.0), 60.0) == pytest.approx(math.pi * 3600.0)
    # one tangent edge, the disk otherwise inside
    assert polygon_disk_area(square, (0.0, 20.0), 40.0) == pytest.approx(math.pi * 1600.0)
