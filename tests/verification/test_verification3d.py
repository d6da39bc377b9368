from __future__ import annotations

import dataclasses
import math
import time
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, Delaunay, QhullError, cKDTree
from scipy.spatial.transform import Rotation

import regopack.verification.polyhedra as v3
from regopack.base.errors import ConfigError, GeometryError, PackingError
from regopack.verification.polyhedra import (
    FLAT_TOL,
    Report3D,
    overlap_volume,
    separating_gap,
    verify_polyhedra,
    verify_spheres,
)

CUBE = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
AXES = np.eye(3)


def rotated_cube(angles, about="xyz"):
    """The unit cube rotated about its centre."""
    rot = Rotation.from_euler(about, angles).as_matrix()
    return (CUBE - 0.5) @ rot.T + 0.5


def random_polyhedron(rng, k=12, spread=1.0):
    return rng.uniform(-spread, spread, size=(k, 3))


def grid(n, size=1.0):
    """Vertices of an n x n x n face-to-face lattice of cubes of side ``size``, as a list."""
    cells = np.array([(a, b, c) for a in range(n) for b in range(n) for c in range(n)], float)
    return [(CUBE + cell) * size for cell in cells]


# ---------------------------------------------------------------- two cubes


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("t", [1.25, 1.5, 2.0, 3.0, 17.0])
def test_separated_cubes_gap_is_the_distance_exactly(axis, t):
    for sign in (1, -1):
        q = CUBE + sign * t * AXES[axis]
        assert separating_gap(CUBE, q) == t - 1.0
        assert overlap_volume(CUBE, q) == 0.0


