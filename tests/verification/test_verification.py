from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import regopack.testing
from regopack.testing import packing_from_polygons
from regopack.verification.polygons import VerifyReport, assert_valid_packing, verify

SQUARE = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])


def squares(*corners, size=1.0):
    return [SQUARE * size + np.asarray(c, dtype=float) for c in corners]


def test_tangent_squares_are_valid():
    p = packing_from_polygons(squares((0, 0), (1, 0), (0, 1), (1, 1)), domain=(0, 2, 0, 2))
    report = verify(p)
    assert report.ok
    assert report.n_checked == 4
    assert report.n_overlapping_pairs == 0
    assert report.worst_overlap is None
    assert report.n_outside == 0
    assert report.worst_outside is None


def test_overlap_is_detected():
    p = packing_from_polygons(squares((0, 0), (3, 0), (3.5, 0)), domain=(0, 5, 0, 1))
    report = verify(p)
    assert not report.ok
    assert report.n_overlapping_pairs == 1
    assert report.worst_overlap is not None
    i, j, frac = report.worst_overlap
    assert (i, j) == (1, 2)
    assert frac == pytest.approx(0.5)
    assert report.n_outside == 0


def test_overlap_relative_to_smaller_particle():
    big = SQUARE * 10
    small = SQUARE * 1 + (9.5, 0)
    report = verify(packing_from_polygons([big, small], domain=(0, 20, 0, 10)))
    assert report.worst_overlap == (0, 1, pytest.approx(0.5))


def test_worst_overlap_is_the_largest():
    p = packing_from_polygons(squares((0, 0), (0.9, 0), (5, 0), (5.5, 0)), domain=(0, 7, 0, 1))
    report = verify(p)
    assert report.n_overlapping_pairs == 2
    assert report.worst_overlap[:2] == (2, 3)


def test_contained_particle_is_an_overlap():
    p = packing_from_polygons([SQUARE * 4, SQUARE + 1], domain=(0, 4, 0, 4))
    assert verify(p).worst_overlap == (0, 1, pytest.approx(1.0))


def test_out_of_domain_is_detected():
    p = packing_from_polygons(squares((0, 0), (1.75, 0)), domain=(0, 2, 0, 1))
    report = verify(p)
    assert not report.ok
    assert report.n_outside == 1
    assert report.worst_outside == (1, pytest.approx(0.75))
    assert report.n_overlapping_pairs == 0


def test_particle_touching_the_walls_is_inside():
    p = packing_from_polygons(squares((0, 0)), domain=(0, 1, 0, 1))
    assert verify(p).ok


def test_particle_entirely_outside():
    p = packing_from_polygons(squares((5, 5)), domain=(0, 1, 0, 1))
    assert verify(p).worst_outside == (0, pytest.approx(1.0))


def test_unplaced_particles_are_ignored():
    p = packing_from_polygons(
        squares((0, 0), (0.5, 0), (9, 9)), domain=(0, 2, 0, 1), placed=[True, False, False]
    )
    report = verify(p)
    assert report.ok
    assert report.n_checked == 1


def test_empty_packing_is_valid():
    assert verify(packing_from_polygons([], domain=(0, 1, 0, 1))).ok


def test_rel_tol():
    # overlap of 1e-6 of the area
    p = packing_from_polygons(squares((0, 0), (1 - 1e-6, 0)), domain=(0, 3, 0, 1))
    assert not verify(p).ok
    assert verify(p, rel_tol=1e-5).ok


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1.0, 1e3, 1e6])
@pytest.mark.parametrize("shift", [0.0, 1.0, -100.0])
def test_scale_invariance(scale, shift):
    corners = [(x, y) for x in range(4) for y in range(3)]
    origin = shift * 10 * scale
    polys = [(SQUARE + c) * scale + origin for c in corners]
    dom = (origin, origin + 4 * scale, origin, origin + 3 * scale)
    assert verify(packing_from_polygons(polys, domain=dom)).ok
    bad = [*polys, (SQUARE + np.array([0.5, 0.5])) * scale + origin]
    report = verify(packing_from_polygons(bad, domain=dom))
    assert report.n_overlapping_pairs == 4
    assert report.worst_overlap[2] == pytest.approx(0.25)


@settings(max_examples=30, deadline=None)
@given(
    st.floats(min_value=-6, max_value=6),
    st.floats(min_value=0, max_value=2 * np.pi),
    st.integers(min_value=2, max_value=6),
)
def test_rotated_tangent_grid_is_valid(log_scale, angle, k):
    scale = 10.0**log_scale
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    polys = [((SQUARE + np.array([x, y])) @ rot.T) * scale for x in range(k) for y in range(k)]
    allv = np.concatenate(polys)
    dom = (allv[:, 0].min(), allv[:, 0].max(), allv[:, 1].min(), allv[:, 1].max())
    assert verify(packing_from_polygons(polys, domain=dom)).ok


