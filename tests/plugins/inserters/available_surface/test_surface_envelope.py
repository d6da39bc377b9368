"""The compiled Minkowski envelope ``P ⊕ (-Q)`` against scipy's hull of all differences."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from surface_helpers import (
    box,
    check_closed_surface,
    circumradius,
    differences,
    random_polyhedron,
    rotation,
    tetrahedron,
    transformed,
)

from regopack.plugins.inserters.available_surface.envelope import (
    ANGLE_EPS,
    PARALLEL_EPS,
    _sides,
    candidate_directions,
    edge_arcs,
    minkowski_envelope,
    polyhedron_edges,
)
from regopack.plugins.inserters.available_surface.polyhedron import (
    Polyhedron,
    polyhedron_from_points,
    reflect,
    volume,
)


def check_against_hull(p: Polyhedron, q: Polyhedron) -> Polyhedron:
    """Every check of the envelope against the hull of the vertex differences."""
    env = minkowski_envelope(p, q)
    size = circumradius(p) + circumradius(q)
    tol = 1e-9 * size
    check_closed_surface(env, tol)
    diffs = differences(p, q)
    hull = ConvexHull(diffs)
    assert volume(env) == pytest.approx(hull.volume, rel=1e-9)
    # every vertex of the envelope is a difference p_i - q_j, exactly
    d = np.linalg.norm(env.vertices[:, None, :] - diffs[None, :, :], axis=2)
    assert np.all(d.min(axis=1) == 0.0)
    # every hull vertex lies on the envelope's boundary
    g = diffs[hull.vertices] @ env.normals.T - env.support
    assert np.all(np.abs(g.max(axis=1)) <= tol)
    # the same facets: normals and support values
    ref = polyhedron_from_points(diffs)
    assert len(ref.normals) == len(env.normals)
    close = np.linalg.norm(env.normals[:, None, :] - ref.normals[None, :, :], axis=2)
    match = close.argmin(axis=1)
    assert np.all(close.min(axis=1) <= 1e-7)
    assert len(np.unique(match)) == len(env.normals)
    assert np.allclose(env.support, ref.support[match], rtol=0, atol=tol)
    return env


@given(
    seed=st.integers(0, 2**32 - 1),
    npoints=st.sampled_from([4, 5, 8, 12, 24, 40]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    ratio=st.sampled_from([1e-3, 0.3, 1.0, 3.0, 1e3]),
)
@settings(max_examples=120, deadline=None)
def test_random_polyhedra(seed: int, npoints: int, scale: float, ratio: float) -> None:
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng, npoints, scale)
    q = random_polyhedron(rng, int(rng.integers(4, 30)), scale * ratio)
    check_against_hull(p, q)


@given(seed=st.integers(0, 2**32 - 1), aspect=st.sampled_from([10.0, 100.0, 1000.0]))
@example(seed=3513128, aspect=1000.0).xfail(
    raises=AssertionError,
    reason="a sliver face beside a nearly parallel large one: both kept, the surface does not "
    "close (docs/explanation/method.md, 'A known limit of the 3D envelope')",
)
@example(seed=479001600, aspect=1000.0).xfail(
    raises=AssertionError,
    reason="the same known limit of the 3D envelope",
)
# derandomized: the known limit is met by a few seeds at aspect 1000, and a suite
# must not fail by chance; the examples above keep it in sight
@settings(max_examples=40, deadline=None, derandomize=True)
def test_extreme_aspect_ratios(seed: int, aspect: float) -> None:
    rng = np.random.default_rng(seed)
    needle = random_polyhedron(rng, 16, 1.0, (aspect, 1.0, 1.0))
    plate = random_polyhedron(rng, 16, 1.0, (aspect, aspect, 1.0))
    check_against_hull(needle, plate)
    check_against_hull(plate, needle)
    check_against_hull(box((aspect, 1.0, 1.0), rotation(rng)), box((1.0, aspect, 1 / aspect)))


def test_axis_aligned_cubes_give_a_cube() -> None:
    env = check_against_hull(box(1.0), box(0.25))
    assert len(env.normals) == 6 and len(env.vertices) == 8
    assert np.allclose(np.abs(env.vertices), 1.25)
    assert np.allclose(env.support, 1.25)


def test_boxes_with_parallel_faces_merge() -> None:
    env = check_against_hull(box((1.0, 2.0, 3.0)), box((0.5, 0.1, 4.0)))
    assert len(env.normals) == 6 and len(env.vertices) == 8
    assert np.allclose(np.sort(env.support), [1.5, 1.5, 2.1, 2.1, 7.0, 7.0])


@pytest.mark.parametrize("seed", range(5))
def test_a_rotated_cube_with_itself_is_a_cube(seed: int) -> None:
    rot = rotation(np.random.default_rng(seed))
    cube = box(1.0, rot)
    env = check_against_hull(cube, cube)
    assert len(env.normals) == 6 and len(env.vertices) == 8
    assert volume(env) == pytest.approx(64.0, rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_cubes_in_general_orientation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    check_against_hull(box(1.0, rotation(rng)), box(0.3, rotation(rng)))


def test_tetrahedron_minus_itself_is_a_cuboctahedron() -> None:
    tet = tetrahedron()
    env = check_against_hull(tet, tet)
    sizes = np.diff(env.face_offsets)
    assert len(env.vertices) == 12
    assert sorted(sizes.tolist()) == [3] * 8 + [4] * 6


@pytest.mark.parametrize("seed", range(5))
def test_tetrahedra(seed: int) -> None:
    rng = np.random.default_rng(seed)
    tet = tetrahedron(1.0, rotation(rng))
    check_against_hull(tet, tetrahedron(0.7, rotation(rng)))
    # a tetrahedron plus itself (Q = -P): twice the tetrahedron, four faces
    env = check_against_hull(tet, reflect(tet))
    assert len(env.normals) == 4
    got = env.vertices[np.lexsort(env.vertices.T)]
    want = 2.0 * tet.vertices[np.lexsort(tet.vertices.T)]
    assert np.allclose(got, want, rtol=0, atol=1e-12)


@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-6, 1.0, 1e6]))
@settings(max_examples=40, deadline=None)
def test_a_polyhedron_with_itself(seed: int, scale: float) -> None:
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng, 20, scale)
    env = check_against_hull(p, p)  # P ⊕ (-P): centrally symmetric
    assert np.allclose(
        np.sort(env.support), np.sort(env.support[_antipodes(env.normals)]), rtol=1e-12
    )
    doubled = check_against_hull(p, reflect(p))  # P ⊕ P = 2P
    assert len(doubled.normals) == len(p.normals)
    assert volume(doubled) == pytest.approx(8.0 * volume(p), rel=1e-9)


def _antipodes(normals: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(normals[:, None, :] + normals[None, :, :], axis=2)
    assert np.all(d.min(axis=1) <= 1e-9)
    return d.argmin(axis=1)


@given(
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([1e-6, 1e6]),
    ratio=st.sampled_from([1e-3, 1e3]),
)
@settings(max_examples=40, deadline=None)
def test_scales_and_size_ratios_of_boxes(seed: int, scale: float, ratio: float) -> None:
    rng = np.random.default_rng(seed)
    p = box(tuple(rng.uniform(0.2, 1.0, 3)), rotation(rng))
    q = random_polyhedron(rng, 12, 1.0)
    check_against_hull(transformed(p, scale), transformed(q, scale * ratio))


def prism(sides: int, radius: float, height: float, turn: float = 0.0) -> Polyhedron:
    """A right prism over a regular polygon, axis along z."""
    a = turn + 2.0 * np.pi * np.arange(sides) / sides
    ring = np.column_stack([radius * np.cos(a), radius * np.sin(a)])
    return polyhedron_from_points(
        np.vstack([np.column_stack([ring, np.full(sides, z)]) for z in (-height, height)])
    )


def test_parallel_faces_with_many_corners() -> None:
    """Two 12-gon prisms: the caps add up to 24-gons (144 pairwise sums per cap)."""
    p = prism(12, 1.0, 0.5)
    q = prism(12, 0.4, 2.0, turn=0.1)
    env = check_against_hull(p, q)
    assert sorted(np.diff(env.face_offsets).tolist())[-2:] == [24, 24]
    assert len(env.normals) == 2 + 24


def test_swapping_p_and_q_reflects_the_envelope() -> None:
    """``E(P, Q)`` is ``-E(Q, P)``: same facets with the normals reversed."""
    rng = np.random.default_rng(7)
    p = random_polyhedron(rng, 24)
    q = random_polyhedron(rng, 24, 0.5)
    a = minkowski_envelope(p, q)
    b = minkowski_envelope(q, p)
    assert len(a.normals) == len(b.normals)
    assert volume(a) == pytest.approx(volume(b), rel=1e-12)
    d = np.linalg.norm(a.normals[:, None, :] + b.normals[None, :, :], axis=2)
    assert np.all(d.min(axis=1) <= 1e-12)


def test_edges_of_a_cube() -> None:
    cube = box(1.0)
    a, b, left, right = polyhedron_edges(cube.face_vertices, cube.face_offsets, 8)
    assert len(a) == 12
    assert np.all(a < b)
    # the edge runs a -> b in its left face and b -> a in the right one
    for e in range(12):
        for face, (s, t) in ((left[e], (a[e], b[e])), (right[e], (b[e], a[e]))):
            loop = list(cube.face_vertices[cube.face_offsets[face] : cube.face_offsets[face + 1]])
            i = loop.index(s)
            assert loop[(i + 1) % len(loop)] == t


def test_an_open_surface_is_refused() -> None:
    cube = box(1.0)
    with pytest.raises(ValueError):
        polyhedron_edges(cube.face_vertices[:-4], cube.face_offsets[:-1], 8)
    flipped = cube.face_vertices.copy()
    flipped[:4] = flipped[:4][::-1]
    with pytest.raises(ValueError):
        polyhedron_edges(flipped, cube.face_offsets, 8)


def test_candidate_directions_are_the_faces_of_p_and_of_minus_q_then_edge_crossings() -> None:
    rng = np.random.default_rng(5)
    p = box((1.0, 2.0, 3.0))
    q = tetrahedron(0.5, rotation(rng))
    cand, kind, ca, _cb, nc = candidate_directions(p, edge_arcs(p, 1.0), q, edge_arcs(q, -1.0))
    fp, fq = p.normals.shape[0], q.normals.shape[0]
    assert np.array_equal(cand[:fp], p.normals)
    assert np.array_equal(cand[fp : fp + fq], -q.normals)
    assert list(kind[: fp + fq]) == [0] * fp + [1] * fq
    assert list(ca[: fp + fq]) == [*range(fp), *range(fq)]
    assert nc > fp + fq and np.all(kind[fp + fq : nc] == 2)
    # each facet of the envelope takes the normal of the candidate it comes from
    env = minkowski_envelope(p, q)
    assert all((cand[:nc] == normal).all(axis=1).any() for normal in env.normals)


def _pairwise_directions(
    p: Polyhedron, q: Polyhedron
) -> list[tuple[float, float, float, int, int]]:
    """The edge-pair directions by the plain double loop over both sign tables."""
    pl, pr, tp, up = edge_arcs(p, 1.0)
    ql, qr, tq, uq = edge_arcs(q, -1.0)
    side_p = _sides(tp, q.normals, -1.0)
    side_q = _sides(tq, p.normals, 1.0)
    out = []
    for e in range(len(tp)):
        for e2 in range(len(tq)):
            if int(side_p[e, ql[e2]]) * int(side_p[e, qr[e2]]) > 0:
                continue
            if int(side_q[e2, pl[e]]) * int(side_q[e2, pr[e]]) > 0:
                continue
            tx, ty, tz = tp[e]
            sx, sy, sz = tq[e2]
            dx = ty * sz - tz * sy
            dy = tz * sx - tx * sz
            dz = tx * sy - ty * sx
            dn = np.sqrt(dx * dx + dy * dy + dz * dz)
            if dn < PARALLEL_EPS:
                continue
            dx, dy, dz = dx / dn, dy / dn, dz / dn
            a1 = dx * up[e, 0] + dy * up[e, 1] + dz * up[e, 2]
            a2 = dx * up[e, 3] + dy * up[e, 4] + dz * up[e, 5]
            b1 = dx * uq[e2, 0] + dy * uq[e2, 1] + dz * uq[e2, 2]
            b2 = dx * uq[e2, 3] + dy * uq[e2, 4] + dz * uq[e2, 5]
            if min(a1, a2, b1, b2) >= -ANGLE_EPS:
                out.append((dx, dy, dz, e, e2))
            elif max(a1, a2, b1, b2) <= ANGLE_EPS:
                out.append((-dx, -dy, -dz, e, e2))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_edge_pair_directions_are_those_of_the_pairwise_test(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pairs = [
        (random_polyhedron(rng, 20), random_polyhedron(rng, 12, 0.4)),
        (box((1.0, 0.5, 0.3)), box(0.7)),  # parallel edges and faces: sides of 0
        (box(1.0, rotation(rng)), tetrahedron(0.5, rotation(rng))),
    ]
    for p, q in pairs:
        cand, kind, ca, cb, nc = candidate_directions(p, edge_arcs(p, 1.0), q, edge_arcs(q, -1.0))
        first = len(p.normals) + len(q.normals)
        assert np.all(kind[first:nc] == 2)
        got = [(*cand[c], ca[c], cb[c]) for c in range(first, nc)]
        assert got == _pairwise_directions(p, q)


def test_the_envelope_dot_products_are_those_of_numpy() -> None:
    from regopack.plugins.inserters.available_surface.envelope import dots3

    rng = np.random.default_rng(7)
    a, b = rng.normal(size=(13, 3)), rng.normal(size=(5, 3)) * 1e6
    assert np.allclose(dots3(a, b), a @ b.T, rtol=1e-14, atol=0.0)
    assert dots3(a[:0], b).shape == (0, 5)