@pytest.mark.parametrize("t", [1.1, 1.001, 1 + 1e-9, 2.7])
def test_separated_cubes_gap_not_dyadic(t):
    q = CUBE + (t, 0, 0)
    assert separating_gap(CUBE, q) == pytest.approx(t - 1.0, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("t", [0.0, 0.125, 0.25, 0.5, 0.75, 0.875, 0.96875])
def test_overlapping_cubes(axis, t):
    for sign in (1, -1):
        q = CUBE + sign * t * AXES[axis]
        assert overlap_volume(CUBE, q) == pytest.approx(1.0 - t, rel=1e-13)
        # the shortest separating translation: along the axis, or 1 sideways
        assert separating_gap(CUBE, q) == pytest.approx(-(1.0 - t), rel=1e-13)


@pytest.mark.parametrize("t", [0.1, 0.3, 0.9, 0.999])
def test_overlapping_cubes_not_dyadic(t):
    q = CUBE + (t, 0, 0)
    assert overlap_volume(CUBE, q) == pytest.approx(1.0 - t, rel=1e-9)


def test_cubes_touching_face_to_face_exactly():
    for axis in range(3):
        for sign in (1, -1):
            q = CUBE + sign * AXES[axis]
            assert separating_gap(CUBE, q) == 0.0
            assert overlap_volume(CUBE, q) == 0.0


@pytest.mark.parametrize(
    "shift",
    [(1, 1, 0), (1, 0, -1), (1, 1, 1), (-1, 1, -1), (1, 0.25, 0.5), (1, 0.5, 1)],
    ids=["edge", "edge2", "vertex", "vertex2", "partial-face", "edge-partial"],
)
def test_cubes_touching_at_edges_and_vertices(shift):
    q = CUBE + np.asarray(shift, float)
    assert separating_gap(CUBE, q) == 0.0
    assert overlap_volume(CUBE, q) == 0.0


def test_cube_vertex_on_a_face():
    q = rotated_cube([0.61, 0.47, 0.2])
    low = int(np.argmin(q[:, 2]))
    q = q + (0.5, 0.5, 1.0) - q[low]
    q[low] = (0.5, 0.5, 1.0)  # the lowest vertex exactly on the top face of CUBE (an ulp moved)
    assert np.sum(q[:, 2] <= 1.0 + 1e-12) == 1
    assert abs(separating_gap(CUBE, q)) <= 1e-15
    assert overlap_volume(CUBE, q) == 0.0
    pushed = q - (0.0, 0.0, 1e-3)
    assert separating_gap(CUBE, pushed) == pytest.approx(-1e-3, rel=1e-9)
    assert overlap_volume(CUBE, pushed) > 0.0


def test_crossing_edges_touch():
    p = rotated_cube(math.pi / 4, about="x")  # a top edge along x
    q = rotated_cube(math.pi / 4, about="y")  # a bottom edge along y
    top = np.flatnonzero(p[:, 2] > p[:, 2].max() - 1e-12)
    bottom = np.flatnonzero(q[:, 2] < q[:, 2].min() + 1e-12)
    assert len(top) == len(bottom) == 2
    z = p[top, 2].max()
    q = q + (0.0, 0.0, z - q[bottom, 2].min())
    q[bottom, 2] = p[top, 2] = z  # both edges exactly in one plane (ulps moved)
    assert abs(separating_gap(p, q)) <= 1e-15
    assert overlap_volume(p, q) == 0.0
    assert separating_gap(p, q + (0, 0, 0.5)) == pytest.approx(0.5, rel=1e-12)
    # pressed together: the edges cross inside both
    assert separating_gap(p, q - (0, 0, 0.01)) == pytest.approx(-0.01, rel=1e-9)
    assert overlap_volume(p, q - (0, 0, 0.01)) > 0.0


def _sat_separation(p, q):
    """Facet-plane and edge-cross separations of one pair, as verify_polyhedra measures them."""
    parts = v3._Particles([v3._polyhedron(p, "p"), v3._polyhedron(q, "q")])
    i, j, t = np.array([0]), np.array([1]), np.zeros((1, 3))
    return float(v3._face_separations(parts, i, j, t)[0]), float(
        v3._edge_separations(parts, i, j, t)[0]
    )


def test_crossing_edges_are_settled_by_the_edge_directions():
    """Only an edge-cross direction separates two cubes touching edge to edge."""
    p = rotated_cube(math.pi / 4, about="x")
    q = rotated_cube(math.pi / 4, about="y")
    q = q + (0.0, 0.0, p[:, 2].max() - q[:, 2].min())
    face, edge = _sat_separation(p, q)
    assert face < -0.1  # no facet plane separates them
    assert abs(edge) <= 1e-15
    face, edge = _sat_separation(p, q - (0, 0, 0.01))
    assert edge == pytest.approx(-0.01, rel=1e-9)
    assert not verify_polyhedra([p, q - (0, 0, 0.01)], None, (-2, -2, -2), (3, 3, 4))
    assert verify_polyhedra([p, q], None, (-2, -2, -2), (3, 3, 4))


@pytest.mark.parametrize("seed", range(12))
def test_separating_axes_give_the_penetration_depth(seed):
    """The larger of the two separations is minus the penetration depth of an overlapping pair."""
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng)
    q = random_polyhedron(rng) + rng.normal(size=3) * 0.5
    depth = separating_gap(p, q)
    sat = max(_sat_separation(p, q))
    if depth < 0:
        assert sat == pytest.approx(depth, rel=1e-9, abs=1e-12)
    else:  # apart: the axes' margin is at most the distance
        assert 0 <= sat <= depth * (1 + 1e-12) + 1e-15


def _ball(rng, k):
    """The hull of ``k`` random points of the unit sphere."""
    x = rng.normal(size=(k, 3))
    return x / np.linalg.norm(x, axis=1)[:, None]


def test_polyhedra_of_many_vertices_do_not_pad_the_edge_directions():
    """Hulls of 200 vertices go to Qhull; two cubes beside them are still settled by their edges.

    The edge directions cost a pair ``e**2 v`` products (``e`` edges, ``v``
    vertices): padded to a 200-vertex hull, every pair needed a gigabyte.
    """
    rng = np.random.default_rng(5)
    ball = _ball(rng, 200)
    p = rotated_cube(math.pi / 4, about="x")
    q = rotated_cube(math.pi / 4, about="y")
    q = q + (0.0, 0.0, p[:, 2].max() - q[:, 2].min())
    solids = [ball, ball + (1.5, 0, 0), p + (10, 0, 0), q + (10, 0, 0)]
    tracemalloc.start()
    try:
        report = verify_polyhedra(solids, None, (-2, -2, -2), (14, 4, 6))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert report.overlapping_pairs == ((0, 1),)
    assert report.worst_overlap_fraction == pytest.approx(
        overlap_volume(ball, ball + (1.5, 0, 0)) / ConvexHull(ball).volume, rel=1e-9
    )
    assert peak < 64e6
    parts = v3._Particles([v3._polyhedron(s, "s") for s in solids])
    edges = v3._edge_separations(parts, np.array([0, 2]), np.array([1, 3]), np.zeros((2, 3)))
    assert edges[0] == -np.inf and abs(edges[1]) <= 1e-15


