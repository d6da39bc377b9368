"""Direction sets of the random polyhedra and their validation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from regopack.plugins.shapes.polyhedra.directions import (
    check_directions,
    cube,
    fibonacci,
    hull_depth,
    rhombic_dodecahedron,
    truncated_octahedron,
)

SETS = {
    "cube": (cube, 6),
    "truncated_octahedron": (truncated_octahedron, 14),
    "rhombic_dodecahedron": (rhombic_dodecahedron, 12),
}


def _bounded(d: np.ndarray) -> bool:
    """Whether {x : d x <= 1} is bounded, by linear programming along ±x, ±y, ±z.

    The variables are boxed to ±1e8 (so that every program has an optimum); the
    tests call this only when the polyhedron, if bounded, lies within 1e6.
    """
    box = [(-1e8, 1e8)] * 3
    for c in np.vstack([np.eye(3), -np.eye(3)]):
        res = linprog(-c, A_ub=d, b_ub=np.ones(len(d)), bounds=box, method="highs")
        assert res.status == 0
        if -res.fun > 1e7:
            return False
    return True


@pytest.mark.parametrize("name", SETS)
def test_named_sets_are_valid_unit_and_distinct(name: str) -> None:
    make, m = SETS[name]
    d = make()
    assert d.shape == (m, 3) and d.dtype == np.float64 and d.flags.c_contiguous
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-15)
    assert len({tuple(np.round(row, 12)) for row in d}) == m
    assert np.array_equal(check_directions(d), d)
    assert _bounded(d)
    # every named set is centrally symmetric
    assert all(np.any(np.all(np.isclose(d, -row), axis=1)) for row in d)


def test_truncated_octahedron_is_the_cube_and_the_octahedron_normals() -> None:
    d = truncated_octahedron()
    assert np.array_equal(d[:6], cube())
    diag = d[6:] * np.sqrt(3.0)
    assert np.allclose(np.abs(diag), 1.0)
    assert {tuple(np.sign(row).astype(int)) for row in diag} == set(
        itertools.product((1, -1), repeat=3)
    )


def test_rhombic_dodecahedron_normals() -> None:
    d = rhombic_dodecahedron() * np.sqrt(2.0)
    assert np.allclose(np.sort(np.abs(d), axis=1), [0.0, 1.0, 1.0])


@pytest.mark.parametrize("m", [4, 5, 6, 7, 14, 20, 57, 200, 1000])
def test_fibonacci_sets_are_valid_deterministic_and_spread(m: int) -> None:
    d = fibonacci(m)
    assert d.shape == (m, 3)
    assert np.array_equal(d, fibonacci(m))
    check_directions(d)
    # quasi-uniform: the heights are evenly spaced and the mean direction is nearly zero
    assert np.allclose(np.diff(np.sort(d[:, 2])), 2.0 / m)
    assert np.linalg.norm(d.mean(axis=0)) < 1.0 / m


@pytest.mark.parametrize("m", [-1, 0, 3, 4.0, True])
def test_fibonacci_refuses_too_few(m: object) -> None:
    with pytest.raises(ValueError, match="m >= 4"):
        fibonacci(m)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("d", "message"),
    [
        (np.ones((4, 2)), "shape"),
        (np.ones(12), "shape"),
        (cube()[:3], "at least 4"),
        (np.vstack([cube()[:5], [[np.nan, 0.0, 0.0]]]), "NaN"),
        (np.vstack([cube()[:5], [[0.0, 0.0, -1.0 - 1e-6]]]), "not a unit vector"),
        (np.vstack([cube(), cube()[2]]), "not distinct"),
        (cube()[:5], "not positively spanning"),
        # all in the upper half space: the half-spaces leave the -z direction open
        (fibonacci(40)[:20], "not positively spanning"),
        # the origin on a facet of the hull: not strictly inside
        (np.vstack([cube()[:4], [[0.0, 0.0, 1.0]]]), "not positively spanning"),
        (np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]]), "lie in a plane"),
    ],
)
def test_check_directions_refuses_with_one_line(d: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message) as info:
        check_directions(d)
    assert "\n" not in str(info.value)


@given(
    points=st.lists(
        st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda p: np.linalg.norm(p) > 0.1),
        min_size=4,
        max_size=9,
    )
)
@settings(max_examples=150, deadline=None)
def test_positive_spanning_agrees_with_linear_programming(points: list) -> None:
    d = np.array(points)
    d /= np.linalg.norm(d, axis=1)[:, None]
    try:
        depth = hull_depth(d)
    except ValueError:
        depth = 0.0  # coplanar directions bound nothing
    if abs(depth) < 1e-6:
        return  # too close to call for the linear program
    gaps = np.linalg.norm(d[:, None] - d[None], axis=2) + np.eye(len(d))
    if gaps.min() <= 1e-9:
        return
    try:
        check_directions(d)
        accepted = True
    except ValueError:
        accepted = False
    assert accepted == _bounded(d)
