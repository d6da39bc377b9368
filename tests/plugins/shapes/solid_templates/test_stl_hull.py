"""The normalised hull: polygon faces, orientation, volume 1 about the centroid, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from stl_helpers import CUBE, ICOSAHEDRON, L_PRISM, TETRAHEDRON

from regopack.base.errors import ConfigError
from regopack.plugins.shapes.solid_templates.hull import ConvexSolid, normalised_hull


def check_hull(solid: ConvexSolid, points: np.ndarray) -> None:
    """Independent checks: a closed, convex, counter-clockwise polyhedron of volume 1
    about its centroid, whose shape is the hull of ``points``."""
    check_polyhedron(solid)
    v = solid.vertices
    reach = float(np.max(np.linalg.norm(v, axis=1)))
    # the same shape as the hull of the input, up to the translation and the scale
    hull = ConvexHull(points)
    s = (1.0 / hull.volume) ** (1.0 / 3.0)
    assert len(v) == len(hull.vertices)
    expected = np.sort((points[hull.vertices] - points[hull.vertices].mean(0)) * s, axis=0)
    got = np.sort(v - v.mean(0), axis=0)
    assert np.allclose(got, expected, rtol=0, atol=1e-9 * reach)


def check_polyhedron(solid: ConvexSolid) -> None:
    """A closed, convex, counter-clockwise polyhedron of volume 1 about its centroid, with
    distinct vertices (the contract of a solid, to 1e-9 of its size)."""
    v = solid.vertices
    fvo = solid.face_vertex_offsets
    loops = [solid.face_vertices[fvo[f] : fvo[f + 1]] for f in range(solid.n_faces)]
    reach = float(np.max(np.linalg.norm(v, axis=1)))
    tol = 1e-9 * reach
    volume, moment, edges = 0.0, np.zeros(3), set()
    for loop, n, h in zip(loops, solid.normals, solid.support, strict=True):
        p = v[loop]
        assert len(loop) >= 3 and len(set(loop.tolist())) == len(loop)
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        assert np.all(np.abs(p @ n - h) <= tol)  # planar, in the plane of its support
        area = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
        assert area @ n > 0  # counter-clockwise seen from outside
        for a, b in zip(loop.tolist(), np.roll(loop, -1).tolist(), strict=True):
            edges.add((a, b))
        for i in range(1, len(loop) - 1):  # fan tetrahedra with the origin
            det = float(np.dot(p[0], np.cross(p[i], p[i + 1])))
            volume += det / 6.0
            moment += det / 24.0 * (p[0] + p[i] + p[i + 1])
    assert all((b, a) in edges for a, b in edges)  # closed, consistently oriented
    assert np.max(v @ solid.normals.T - solid.support) <= tol  # convex
    assert np.allclose(solid.support, (v @ solid.normals.T).max(axis=0), rtol=0, atol=1e-15)
    assert volume == pytest.approx(1.0, rel=1e-12)
    assert np.all(np.abs(moment) <= 1e-12 * reach)  # the centroid is the origin
    assert np.unique(np.round(v / reach, 12), axis=0).shape[0] == len(v)  # distinct


def test_a_cube_has_six_square_faces_at_distance_one_half() -> None:
    solid = normalised_hull(CUBE * 5.0 - 2.0, "cube")
    check_hull(solid, CUBE)
    assert solid.n_faces == 6
    assert np.all(np.diff(solid.face_vertex_offsets) == 4)
    assert np.allclose(solid.support, 0.5, atol=1e-15)
    assert np.allclose(np.abs(solid.normals).max(axis=1), 1.0)


def test_a_tetrahedron_and_an_icosahedron() -> None:
    tet = normalised_hull(TETRAHEDRON, "tet")
    check_hull(tet, TETRAHEDRON)
    ico = normalised_hull(ICOSAHEDRON, "ico")
    check_hull(ico, ICOSAHEDRON)
    assert (tet.n_faces, ico.n_faces) == (4, 20)
    # the icosahedron's faces all lie at the same distance from its centre
    assert np.ptp(ico.support) < 1e-14


def test_a_non_convex_prism_gives_its_hull() -> None:
    solid = normalised_hull(L_PRISM, "L")
    check_hull(solid, L_PRISM)
    # the notch's corner (1, 1) is not a vertex; the hull has 5 sides and 2 lids
    assert solid.n_faces == 7 and len(solid.vertices) == 10


def test_points_inside_faces_and_on_edges_are_dropped() -> None:
    rng = np.random.default_rng(0)
    on_faces = rng.random((200, 3))
    on_faces[np.arange(200), rng.integers(0, 3, 200)] = rng.integers(0, 2, 200)
    solid = normalised_hull(np.vstack([CUBE, on_faces, rng.random((50, 3))]), "noisy cube")
    assert solid.n_faces == 6 and len(solid.vertices) == 8


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(*[st.integers(-2, 2)] * 3), min_size=4, max_size=25, unique=True).map(
        lambda p: np.array(p, dtype=np.float64)
    ),
)
def test_lattice_points_give_valid_hulls_or_a_clear_refusal(points: np.ndarray) -> None:
    # lattice points have many exactly coplanar hull triangles and flat configurations
    try:
        solid = normalised_hull(points, "lattice")
    except ConfigError as err:
        assert "flat" in str(err)
        assert np.linalg.matrix_rank(points - points[0]) < 3
        return
    check_hull(solid, points)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(4, 300),
    axes=st.tuples(*[st.floats(1e-3, 1e3)] * 3),
    offset=st.floats(-10.0, 10.0),
)
def test_random_clouds_give_valid_hulls(
    seed: int, n: int, axes: tuple[float, float, float], offset: float
) -> None:
    points = np.random.default_rng(seed).standard_normal((n, 3)) * axes + offset
    try:
        solid = normalised_hull(points, "cloud")
    except ConfigError as err:  # only a very thin cloud can be refused
        assert_really_flat(points, err)
        return
    check_hull(solid, points)


def assert_really_flat(points: np.ndarray, err: ConfigError) -> None:
    """A hull refused as flat is thin: the centroid lies at least a quarter of the width
    from every face (Minkowski-Radon), so the hull is thinner than 4e-6 of its diameter."""
    assert "flat" in str(err)
    corners = points[ConvexHull(points).vertices]
    diameter = np.max(np.linalg.norm(corners[:, None] - corners[None], axis=2))
    assert ConvexHull(points).volume <= 4e-6 * np.pi * diameter**3


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(4, 120),
    noise=st.sampled_from([1e-15, 1e-13, 1e-11, 1e-9, 1e-7]),
    binary=st.booleans(),
)
def test_nearly_coincident_points_still_give_valid_hulls(
    seed: int, n: int, noise: float, binary: bool
) -> None:
    # every point has a twin a rounding error away: thin hull triangles with spoilt normals
    rng = np.random.default_rng(seed)
    base = rng.standard_normal((n, 3)) * [1.0, 0.7, 0.4]
    points = np.vstack([base, base + rng.standard_normal(base.shape) * noise])
    if binary:
        points = (points * 1000.0 + 7.0).astype(np.float32).astype(np.float64)
    try:
        solid = normalised_hull(points, "noisy", np.float32 if binary else np.float64)
    except ConfigError as err:  # four nearly coplanar points, say
        assert_really_flat(points, err)
        return
    check_polyhedron(solid)


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (CUBE[:3], r"3 distinct points; a solid needs at least 4"),
        (np.vstack([CUBE[:3]] * 5), r"3 distinct points"),
        (CUBE[[0, 2, 4, 6]], r"flat \(its points lie in one plane"),  # the face x = 0
        (np.outer(np.arange(6.0), [1.0, 2.0, 3.0]), r"flat \(its .* or in one line"),
        (CUBE * [1.0, 1.0, 1e-9], r"flat"),  # a slab 10^-9 thick
        (CUBE + 1e4, r"resolve only .* of the mesh's size"),  # 10^4 sizes away (float32)
        ((CUBE - 0.5) * 3e308, r"size overflows 64-bit floats"),
    ],
)  # fmt: skip
def test_unusable_point_sets_are_refused(points: np.ndarray, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as err:
        normalised_hull(points, "g.stl", np.float32)
    assert str(err.value).startswith("g.stl: ") and "\n" not in str(err.value)


def test_the_precision_limit_depends_on_how_the_file_stored_the_numbers() -> None:
    far = CUBE + 1e4
    check_hull(normalised_hull(far, "ascii", np.float64), far)  # float64 resolves it
    near = CUBE + 500.0  # 500 sizes away: float32 still resolves 6e-5 of the size
    check_hull(normalised_hull(near, "binary", np.float32), near)