def test_diagonal_distance_is_euclidean():
    # the closest points are two vertices, not along a face normal
    assert separating_gap(CUBE, CUBE + (2, 2, 2)) == pytest.approx(math.sqrt(3), rel=1e-14)
    assert separating_gap(CUBE, CUBE + (2, 3, 0)) == pytest.approx(math.sqrt(5), rel=1e-14)


def test_contained_polyhedron():
    small = CUBE * 0.25 + 0.25
    assert overlap_volume(CUBE, small) == pytest.approx(0.25**3, rel=1e-13)
    assert overlap_volume(small, CUBE) == pytest.approx(0.25**3, rel=1e-13)
    # it must move by 0.5 (its distance to the nearest face, 0.25, plus its side) to leave
    assert separating_gap(CUBE, small) == pytest.approx(-0.5, rel=1e-13)


def test_interior_points_are_ignored():
    cloud = np.vstack([CUBE, np.random.default_rng(0).uniform(0.1, 0.9, size=(30, 3))])
    assert overlap_volume(cloud, CUBE + (0.5, 0, 0)) == pytest.approx(0.5, rel=1e-13)
    assert separating_gap(cloud, CUBE + (1.5, 0, 0)) == 0.5


# ---------------------------------------------------------------- random polyhedra


def _monte_carlo(p, q, rng, n=400_000):
    """Volume of hull(p) & hull(q) by sampling the overlap of their bounding boxes."""
    lo = np.maximum(p.min(axis=0), q.min(axis=0))
    hi = np.minimum(p.max(axis=0), q.max(axis=0))
    if np.any(hi <= lo):
        return 0.0, 0.0
    pts = rng.uniform(lo, hi, size=(n, 3))
    inside = (Delaunay(p).find_simplex(pts) >= 0) & (Delaunay(q).find_simplex(pts) >= 0)
    frac = inside.mean()
    box = float(np.prod(hi - lo))
    return box * frac, box * math.sqrt(max(frac * (1 - frac), 1.0 / n) / n)


@pytest.mark.parametrize("seed", range(6))
def test_overlap_volume_agrees_with_monte_carlo(seed):
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng, k=int(rng.integers(6, 20)))
    q = random_polyhedron(rng, k=int(rng.integers(6, 20))) + rng.uniform(-0.8, 0.8, size=3)
    exact = overlap_volume(p, q)
    estimate, sigma = _monte_carlo(p, q, rng)
    assert exact > 0.05
    assert abs(exact - estimate) <= 5 * sigma
    assert overlap_volume(q, p) == pytest.approx(exact, rel=1e-9)
    assert separating_gap(p, q) < 0
    assert separating_gap(q, p) == pytest.approx(separating_gap(p, q), rel=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_self_overlap_is_the_volume(seed):
    p = random_polyhedron(np.random.default_rng(seed), k=15)
    assert overlap_volume(p, p) == pytest.approx(ConvexHull(p).volume, rel=1e-12)


def _qp_distance(p, q):
    """Distance between two hulls as the quadratic program over convex weights (SLSQP)."""
    k = len(p)

    def f(w):
        d = w[:k] @ p - w[k:] @ q
        return d @ d

    def grad(w):
        d = w[:k] @ p - w[k:] @ q
        return np.concatenate([2 * p @ d, -2 * q @ d])

    cons = [
        {"type": "eq", "fun": lambda w: w[:k].sum() - 1},
        {"type": "eq", "fun": lambda w: w[k:].sum() - 1},
    ]
    w0 = np.concatenate([np.full(k, 1 / k), np.full(len(q), 1 / len(q))])
    res = minimize(
        f,
        w0,
        jac=grad,
        bounds=[(0, 1)] * len(w0),
        constraints=cons,
        method="SLSQP",
        options={"ftol": 1e-15, "maxiter": 1000},
    )
    return math.sqrt(res.fun)


@pytest.mark.parametrize("seed", range(5))
def test_separated_random_polyhedra_gap_is_the_distance(seed):
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng, k=10)
    q = random_polyhedron(rng, k=10) + rng.choice([-1, 1], size=3) * rng.uniform(1.5, 2.5, 3)
    gap = separating_gap(p, q)
    assert gap > 0
    assert gap == pytest.approx(_qp_distance(p, q), rel=1e-6)
    # points of both hulls (convex combinations of vertices): none closer than the gap
    wp = rng.dirichlet(np.full(len(p), 0.2), size=20_000)
    wq = rng.dirichlet(np.full(len(q), 0.2), size=20_000)
    d, _ = cKDTree(wq @ q).query(wp @ p)
    assert d.min() >= gap * (1 - 1e-12)
    assert overlap_volume(p, q) == 0.0