def test_report_text():
    report = verify(
        packing_from_polygons(squares((0, 0), (0.5, 0), (1.75, 0)), domain=(0, 2, 0, 1))
    )
    text = str(report)
    assert "VIOLATED" in text
    assert "particles 0 and 1" in text
    assert "particle 2" in text
    assert "OK" in str(verify(packing_from_polygons(squares((0, 0)), domain=(0, 1, 0, 1))))


def test_assert_valid_packing():
    good = packing_from_polygons(squares((0, 0), (1, 0)), domain=(0, 2, 0, 1))
    assert isinstance(assert_valid_packing(good), VerifyReport)
    bad = packing_from_polygons(squares((0, 0), (0.5, 0)), domain=(0, 2, 0, 1))
    with pytest.raises(AssertionError, match="overlapping pairs: 1"):
        assert_valid_packing(bad)
    assert regopack.testing.assert_valid_packing is assert_valid_packing


def test_a_large_touching_packing_is_verified():
    """40 000 touching particles: every one checked, none overlapping (the time a
    verification takes is measured by the asv suite, ``benchmarks/benchmarks/verification.py``)."""
    p = regopack.testing.touching_squares(200)
    report = verify(p)
    assert report.ok
    assert report.n_checked == 40_000


@pytest.mark.parametrize(
    ("shift", "ok"), [(0.0, True), (0.25, False), (-0.25, True)], ids=["tangent", "overlap", "gap"]
)
def test_periodic_pairs_are_compared_through_the_side(shift, ok) -> None:
    from regopack.geometry.domain import PeriodicRectangle

    domain = PeriodicRectangle(0.0, 10.0, 0.0, 10.0)
    sq = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    # centres at 0.5 and 9.5 + shift (wrapped): the squares meet across x = 0 = 10
    right = domain.wrap([[9.5 + shift, 5.2]])[0]
    p = packing_from_polygons([sq + (0.5, 5.0), sq + right], domain=domain)
    report = verify(p)
    assert report.ok is ok, str(report)
    assert report.n_outside == 0


@pytest.mark.parametrize(
    ("centre", "ok"), [((2.0, 0.0), True), ((2.2, 0.0), False)], ids=["inside", "across"]
)
def test_circle_and_polygon_walls(centre, ok) -> None:
    from regopack.geometry.domain import Circle, ConvexPolygon

    sq = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    # the corner (2.5, 0.5) lies inside radius 2.55 at x = 2; at x = 2.2 it pokes out
    circle = Circle(0.0, 0.0, float(np.hypot(2.5, 0.5)) + 1e-12)
    report = verify(packing_from_polygons([sq + centre], domain=circle))
    assert report.ok is ok, str(report)
    tri = ConvexPolygon(((-5.0, -5.0), (2.5, -5.0), (2.5, 5.0)))  # wall x = 2.5
    report = verify(packing_from_polygons([sq + (2.0, -2.0), sq + (2.2, -3.0)], domain=tri))
    assert report.n_outside == 1 and report.worst_outside is not None
    assert report.worst_outside[0] == 1
    assert report.worst_outside[1] == pytest.approx(0.2)


@pytest.mark.parametrize(
    ("k", "scale"), [(0, 1.0), (-3, 1.0), (2.5, 1.0), (2, 0.0), (2, float("nan"))]
)
def test_touching_squares_refuses_a_bad_grid(k, scale) -> None:
    with pytest.raises(ValueError, match=r"touching_squares: (k|scale) = .*allowed"):
        regopack.testing.touching_squares(k, scale)


def test_touching_squares_touch_and_do_not_overlap() -> None:
    report = verify(regopack.testing.touching_squares(3, scale=1e-6))
    assert report.ok and report.n_checked == 9


@pytest.mark.parametrize("far", [1e17, 1e6, 12.0])
@pytest.mark.parametrize(
    "domain",
    [
        (0, 10, 0, 10),
        regopack.geometry.domain.Circle(5.0, 5.0, 5.0),
        regopack.geometry.domain.ConvexPolygon(
            np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
        ),
    ],
    ids=["rectangle", "circle", "polygon"],
)
def test_a_particle_far_outside_is_outside(far, domain):
    """Containment is decided on coordinates: beyond ~1e17 an outline rounds to a point
    in the frame of the domain, and a particle there used to pass."""
    p = packing_from_polygons(squares((4, 4), (6, 4)), domain=domain)
    p = dataclasses.replace(p, centre=p.centre + [[0.0, 0.0], [far, 0.0]])
    report = verify(p)
    assert not report.ok
    assert report.n_outside == 1
    assert report.worst_outside == (1, pytest.approx(1.0))
