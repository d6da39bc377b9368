"""Envelope construction and segment clipping of the available-arc kernel."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from arc_helpers import octagon_population
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.inserters.available_arc.geometry import (
    angle_slot,
    clip_closed_box,
    clip_open_interior,
    minkowski_envelope,
    prepare_outlines,
    reflect_outline,
)


def _envelope(pop, p: int, q: int):
    vx, vy, ex, ey, ang, _circum, _box = prepare_outlines(pop.shapes.vertices, pop.shapes.offsets)
    off = pop.shapes.offsets
    mq = int(off[q + 1] - off[q])
    r = [np.empty(mq) for _ in range(5)]
    reflect_outline(q, vx, vy, ex, ey, ang, off, *r)
    cap = int(off[p + 1] - off[p]) + mq
    w = [np.empty(cap) for _ in range(4)]
    n = minkowski_envelope(p, vx, vy, ex, ey, ang, off, *r, mq, *w)
    return n, w


@given(
    seed=st.integers(0, 2**32 - 1),
    psi=st.floats(0.01, 1000),
    a=st.floats(0.05, 1.0),
    mp=st.sampled_from([3, 5, 8, 13]),
    ratio=st.floats(1e-4, 1e4),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
@settings(max_examples=150, deadline=None)
def test_envelope_is_the_hull_of_all_vertex_differences(seed, psi, a, mp, ratio, scale) -> None:
    rng = np.random.default_rng(seed)
    pop_p = octagon_population(np.array([scale]), rng, psi=psi, a=a, m=mp)
    pop_q = octagon_population(np.array([scale * ratio]), rng, psi=psi, a=a, m=8)
    from regopack.geometry.population import Population, concat_shapes

    shapes = concat_shapes([(np.array([0]), pop_p.shapes), (np.array([1]), pop_q.shapes)], 2)
    pop = Population(np.array([scale, scale * ratio]), np.zeros(2, dtype=np.int64), ("m",), shapes)
    n, (wx, wy, wex, wey) = _envelope(pop, 0, 1)
    assert n == mp + 8
    P = shapes.outline(0)
    Q = shapes.outline(1)
    diffs = (P[:, None, :] - Q[None, :, :]).reshape(-1, 2)
    hull = shapely.MultiPoint(diffs).convex_hull
    env = shapely.Polygon(np.column_stack([wx[:n], wy[:n]]))
    size = max(hull.length, 1e-300)
    assert env.area == pytest.approx(hull.area, rel=1e-9, abs=1e-12 * size**2)
    assert shapely.hausdorff_distance(env.exterior, hull.exterior) <= 1e-9 * size
    # the unit edge directions follow the outline counter-clockwise
    e = np.column_stack([np.roll(wx[:n], -1) - wx[:n], np.roll(wy[:n], -1) - wy[:n]])
    cross = wex[:n] * e[:, 1] - wey[:n] * e[:, 0]
    assert np.all(np.abs(cross) <= 1e-9 * size)
    assert np.all(wex[:n] * e[:, 0] + wey[:n] * e[:, 1] >= -1e-9 * size)


def test_angle_slot_wraps_by_whole_turns_and_finds_the_slot() -> None:
    va = np.array([-1.0, 0.5, 2.0, -1.0 + 2 * np.pi])  # three slots of one turn
    assert angle_slot(va, 3, 0.0) == (0.0, 0)
    assert angle_slot(va, 3, 1.0) == (1.0, 1)
    assert angle_slot(va, 3, 0.5) == (0.5, 0)  # a bound belongs to the slot below it
    a, j = angle_slot(va, 3, 1.0 + 4 * np.pi)
    assert j == 1 and a == pytest.approx(1.0, abs=1e-12)
    a, j = angle_slot(va, 3, -2.0)  # below the first bound: one turn up, in the last slot
    assert j == 2 and a == pytest.approx(-2.0 + 2 * np.pi, abs=1e-12)


def test_clip_open_interior_square() -> None:
    # unit square, counter-clockwise, edge directions
    wx = np.array([0.0, 1.0, 1.0, 0.0])
    wy = np.array([0.0, 0.0, 1.0, 1.0])
    wex = np.array([1.0, 0.0, -1.0, 0.0])
    wey = np.array([0.0, 1.0, 0.0, -1.0])
    lo, hi = clip_open_interior(-1.0, 0.5, 3.0, 0.0, wx, wy, wex, wey, 4)
    assert lo == pytest.approx(1 / 3) and hi == pytest.approx(2 / 3)
    # a segment along an edge is not inside the open interior (tangent contact)
    lo, hi = clip_open_interior(-1.0, 0.0, 3.0, 0.0, wx, wy, wex, wey, 4)
    assert not lo < hi
    lo, hi = clip_open_interior(-1.0, 2.0, 3.0, 0.0, wx, wy, wex, wey, 4)
    assert not lo < hi


def test_clip_closed_box() -> None:
    lo, hi = clip_closed_box(-2.0, 0.0, 4.0, 0.0, -1.0, 1.0, -1.0, 1.0)
    assert (lo, hi) == (0.25, 0.75)
    lo, hi = clip_closed_box(-2.0, 5.0, 4.0, 0.0, -1.0, 1.0, -1.0, 1.0)
    assert lo > hi
    lo, hi = clip_closed_box(0.0, -2.0, 0.0, 4.0, -1.0, 1.0, -1.0, 1.0)
    assert (lo, hi) == (0.25, 0.75)


def test_prepare_outlines_orders_edges() -> None:
    pop = octagon_population(np.ones(200), np.random.default_rng(1), psi=0.05, a=1.0)
    outlines = prepare_outlines(pop.shapes.vertices, pop.shapes.offsets)
    ang, circum = outlines[4], outlines[5]
    a = ang.reshape(200, 8)
    assert np.all(np.diff(a, axis=1) >= 0)
    assert np.all((a >= 0) & (a < 2 * np.pi))
    d = np.hypot(pop.shapes.vertices[:, 0], pop.shapes.vertices[:, 1]).reshape(200, 8)
    assert np.allclose(circum, d.max(axis=1))


def _with_collinear_points(outline: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The same polygon with points inserted inside random edges, listed from a random vertex."""
    out = []
    for k in range(len(outline)):
        a, b = outline[k], outline[(k + 1) % len(outline)]
        out.append(a)
        for t in sorted(rng.random(rng.integers(0, 3))):
            out.append(a + t * (b - a))
    out = np.array(out)
    return np.roll(out, -int(rng.integers(0, len(out))), axis=0)


