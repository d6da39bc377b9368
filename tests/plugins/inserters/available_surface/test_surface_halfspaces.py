"""The interferer envelope as half-spaces is the envelope P ⊕ (-Q) exactly."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from regopack.plugins.inserters.available_surface.envelope import minkowski_envelope
from regopack.plugins.inserters.available_surface.halfspaces import minkowski_halfspaces
from regopack.plugins.inserters.available_surface.polyhedron import polyhedron_from_points
from regopack.plugins.shapes.polyhedra.shape import PolyhedronConfig, RandomPolyhedron


def _random_pair(seed: int, ratio: float, scale: float):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    # centred on their mean, so that the reference point lies inside each hull
    pts_p = rng.normal(size=(20, 3))
    pts_q = rng.normal(size=(16, 3))
    pts_p = (pts_p - pts_p.mean(axis=0)) * scale
    pts_q = (pts_q - pts_q.mean(axis=0)) * scale * ratio
    return polyhedron_from_points(pts_p), polyhedron_from_points(pts_q), pts_p, pts_q


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    ratio=st.sampled_from([1.0, 0.1, 1e-3]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_the_half_spaces_bound_the_envelope_exactly(seed: int, ratio: float, scale: float) -> None:
    p, q, pts_p, pts_q = _random_pair(seed, ratio, scale)
    normals, support = minkowski_halfspaces(p, q)
    env = minkowski_envelope(p, q)
    size = scale * (1 + ratio)
    # every vertex of the envelope is inside every half-space, on at least three planes
    slack = env.vertices @ normals.T - support
    assert slack.max() <= 1e-9 * size
    assert np.all(np.sum(np.abs(slack) <= 1e-9 * size, axis=1) >= 3)
    # every facet of the envelope is one of the planes
    match = np.abs(env.normals @ normals.T - 1.0) < 1e-9
    assert match.any(axis=1).all()
    # and the hull of the differences agrees on random points
    diffs = (pts_p[:, None, :] - pts_q[None, :, :]).reshape(-1, 3)
    hull = ConvexHull(diffs)
    rng = np.random.default_rng(seed)
    probe = rng.uniform(diffs.min(0), diffs.max(0), size=(2000, 3))
    in_hull = np.all(probe @ hull.equations[:, :3].T + hull.equations[:, 3] <= 1e-9 * size, axis=1)
    in_half = np.all(probe @ normals.T - support <= 1e-9 * size, axis=1)
    assert np.array_equal(in_hull, in_half)


def test_random_polyhedra_pairs() -> None:
    batch = RandomPolyhedron(PolyhedronConfig(psi=0.25)).generate(
        np.array([1.0, 0.3]), np.random.default_rng(2)
    )
    from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron

    polys = []
    for j in range(2):
        verts, loops = batch.solid(j)
        f0, f1 = batch.face_offsets[j], batch.face_offsets[j + 1]
        fo = np.concatenate([[0], np.cumsum([len(lp) for lp in loops])]).astype(np.int64)
        polys.append(
            Polyhedron(verts, batch.normals[f0:f1], batch.support[f0:f1], np.concatenate(loops), fo)
        )
    normals, support = minkowski_halfspaces(polys[0], polys[1])
    env = minkowski_envelope(polys[0], polys[1])
    assert (env.vertices @ normals.T - support).max() <= 1e-9
    assert len(support) >= len(env.support)
    assert len(support) == pytest.approx(len(env.support), rel=0.5)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_largest_dot_is_the_running_maximum(sign: float) -> None:
    from regopack.plugins.inserters.available_surface.halfspaces import _largest_dot

    rng = np.random.default_rng(5)
    for rows in range(0, 12):
        for _ in range(20):
            v = rng.normal(size=(rows, 3))
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            best = -np.inf
            for i in range(rows):
                d = sign * (n[0] * v[i, 0] + n[1] * v[i, 1] + n[2] * v[i, 2])
                best = d if d > best else best
            assert _largest_dot(n[0], n[1], n[2], v, sign) == best
