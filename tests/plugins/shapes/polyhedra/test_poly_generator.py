"""Random convex polyhedra with shape coefficient psi."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from poly_helpers import check_polyhedron, vector_area

from regopack.plugins.shapes.polyhedra import (
    PolyhedronBatch,
    cube,
    fibonacci,
    polyhedra_from_support,
    random_polyhedra,
    rhombic_dodecahedron,
    truncated_octahedron,
)
from regopack.plugins.shapes.polyhedra.generator import raw_support

SETS = {
    "truncated_octahedron": truncated_octahedron(),
    "cube": cube(),
    "rhombic_dodecahedron": rhombic_dodecahedron(),
    "fibonacci20": fibonacci(20),
}


def _generate(
    psi: float, a: float, radius: np.ndarray, seed: int = 0, directions: np.ndarray | None = None
) -> PolyhedronBatch:
    return random_polyhedra(np.random.default_rng(seed), radius, psi, a, directions)


def _fields(batch: PolyhedronBatch) -> dict[str, np.ndarray]:
    return {f.name: getattr(batch, f.name) for f in dataclasses.fields(batch)}


@given(
    psi=st.floats(0.01, 1000.0),
    a=st.floats(0.05, 1.0),
    r=st.floats(1e-6, 1e6),
    name=st.sampled_from(sorted(SETS)),
    seed=st.integers(0, 2**32 - 1),
)
@settings(max_examples=150, deadline=None)
def test_every_polyhedron_is_valid(psi: float, a: float, r: float, name: str, seed: int) -> None:
    batch = _generate(psi, a, np.full(4, r), seed, SETS[name])
    assert len(batch) == 4
    for i in range(4):
        check_polyhedron(batch, i, r)


@pytest.mark.parametrize(("psi", "a"), [(0.01, 1.0), (0.25, 1.0), (1.0, 1 / 3), (15.0, 0.05)])
def test_many_polyhedra_are_valid(psi: float, a: float) -> None:
    radius = np.geomspace(1.0, 20.0, 300)
    batch = _generate(psi, a, radius, seed=11)
    for i in range(len(batch)):
        check_polyhedron(batch, i, radius[i])


def test_volume_is_exact() -> None:
    radius = np.geomspace(1e-6, 1e6, 500)
    batch = _generate(0.5, 1 / 3, radius, seed=1)
    assert np.allclose(batch.volume / (4.0 / 3.0 * np.pi * radius**3), 1.0, rtol=1e-12, atol=0)


def test_at_most_m_faces_and_all_of_them_when_regular_enough() -> None:
    for name, d in SETS.items():
        m = len(d)
        rough = np.diff(_generate(0.25, 1.0, np.ones(500), 2, d).face_offsets)
        assert rough.max() <= m and rough.min() >= 4
        if name != "cube":  # a box keeps its six faces whatever its supports
            assert rough.min() < m, name  # some directions touch at an edge or a vertex only
        regular = np.diff(_generate(1000.0, 0.05, np.ones(500), 2, d).face_offsets)
        assert np.all(regular == m), name


def test_large_psi_gives_the_regular_truncated_octahedron() -> None:
    """Equal support distances along the 14 normals.

    Expected values, with supports 1: the square face x = 1 is the section of
    the octahedron |x| + |y| + |z| <= √3 (the hexagon planes), the square
    |y| + |z| <= c with c = √3 - 1, of area 2c². The hexagon is the triangle
    x + y + z = √3 in the positive octant (side √6, area 3√3/2) less three
    corners cut by x, y, z <= 1, equilateral triangles of side c√2 (area
    √3c²/2 each): (3√3/2)(1 - c²). With c² = 4 - 2√3 the ratio of the hexagon's
    area to the square's is 9/8. The farthest vertices, (1, c, 0) and its
    images, lie at √(1 + c²) = √(5 - 2√3) from the centre.
    """
    c2 = 4.0 - 2.0 * np.sqrt(3.0)
    square, hexagon = 2.0 * c2, 1.5 * np.sqrt(3.0) * (1.0 - c2)
    assert hexagon / square == pytest.approx(9.0 / 8.0, rel=1e-14)
    batch = _generate(1e6, 1 / 3, np.full(50, 2.0), seed=5)
    for i in range(len(batch)):
        v, faces = batch.polyhedron(i)
        assert len(faces) == 14 and len(v) == 24
        area = np.array([np.linalg.norm(vector_area(v, f)) for f in faces])
        sizes = np.array([len(f) for f in faces])
        direction = batch.face_direction[batch.face_offsets[i] : batch.face_offsets[i + 1]]
        assert np.array_equal(direction, np.arange(14))
        assert np.all(sizes[:6] == 4) and np.all(sizes[6:] == 6)
        assert np.allclose(area[:6], area[0], rtol=1e-9)
        assert np.allclose(area[6:], area[6], rtol=1e-9)
        assert area[6] / area[0] == pytest.approx(hexagon / square, rel=1e-9)
        assert batch.circumradius[i] / batch.inradius[i] == pytest.approx(
            np.sqrt(1.0 + c2), rel=1e-9
        )
        support = batch.support[batch.face_offsets[i] : batch.face_offsets[i + 1]]
        assert np.allclose(support, support[0], rtol=1e-9)


def test_smaller_psi_is_more_irregular() -> None:
    def spread(psi: float) -> float:
        batch = _generate(psi, 1 / 3, np.ones(500), seed=1)
        return float(np.mean(batch.circumradius / batch.inradius))

    assert spread(0.25) > spread(2.0) > spread(15.0) > spread(1e6)


@pytest.mark.parametrize("r", [1e-6, 1e6])
def test_radius_scales_exactly(r: float) -> None:
    one = _generate(0.5, 0.5, np.ones(200), seed=3)
    scaled = _generate(0.5, 0.5, np.full(200, r), seed=3)
    for name in ("vertex_offsets", "face_offsets", "face_vertices", "face_direction"):
        assert np.array_equal(getattr(one, name), getattr(scaled, name))
    assert np.array_equal(one.normals, scaled.normals)
    assert np.array_equal(one.rotation, scaled.rotation)
    for name in ("support", "circumradius", "inradius", "direction_support"):
        assert np.allclose(getattr(scaled, name), r * getattr(one, name), rtol=1e-13, atol=0)
    # a coordinate near zero is a sum of terms that cancel: its error is relative to the size
    assert np.allclose(scaled.vertices, r * one.vertices, rtol=1e-13, atol=1e-14 * r)
    assert np.allclose(scaled.volume, r**3 * one.volume, rtol=1e-13, atol=0)


@pytest.mark.parametrize("s", [2.0**-20, 2.0**20])
def test_radius_times_a_power_of_two_scales_bit_for_bit(s: float) -> None:
    """No hidden unit: every length times ``s``, the volume times ``s**3``, without rounding.

    The scale is ``r`` times the cube root of a number without a unit; the cube
    root of ``r**3 / volume`` rounded differently at ``2**-20`` on glibc.
    """
    radius = np.exp(np.random.default_rng(1).uniform(-8.0, 8.0, 500))
    one = _generate(0.5, 0.5, radius, seed=3)
    scaled = _generate(0.5, 0.5, s * radius, seed=3)
    for name in ("vertices", "support", "circumradius", "inradius", "direction_support"):
        assert np.array_equal(getattr(scaled, name), s * getattr(one, name)), name
    assert np.array_equal(scaled.volume, s**3 * one.volume)


def test_same_seed_gives_identical_arrays_and_other_seeds_differ() -> None:
    radius = np.linspace(1.0, 3.0, 300)
    a = _fields(_generate(0.5, 1 / 3, radius, seed=9))
    b = _fields(_generate(0.5, 1 / 3, radius, seed=9))
    c = _fields(_generate(0.5, 1 / 3, radius, seed=10))
    for name, value in a.items():
        assert value.dtype == b[name].dtype and np.array_equal(value, b[name]), name
    for name in ("vertices", "normals", "rotation", "direction_support"):
        assert a[name].shape != c[name].shape or not np.allclose(a[name], c[name]), name


def test_draws_come_in_the_documented_order() -> None:
    """Signs, then xi, then quaternions, each one call: the raw half-spaces are exact."""
    n, m, psi, a = 400, 14, 0.3, 1.0
    radius = np.ones(n)
    rng = np.random.default_rng(42)
    batch = random_polyhedra(rng, radius, psi, a)
    after = rng.random()
    replay = np.random.default_rng(42)
    sign = 2.0 * replay.integers(0, 2, size=(n, m)) - 1.0
    xi = replay.random((n, m))
    q = replay.standard_normal((n, 4))
    assert replay.random() == after  # nothing else was drawn
    s = raw_support(sign, xi, psi, a)
    rebuilt = polyhedra_from_support(s, radius, truncated_octahedron(), batch.rotation)
    for name, value in _fields(batch).items():
        assert np.array_equal(value, getattr(rebuilt, name)), name
    # the rotations are those of the quaternions: q rotates the body frame
    w, x, y, z = (q / np.linalg.norm(q, axis=1)[:, None]).T
    assert np.allclose(batch.rotation[:, 2, 2], 1.0 - 2.0 * (x * x + y * y))
    assert np.allclose(batch.rotation[:, 1, 0], 2.0 * (x * y + w * z))


def test_support_is_replaced_by_the_true_support() -> None:
    """Faces are the raw half-spaces that touch; the others keep only their true support.

    In the body frame, a face plane is ``d_k . x = λ (s_k - d_k . c)`` for the
    raw support ``s_k``, the centroid ``c`` and the scale ``λ``; these are
    solved from the faces. A direction whose raw plane missed the polyhedron
    must have a smaller support than its raw plane, and exactly the largest
    ``d_k . v`` over the vertices: a generator that kept the raw values would
    fail here.
    """
    n, m, psi, a = 300, 14, 0.25, 1.0
    rng = np.random.default_rng(8)
    batch = random_polyhedra(rng, np.ones(n), psi, a)
    replay = np.random.default_rng(8)
    sign = 2.0 * replay.integers(0, 2, size=(n, m)) - 1.0
    s = raw_support(sign, replay.random((n, m)), psi, a)
    d = batch.directions
    lowered = 0
    for i in range(n):
        v = batch.vertices_of(i) @ batch.rotation[i]  # back to the body frame
        true = np.max(v @ d.T, axis=0)
        assert np.allclose(batch.direction_support[i], true, rtol=0, atol=1e-12)
        fd = batch.face_direction[batch.face_offsets[i] : batch.face_offsets[i + 1]]
        # least squares for (λ, λ c): support_k = λ s_k - d_k . (λ c)
        rows = np.column_stack([s[i, fd], -d[fd]])
        sol, *_ = np.linalg.lstsq(rows, batch.direction_support[i, fd], rcond=None)
        raw_plane = np.column_stack([s[i], -d]) @ sol
        assert np.allclose(raw_plane[fd], batch.direction_support[i, fd], atol=1e-12)
        assert np.all(batch.direction_support[i] <= raw_plane + 1e-12)
        missed = np.setdiff1d(np.arange(m), fd)
        gap = raw_plane[missed] - batch.direction_support[i, missed]
        lowered += int(np.sum(gap > 1e-6))
    assert lowered > 50  # the case the replacement exists for is common here


def test_rebuilding_from_the_true_supports_gives_the_same_polyhedra() -> None:
    """Every plane now touches: vertices where four or more planes meet must be found once."""
    radius = np.linspace(1.0, 2.0, 300)
    for name, d in SETS.items():
        batch = _generate(0.2, 1.0, radius, 4, d)
        again = polyhedra_from_support(batch.direction_support, radius, d, batch.rotation)
        # the same counts; the vertices may be found in another order
        for field in ("vertex_offsets", "face_offsets", "face_direction", "face_vertex_offsets"):
            assert np.array_equal(getattr(again, field), getattr(batch, field)), (name, field)
        assert np.allclose(again.direction_support, batch.direction_support, atol=1e-10), name
        for i in range(len(batch)):
            (v, faces), (w, faces2) = batch.polyhedron(i), again.polyhedron(i)
            gap = np.linalg.norm(v[:, None] - w[None], axis=2)
            match = np.argmin(gap, axis=1)  # vertex j of batch is vertex match[j] of again
            assert gap.min(axis=1).max() < 1e-10 and len(set(match.tolist())) == len(v)
            for f, g in zip(faces, faces2, strict=True):
                mapped = match[f].tolist()
                start = mapped.index(int(g[0]))
                assert mapped[start:] + mapped[:start] == g.tolist(), (name, i)


def test_regular_solids_from_equal_supports() -> None:
    one = np.ones(1)
    cube_batch = polyhedra_from_support(np.ones((1, 6)), one, cube())
    v, faces = cube_batch.polyhedron(0)
    side = (4.0 / 3.0 * np.pi) ** (1.0 / 3.0)
    assert len(v) == 8 and len(faces) == 6
    assert np.allclose(np.abs(v), side / 2.0)
    rd = polyhedra_from_support(np.ones((1, 12)), one, rhombic_dodecahedron())
    v, faces = rd.polyhedron(0)
    # 14 vertices, where three or four faces meet; 12 rhombi
    assert len(v) == 14 and len(faces) == 12 and all(len(f) == 4 for f in faces)
    check_polyhedron(rd, 0, 1.0)


def test_the_reference_point_is_the_centroid_and_may_leave_the_raw_origin() -> None:
    # raw supports far from symmetric: the centroid is not the origin of the half-spaces
    s = np.ones((1, 6))
    s[0, 0] = 3.0  # x <= 3, x >= -1: a box centred at x = 1
    batch = polyhedra_from_support(s, np.ones(1), cube())
    v = batch.vertices_of(0)
    assert np.allclose(v.mean(axis=0), 0.0, atol=1e-14)
    assert np.allclose(np.sort(np.unique(np.round(np.abs(v[:, 0]) / np.abs(v[:, 1]), 9))), [2.0])
    check_polyhedron(batch, 0, 1.0)


def test_empty_batch() -> None:
    batch = _generate(1.0, 0.5, np.zeros(0))
    assert len(batch) == 0
    assert batch.vertices.shape == (0, 3) and batch.normals.shape == (0, 3)
    assert batch.vertex_offsets.tolist() == [0] and batch.face_vertex_offsets.tolist() == [0]


def test_polyhedron_index_is_checked() -> None:
    batch = _generate(1.0, 0.5, np.ones(2))
    with pytest.raises(IndexError):
        batch.polyhedron(2)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"psi": 0.0}, "psi"),
        ({"psi": -1.0}, "psi"),
        ({"psi": float("inf")}, "psi"),
        ({"psi": float("nan")}, "psi"),
        ({"a": -0.1}, "a must"),
        ({"a": 1.5}, "a must"),
        ({"a": float("nan")}, "a must"),
        ({"radius": np.array([1.0, -1.0])}, "radius"),
        ({"radius": np.array([1.0, np.nan])}, "radius"),
        ({"radius": np.ones((2, 2))}, "1-D"),
        ({"directions": cube()[:5]}, "positively spanning"),
    ],
)
def test_bad_inputs_raise_value_errors(kwargs: dict, message: str) -> None:
    args = {"radius": np.ones(3), "psi": 1.0, "a": 0.5, **kwargs}
    with pytest.raises(ValueError, match=message):
        random_polyhedra(np.random.default_rng(0), **args)


def test_flat_or_empty_support_is_refused() -> None:
    flat = np.ones((1, 6))
    flat[0, 0] = flat[0, 1] = 0.0  # 0 <= x <= 0
    with pytest.raises(ValueError, match="empty or flat"):
        polyhedra_from_support(flat, np.ones(1), cube())
    empty = np.ones((1, 6))
    empty[0, 0] = empty[0, 1] = -1.0  # x <= -1 and x >= 1
    with pytest.raises(ValueError, match="empty or flat"):
        polyhedra_from_support(empty, np.ones(1), cube())
    with pytest.raises(ValueError, match="shape"):
        polyhedra_from_support(np.ones((2, 6)), np.ones(1), cube())


def test_raw_support_formula_range_and_floor() -> None:
    sign = np.array([[1.0, -1.0, 1.0, -1.0, -1.0]])
    xi = np.array([[0.0, 0.0, 0.75, 0.25, 0.5]])
    s = raw_support(sign, xi, psi=2.0, a=0.5)
    assert np.array_equal(s, [[1.5, 0.5, 1.125, 0.875, 1.0]])
    # a = 1 and xi = 0 reach zero: the floor keeps the origin strictly inside
    assert np.array_equal(raw_support(sign, xi, psi=1.0, a=1.0)[0, :2], [2.0, 1e-9])
    rng = np.random.default_rng(0)
    sign = 2.0 * rng.integers(0, 2, size=(1000, 14)) - 1.0
    s = raw_support(sign, rng.random((1000, 14)), psi=0.5, a=1 / 3)
    assert s.min() >= 2 / 3 and s.max() <= 4 / 3
    assert s.min() < 0.7 and s.max() > 1.3