@given(seed=st.integers(0, 2**32 - 1), m=st.sampled_from([3, 4, 5, 8]))
@settings(max_examples=200, deadline=None)
def test_envelope_with_collinear_vertices(seed: int, m: int) -> None:
    from regopack.geometry.population import Population, ShapeBatch

    rng = np.random.default_rng(seed)
    base = octagon_population(np.array([1.0, 1.3]), rng, psi=1.0, m=m)
    p_out = _with_collinear_points(base.shapes.outline(0), rng)
    q_out = _with_collinear_points(base.shapes.outline(1), rng)
    shapes = ShapeBatch(
        np.concatenate([p_out, q_out]),
        np.array([0, len(p_out), len(p_out) + len(q_out)]),
        np.zeros(2),
    )
    pop = Population(np.array([1.0, 1.3]), np.zeros(2, dtype=np.int64), ("m",), shapes)
    n, (wx, wy, _, _) = _envelope(pop, 0, 1)
    hull = shapely.MultiPoint((p_out[:, None, :] - q_out[None, :, :]).reshape(-1, 2)).convex_hull
    env = shapely.Polygon(np.column_stack([wx[:n], wy[:n]]))
    assert env.symmetric_difference(hull).area <= 1e-9 * hull.area


def test_split_lowest_edge_listed_first() -> None:
    """A collinear vertex at the start of the lowest edge must not reorder the edges."""
    from regopack.geometry.population import Population, ShapeBatch

    p_out = np.array([[0.3, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]], dtype=float)
    th = 0.4
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    q_out = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) @ rot.T
    for first, second in ((p_out, q_out), (q_out, p_out)):
        shapes = ShapeBatch(
            np.concatenate([first, second]), np.array([0, len(first), 9]), np.zeros(2)
        )
        pop = Population(np.array([1.0, 1.0]), np.zeros(2, dtype=np.int64), ("m",), shapes)
        n, (wx, wy, _, _) = _envelope(pop, 0, 1)
        hull = shapely.MultiPoint(
            (first[:, None, :] - second[None, :, :]).reshape(-1, 2)
        ).convex_hull
        env = shapely.Polygon(np.column_stack([wx[:n], wy[:n]]))
        assert env.symmetric_difference(hull).area <= 1e-12 * hull.area