@pytest.mark.parametrize("scale", [1e-6, 1e6, 2.0**-40, 3.7e9])
@pytest.mark.parametrize("seed", range(3))
def test_results_scale_with_the_lengths(scale, seed):
    rng = np.random.default_rng(seed)
    p = random_polyhedron(rng)
    pairs = [
        (p, random_polyhedron(rng) + (0.4, 0.2, 0.0)),  # overlapping
        (p, random_polyhedron(rng) + (2.5, 0.0, 0.0)),  # apart
    ]
    origin = rng.uniform(-5, 5, size=3)
    for a, b in pairs:
        gap, vol = separating_gap(a, b), overlap_volume(a, b)
        sa, sb = (a + origin) * scale, (b + origin) * scale
        assert separating_gap(sa, sb) / scale == pytest.approx(gap, rel=1e-9)
        assert overlap_volume(sa, sb) / scale**3 == pytest.approx(vol, rel=1e-9, abs=0.0)


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_thin_overlaps_are_measured_at_every_scale(scale):
    """Fails if the flat tolerance were absolute: at 1e-6 a 1e-8 overlap is 1e-14 long."""
    depth = 1e-8
    vol = overlap_volume(CUBE * scale, (CUBE + (1 - depth, 0, 0)) * scale)
    assert vol / scale**3 == pytest.approx(depth, rel=1e-6)
    assert separating_gap(CUBE * scale, (CUBE + (1 - depth, 0, 0)) * scale) / scale == (
        pytest.approx(-depth, rel=1e-6)
    )
    # below the flat tolerance it is a contact
    tiny = CUBE + (1 - FLAT_TOL / 2, 0, 0)
    assert overlap_volume(CUBE * scale, tiny * scale) == 0.0


polyhedra = st.builds(
    lambda seed, k1, k2, shift: (
        np.random.default_rng(seed).normal(size=(k1, 3)),
        np.random.default_rng(seed + 1).normal(size=(k2, 3)) + np.asarray(shift),
    ),
    st.integers(0, 2**31),
    st.integers(4, 16),
    st.integers(4, 16),
    st.tuples(*[st.floats(-4.0, 4.0)] * 3),
)


@settings(max_examples=80, deadline=None)
@given(polyhedra)
def test_gap_sign_agrees_with_the_volume(pair):
    p, q = pair
    gap, vol = separating_gap(p, q), overlap_volume(p, q)
    size = min(np.linalg.norm(np.ptp(p, axis=0)), np.linalg.norm(np.ptp(q, axis=0)))
    smaller = min(ConvexHull(p).volume, ConvexHull(q).volume)
    assert vol >= 0.0
    if vol > 1e-9 * smaller:
        assert gap < 0.0
    if gap > 1e-9 * size:
        assert vol == 0.0
    if gap < -1e-6 * size:
        assert vol > 0.0
    assert vol <= smaller * (1 + 1e-9)


near_contact = st.builds(
    lambda seed, k1, k2, theta, phi, depth: _placed_along(seed, k1, k2, theta, phi, depth),
    st.integers(0, 2**31),
    st.integers(4, 16),
    st.integers(4, 16),
    st.floats(0.0, math.pi),
    st.floats(0.0, 2 * math.pi),
    st.sampled_from([0.0, 1e-11, -1e-11, 1e-9, -1e-9, 1e-6, -1e-6, 1e-3, -1e-3, 0.1, -0.1]),
)


def _placed_along(seed, k1, k2, theta, phi, depth):
    """Q beyond P along n, with a gap ``depth`` between their supporting planes."""
    rng = np.random.default_rng(seed)
    p, q = rng.normal(size=(k1, 3)), rng.normal(size=(k2, 3))
    n = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    q = q + n * ((p @ n).max() - (q @ n).min() + depth)
    return p, q, depth


