"""Wall clipping of the built-in inserters against a dense sampling oracle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.geometry.domain import Circle, ConvexPolygon
from regopack.plugins.common.walls import (
    WALL_CIRCLE,
    WALL_HALFPLANES,
    clip_closed_circle,
    clip_closed_halfplanes,
    particle_offsets,
    point_fits,
    wall_arrays,
    wrap_periodic,
)

SAMPLES = 2001


def _outline(rng: np.random.Generator, scale: float) -> np.ndarray:
    t = np.sort(rng.uniform(0, 2 * np.pi, 7))
    r = rng.uniform(0.5, 1.0, 7)
    return scale * np.column_stack([r * np.cos(t), r * np.sin(t)])


def _oracle(a, d, q, mode, walls):
    s = np.linspace(0.0, 1.0, SAMPLES)
    vx = np.ascontiguousarray(q[:, 0])
    vy = np.ascontiguousarray(q[:, 1])
    return s, np.array(
        [point_fits(a[0] + t * d[0], a[1] + t * d[1], vx, vy, 0, len(q), mode, walls) for t in s]
    )


def _check(s, fits, lo, hi):
    inside = (s >= lo) & (s <= hi)
    step = 1.0 / (SAMPLES - 1)
    near_end = (np.abs(s - lo) < 2 * step) | (np.abs(s - hi) < 2 * step)
    assert np.array_equal(inside[~near_end], fits[~near_end])


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), scale=st.sampled_from([1e-6, 1.0, 1e6]))
def test_circle_clip_matches_sampling(seed, scale) -> None:
    rng = np.random.default_rng(seed)
    q = _outline(rng, scale)
    mode, walls = wall_arrays(Circle(0.3 * scale, -0.2 * scale, 3.0 * scale))
    assert mode == WALL_CIRCLE
    a = rng.uniform(-3, 3, 2) * scale
    d = rng.uniform(-4, 4, 2) * scale
    reach = float(np.hypot(q[:, 0], q[:, 1]).max())
    # the kernel reads the reflected outline: pass -q with sign -1
    lo, hi = clip_closed_circle(
        a[0], a[1], d[0], d[1], -q[:, 0].copy(), -q[:, 1].copy(), len(q), -1.0, reach, walls
    )
    s, fits = _oracle(a, d, q, mode, walls)
    _check(s, fits, lo, hi)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), scale=st.sampled_from([1e-6, 1.0, 1e6]))
def test_halfplane_clip_matches_sampling(seed, scale) -> None:
    rng = np.random.default_rng(seed)
    q = _outline(rng, scale)
    t = np.sort(rng.uniform(0, 2 * np.pi, 5))
    t = t if np.diff(np.r_[t, t[0] + 2 * np.pi]).max() < np.pi else np.arange(5) * 1.2566
    domain = ConvexPolygon(tuple(map(tuple, 3.0 * scale * np.column_stack([np.cos(t), np.sin(t)]))))
    mode, walls = wall_arrays(domain)
    assert mode == WALL_HALFPLANES
    off = np.empty(walls.shape[0])
    particle_offsets(
        np.ascontiguousarray(q[:, 0]), np.ascontiguousarray(q[:, 1]), 0, len(q), walls, off
    )
    a = rng.uniform(-3, 3, 2) * scale
    d = rng.uniform(-4, 4, 2) * scale
    lo, hi = clip_closed_halfplanes(a[0], a[1], d[0], d[1], walls, off)
    s, fits = _oracle(a, d, q, mode, walls)
    _check(s, fits, lo, hi)


def test_tangent_to_the_circular_wall_is_admissible() -> None:
    q = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    mode, walls = wall_arrays(Circle(0.0, 0.0, 5.0))
    # centre at (4, y): the vertex (1, 0) touches the wall at y = 0 only
    lo, hi = clip_closed_circle(
        4.0, -1.0, 0.0, 2.0, -q[:, 0].copy(), -q[:, 1].copy(), 4, -1.0, 1.0, walls
    )
    assert lo == pytest.approx(0.5) and hi == pytest.approx(0.5)
    assert point_fits(4.0, 0.0, q[:, 0].copy(), q[:, 1].copy(), 0, 4, mode, walls)


@pytest.mark.parametrize(("x", "expected"), [(10.0, 0.0), (-1e-300, 0.0), (25.0, 5.0), (0.0, 0.0)])
def test_wrap_stays_in_the_half_open_interval(x, expected) -> None:
    out = wrap_periodic(x, 0.0, 10.0)
    assert 0.0 <= out < 10.0
    assert out == pytest.approx(expected)