def test_clip_against_an_empty_box_is_empty() -> None:
    lo, hi = clip_closed_box(-2.0, 0.0, 4.0, 1.0, 1.0, -1.0, -1.0, 1.0)
    assert lo > hi


def _clip_oracle(ax, ay, dx, dy, wx, wy, wex, wey, n):
    """The clip side by side, stopping at the first empty interval (plain Python floats)."""
    lo, hi = -np.inf, np.inf
    for j in range(n):
        f0 = float(wex[j]) * (ay - float(wy[j])) - float(wey[j]) * (ax - float(wx[j]))
        f1 = float(wex[j]) * dy - float(wey[j]) * dx
        if f1 > 0.0:
            lo = max(lo, -f0 / f1)
        elif f1 < 0.0:
            hi = min(hi, -f0 / f1)
        elif f0 <= 0.0:
            return 1.0, 0.0
        if lo >= hi:
            return lo, hi
    return lo, hi


@given(
    seed=st.integers(0, 2**32 - 1),
    psi=st.floats(0.01, 1000),
    ratio=st.floats(1e-4, 1e4),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    kind=st.sampled_from(["random", "along an edge", "through a vertex", "parallel"]),
)
@settings(max_examples=200, deadline=None)
def test_clip_and_inside_match_the_side_by_side_tests(seed, psi, ratio, scale, kind) -> None:
    """The branch-free clip and the point test without early exit give what testing the
    sides one by one gives: the same interval when it is not empty, empty when it is;
    points on the outline (vertices, edge midpoints) are outside the open interior."""
    from regopack.geometry.population import Population, concat_shapes
    from regopack.plugins.inserters.available_arc.geometry import inside_open

    rng = np.random.default_rng(seed)
    pop_p = octagon_population(np.array([scale]), rng, psi=psi, a=0.5, m=8)
    pop_q = octagon_population(np.array([scale * ratio]), rng, psi=psi, a=0.5, m=8)
    shapes = concat_shapes([(np.array([0]), pop_p.shapes), (np.array([1]), pop_q.shapes)], 2)
    pop = Population(np.array([scale, scale * ratio]), np.zeros(2, dtype=np.int64), ("m",), shapes)
    n, (wx, wy, wex, wey) = _envelope(pop, 0, 1)
    size = float(np.ptp(wx[:n]) + np.ptp(wy[:n]))
    for _ in range(20):
        j = int(rng.integers(n))
        j2 = (j + 1) % n
        if kind == "along an edge":
            ax, ay = float(wx[j]), float(wy[j])
            dx, dy = float(wx[j2] - wx[j]), float(wy[j2] - wy[j])
        elif kind == "through a vertex":
            ax, ay = float(wx[j]), float(wy[j])
            dx, dy = rng.normal(size=2) * size
        elif kind == "parallel":
            t = rng.uniform(-1, 1) * size
            ax, ay = float(wx[j] - wey[j] * t), float(wy[j] + wex[j] * t)
            dx, dy = float(wex[j]) * size, float(wey[j]) * size
        else:
            ax, ay = rng.uniform(-1, 1, 2) * size
            dx, dy = rng.normal(size=2) * size
        got = clip_open_interior(ax, ay, dx, dy, wx, wy, wex, wey, n)
        want = _clip_oracle(ax, ay, dx, dy, wx, wy, wex, wey, n)
        assert (got[0] < got[1]) == (want[0] < want[1])
        if want[0] < want[1]:
            assert got == want
        px, py = rng.uniform(-0.6, 0.6, 2) * size
        side = [
            float(wex[k]) * (py - float(wy[k])) - float(wey[k]) * (px - float(wx[k]))
            for k in range(n)
        ]
        assert inside_open(px, py, wx, wy, wex, wey, n) == all(c > 0.0 for c in side)
        assert not inside_open(float(wx[j]), float(wy[j]), wx, wy, wex, wey, n)