@settings(max_examples=150, deadline=None)
@given(near_contact)
def test_near_contact_along_a_plane(case):
    """The gap is at least the distance between the supporting planes (or minus their overlap)."""
    p, q, depth = case
    gap, vol = separating_gap(p, q), overlap_volume(p, q)
    size = min(np.linalg.norm(np.ptp(p, axis=0)), np.linalg.norm(np.ptp(q, axis=0)))
    assert gap >= depth - 1e-12 * size
    # no closer than the nearest two vertices
    assert gap <= np.linalg.norm(p[:, None] - q[None], axis=2).min() * (1 + 1e-12)
    if depth >= 0:
        assert vol == 0.0
    else:
        # the intersection lies in the slab between the two planes
        assert vol <= -depth * math.pi * size**2 / 4 * (1 + 1e-9)
        if vol > 0.0:
            assert gap < 0.0


def test_a_qhull_failure_counts_as_flat_only_for_a_sliver(monkeypatch):
    def failing(halfspaces, interior_point, qhull_options=None):
        raise QhullError("simulated precision error")

    monkeypatch.setattr(v3, "HalfspaceIntersection", failing)
    # inscribed radius 5e-12, between FLAT_TOL and SLIVER_TOL times the diagonal
    assert overlap_volume(CUBE, CUBE + (1 - 1e-11, 0, 0)) == 0.0
    with pytest.raises(GeometryError, match="Qhull failed"):
        overlap_volume(CUBE, CUBE + (1 - 1e-9, 0, 0))
    monkeypatch.undo()
    assert overlap_volume(CUBE, CUBE + (1 - 1e-11, 0, 0)) == pytest.approx(1e-11, rel=1e-4)


# ---------------------------------------------------------------- bad input


def test_bad_polyhedra_are_refused():
    with pytest.raises(PackingError):
        separating_gap(np.zeros((4, 2)), CUBE)
    with pytest.raises(PackingError):
        overlap_volume(CUBE, np.full((8, 3), np.nan))
    with pytest.raises(GeometryError, match="at least 4"):
        overlap_volume(CUBE[:3], CUBE)
    with pytest.raises(GeometryError, match="flat"):
        separating_gap(CUBE, CUBE * (1, 1, 0))


def test_bad_packing_input_is_refused():
    cubes = grid(2)
    with pytest.raises(ConfigError):
        verify_polyhedra(cubes, None, (0, 0, 0), (2, 2, 2), rel_tol=-1)
    with pytest.raises(ConfigError):
        verify_polyhedra(cubes, None, (0, 0, 0), (2, 0, 2))
    with pytest.raises(PackingError):
        verify_polyhedra(np.vstack(cubes), None, (0, 0, 0), (2, 2, 2))
    with pytest.raises(PackingError):
        verify_polyhedra(np.vstack(cubes), np.array([0, 8, 7, 64]), (0, 0, 0), (2, 2, 2))
    with pytest.raises(GeometryError, match="particle 1"):
        verify_polyhedra([CUBE, CUBE[:3]], None, (0, 0, 0), (2, 2, 2))


# ---------------------------------------------------------------- packings


def test_touching_lattice_is_valid():
    report = verify_polyhedra(grid(10), None, (0, 0, 0), (10, 10, 10))
    assert report.ok and bool(report)
    assert report.n_checked == 1000
    # every pair of lattice neighbours (faces, edges, corners) has touching boxes
    faces, edges, corners = 3 * 9 * 100, 6 * 9 * 9 * 10, 4 * 9**3
    assert report.n_candidate_pairs == faces + edges + corners
    assert report.n_overlapping_pairs == 0
    assert report.worst_overlap_fraction == 0.0
    assert report.worst_pair is None
    assert report.n_outside == 0
    assert report.worst_outside is None


def test_flat_arrays_and_lists_give_the_same_report():
    cubes = grid(4)
    cubes[5] = cubes[5] + (0.25, 0, 0)
    flat = np.vstack(cubes)
    offsets = np.arange(0, 8 * len(cubes) + 1, 8)
    a = verify_polyhedra(cubes, None, (0, 0, 0), (5, 5, 5))
    b = verify_polyhedra(flat, offsets, (0, 0, 0), (5, 5, 5))
    c = verify_polyhedra(np.array(cubes), None, (0, 0, 0), (5, 5, 5))
    assert a == b == c
    assert not a


@pytest.mark.parametrize("scale", [1.0, 1e-6, 1e6])
def test_a_nudged_cube_overlaps_the_right_neighbours(scale):
    """A relative tolerance finds the same pairs at every scale (an absolute one would not)."""
    nudge = 1e-3
    cubes = grid(10)
    k = 4 * 100 + 4 * 10 + 4  # the cube at (4, 4, 4)
    cubes[k] = cubes[k] + (nudge, nudge, 0.0)
    cubes = [c * scale for c in cubes]
    report = verify_polyhedra(cubes, None, (0, 0, 0), np.full(3, 10 * scale))
    assert not report.ok
    # the +x and +y neighbours by nudge * (1 - nudge), the +x+y one by nudge^2
    x, y, xy = k + 100, k + 10, k + 110
    assert report.overlapping_pairs == ((k, y), (k, x), (k, xy))
    assert report.n_overlapping_pairs == 3
    assert report.worst_pair in ((k, x), (k, y))
    assert report.worst_overlap_fraction == pytest.approx(nudge * (1 - nudge), rel=1e-9)
    coarse = verify_polyhedra(cubes, None, (0, 0, 0), np.full(3, 10 * scale), rel_tol=1e-5)
    assert coarse.overlapping_pairs == ((k, y), (k, x))


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_a_tiny_relative_overlap_is_found_at_every_scale(scale):
    """Fails if rel_tol (or the flat tolerance) were applied in absolute units."""
    cubes = [CUBE * scale, (CUBE + (1 - 1e-7, 0, 0)) * scale]
    report = verify_polyhedra(cubes, None, (0, 0, 0), (2 * scale, scale, scale))
    assert report.overlapping_pairs == ((0, 1),)
    assert report.worst_overlap_fraction == pytest.approx(1e-7, rel=1e-6)
    touching = [CUBE * scale, (CUBE + (1, 0, 0)) * scale]
    assert verify_polyhedra(touching, None, (0, 0, 0), (2 * scale, scale, scale))


def test_rotated_touching_pairs_are_valid():
    """Vertex-to-face and edge-to-edge contacts in a packing, with rounding in the coordinates."""
    rng = np.random.default_rng(3)
    cubes = []
    for n in range(20):
        base = CUBE + (3.0 * n, 0, 0)
        q = rotated_cube(rng.uniform(0, 2 * np.pi, size=3)) + (3.0 * n, 0, 0)
        q = q + (0.0, 0.0, 1.0 - q[:, 2].min())
        cubes += [base, q]
    report = verify_polyhedra(cubes, None, (-1, -1, -1), (61, 2, 3))
    assert report.ok, str(report)
    assert report.n_candidate_pairs == 20
    assert report.worst_overlap_fraction <= 1e-12


def test_overlap_across_the_periodic_boundary():
    side = 10.0
    a = CUBE + (9.5, 9.5, 9.5)  # pokes out through three sides
    b = CUBE + (0.25, 0.25, 0.25)  # overlaps a's image at (-0.5, -0.5, -0.5)
    c = CUBE + (4.0, 4.0, 4.0)
    report = verify_polyhedra([a, c, b], None, (0, 0, 0), (side, side, side), periodic=True)
    assert not report.ok
    assert report.overlapping_pairs == ((0, 2),)
    assert report.worst_overlap_fraction == pytest.approx(0.25**3, rel=1e-12)
    assert report.n_outside == 0 and report.worst_outside is None
    # the same without periodicity: no overlap, but a particle outside
    walled = verify_polyhedra([a, c, b], None, (0, 0, 0), (side, side, side))
    assert walled.n_overlapping_pairs == 0
    assert walled.n_outside == 1 and walled.worst_outside == (0, pytest.approx(0.5))


def test_periodic_wrapping_of_far_particles():
    a = CUBE + (9.5, 4.0, 4.0)
    for far in (0.0, 10.0, -30.0):
        touching = CUBE + (0.5 + far, 4.0, 4.0)  # a's image at -0.5 ends at 0.5
        overlapping = CUBE + (0.25 + far, 4.0, 4.0)
        assert verify_polyhedra([a, touching], None, (0, 0, 0), (10, 10, 10), periodic=True)
        bad = verify_polyhedra([a, overlapping], None, (0, 0, 0), (10, 10, 10), periodic=True)
        assert bad.overlapping_pairs == ((0, 1),)
        assert bad.worst_overlap_fraction == pytest.approx(0.25, rel=1e-12)


def _needle(centre, length=4.0, width=0.1):
    """A square prism of the given length along (1, 0, 1), about ``centre``."""
    u = np.array([1.0, 0.0, 1.0]) / math.sqrt(2.0)
    v = np.array([-1.0, 0.0, 1.0]) / math.sqrt(2.0)
    w = np.array([0.0, 1.0, 0.0])
    signs = CUBE * 2 - 1
    corners = signs[:, :1] * length / 2 * u + (signs[:, 1:2] * v + signs[:, 2:] * w) * width / 2
    return corners + np.asarray(centre, float)


@pytest.mark.parametrize("period", [1.0, 0.3])
def test_particles_longer_than_the_periodic_box_are_checked_on_every_image(period):
    """A slab thinner than its particles: pairs meet through images two or more periods away."""
    lo, hi = (0.0, 0.0, 0.0), (20.0, 20.0, period)
    a = _needle((10.0, 10.0, 0.5 * period))
    # b is a moved along its own axis by k periods of z (and as much along x): the two overlap
    # by 15 to 30 % of their length, and b's centre wraps to a's height, k periods of x away,
    # so that only b's image k >= 2 periods down finds the overlap (at 0.3: 2.4 below the
    # box, beyond half the reach of two needles)
    shift = math.floor(2.5 / period) * period
    b = a + (shift, 0.0, shift)
    report = verify_polyhedra([a, b], None, lo, hi, periodic=True)
    assert report.overlapping_pairs == ((0, 1),)
    assert report.worst_overlap_fraction > 0.1
    # moved half a period of z: parallel beside a (0.35 period apart, 0.1 thick): valid
    apart = verify_polyhedra([a, b + (0, 0, 0.5 * period)], None, lo, hi, periodic=True)
    assert apart.ok and apart.n_candidate_pairs > 0
    # along z instead of the diagonal, a needle longer than the period meets its own images
    upright = (CUBE - 0.5) * (0.1, 0.1, 1.5 * period) + (10.0, 10.0, 0.5 * period)
    own = verify_polyhedra([upright], None, lo, hi, periodic=True)
    assert own.overlapping_pairs == ((0, 0),)


def test_periodic_touching_lattice_is_valid():
    report = verify_polyhedra(grid(6), None, (0, 0, 0), (6, 6, 6), periodic=True)
    assert report.ok
    assert report.n_candidate_pairs == 13 * 6**3  # every cube and its 26 neighbours, once


def test_containment():
    inside = CUBE + (1, 1, 1)
    on_the_wall = CUBE  # touching the walls is allowed
    out = CUBE + (3, 1, 2 + 1e-3)  # 1e-3 of its size beyond the top
    barely = CUBE + (1, 3, 2 + 1e-12)  # below rel_tol
    report = verify_polyhedra([inside, on_the_wall, out, barely], None, (0, 0, 0), (5, 5, 3))
    assert not report.ok
    assert report.n_outside == 1
    assert report.worst_outside == (2, pytest.approx(1e-3, rel=1e-9))
    assert report.n_overlapping_pairs == 0
    small = verify_polyhedra([inside * 1e-6, barely * 1e-6], None, (0, 0, 0), (5e-6, 5e-6, 3e-6))
    assert small.ok
    assert small.worst_outside == (1, pytest.approx(1e-12, rel=1e-3))


def test_containment_is_relative_to_the_size():
    """1e-3 of a particle's size is found at 1e-6 scale (1e-9 in absolute units)."""
    s = 1e-6
    out = (CUBE + (0, 0, 1e-3)) * s
    report = verify_polyhedra([out], None, (0, 0, 0), (s, s, s))
    assert report.n_outside == 1
    assert report.worst_outside == (0, pytest.approx(1e-3, rel=1e-6))


def test_report_is_frozen_and_reads_as_one_paragraph():
    cubes = grid(3)
    cubes[0] = cubes[0] + (0.5, 0, -0.25)
    report = verify_polyhedra(cubes, None, (0, 0, 0), (3, 3, 3))
    assert isinstance(report, Report3D)
    with pytest.raises(dataclasses.FrozenInstanceError):
        report.ok = True  # type: ignore[misc]
    text = str(report)
    assert "\n" not in text
    assert "INVALID" in text and "particles 0 and" in text and "leave the box" in text
    assert "valid" in str(verify_polyhedra(grid(2), None, (0, 0, 0), (2, 2, 2)))
    empty = verify_polyhedra([], None, (0, 0, 0), (1, 1, 1))
    assert empty.ok and empty.n_checked == 0


# ---------------------------------------------------------------- scale


def _near_fcc(cells, seed):
    """Hulls of 20 points on the Voronoi cells of an FCC lattice, shrunk a little."""
    rng = np.random.default_rng(seed)
    basis = np.array([(0, 0, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1)], dtype=float)
    idx = np.array([(a, b, c) for a in range(cells) for b in range(cells) for c in range(cells)])
    sites = (2.0 * idx[:, None, :] + basis[None, :, :]).reshape(-1, 3)
    u = rng.normal(size=(len(sites), 20, 3))
    u /= np.sort(np.abs(u), axis=2)[:, :, 1:].sum(axis=2)[:, :, None]  # |x_i +- x_j| <= 1
    u *= rng.uniform(0.99, 0.999, size=(len(sites), 1, 1))
    return list(u + sites[:, None, :]), 2.0 * cells


def test_nearly_touching_random_polyhedra_are_valid():
    verts, side = _near_fcc(4, seed=2)
    report = verify_polyhedra(verts, None, (-1, -1, -1), (side, side, side))
    assert report.ok, str(report)
    assert report.n_candidate_pairs > 4 * len(verts)
    periodic = verify_polyhedra(verts, None, (0, 0, 0), (side, side, side), periodic=True)
    assert periodic.ok
    assert periodic.n_candidate_pairs > report.n_candidate_pairs
    # grown by 2 %, neighbours overlap
    grown = [(v - v.mean(axis=0)) * 1.02 + v.mean(axis=0) for v in verts]
    assert not verify_polyhedra(grown, None, (-2, -2, -2), (side + 1, side + 1, side + 1))


@pytest.mark.slow
def test_ten_thousand_polyhedra_in_under_a_minute():
    verts, side = _near_fcc(14, seed=1)  # 10 976 particles
    start = time.process_time()
    report = verify_polyhedra(verts, None, (-1, -1, -1), (side, side, side))
    elapsed = time.process_time() - start
    assert report.ok
    assert report.n_checked == 10_976
    assert elapsed < 60


def test_the_sphere_oracle_finds_overlaps_images_and_walls() -> None:
    from regopack.geometry.sphere_volume import lens_volume
    from regopack.verification.polyhedra import verify_spheres

    # lens volume against the cap formula: two unit balls at distance 1 share 5 pi / 12
    assert lens_volume(1.0, 1.0, 1.0) == pytest.approx(5 * np.pi / 12, rel=1e-12)
    assert lens_volume(2.0, 0.5, 1.0) == pytest.approx(4 / 3 * np.pi * 0.125, rel=1e-12)
    lo, hi = [0, 0, 0], [10, 10, 10]
    ok = verify_spheres([[2, 2, 2], [4, 2, 2]], [1, 1], lo, hi)
    assert ok.ok and ok.worst_overlap_fraction == 0.0
    bad = verify_spheres([[2, 2, 2], [3.9, 2, 2]], [1, 1], lo, hi)
    assert not bad.ok and bad.overlapping_pairs == ((0, 1),)
    out = verify_spheres([[0.5, 2, 2]], [1], lo, hi)
    assert not out.ok and out.n_outside == 1
    # across a periodic face: 0.5 and 9.6 are 0.9 apart
    img = verify_spheres([[0.5, 5, 5], [9.6, 5, 5]], [0.5, 0.5], lo, hi, periodic=True)
    assert not img.ok and img.overlapping_pairs == ((0, 1),)
    assert verify_spheres([[0.5, 5, 5], [9.5, 5, 5]], [0.5, 0.5], lo, hi, periodic=True).ok


def test_a_report_names_what_it_checked() -> None:
    spheres = verify_spheres([[0, 0, 0], [2, 0, 0]], [1, 1], [-1, -1, -1], [3, 1, 1])
    assert str(spheres).startswith("Checked 2 spheres in a walled box")
    solids = verify_polyhedra([CUBE, CUBE + [1.0, 0, 0]], None, [0, 0, 0], [2, 1, 1])
    assert str(solids).startswith("Checked 2 convex polyhedra in a walled box")
