"""Helpers for the polyhedra tests: independent checks of one polyhedron of a batch."""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from regopack.plugins.shapes.polyhedra import PolyhedronBatch


def vector_area(v: np.ndarray, face: np.ndarray) -> np.ndarray:
    """Half the sum of the cross products of consecutive vertices: area times the
    unit normal of the side from which the face runs counter-clockwise."""
    p = v[face]
    return 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)


def hull_volume_and_centroid(v: np.ndarray) -> tuple[float, np.ndarray]:
    """Volume and volume centroid of the convex hull of ``v``, from qhull's triangles."""
    hull = ConvexHull(v)
    inside = v.mean(axis=0)
    tets = v[hull.simplices] - inside
    vol6 = np.abs(np.einsum("ij,ij->i", tets[:, 0], np.cross(tets[:, 1], tets[:, 2])))
    centroid = inside + (vol6[:, None] * tets.sum(axis=1) / 4.0).sum(axis=0) / vol6.sum()
    return float(hull.volume), centroid


def check_polyhedron(batch: PolyhedronBatch, i: int, radius: float, rel: float = 1e-9) -> None:
    """Every property a polyhedron of the batch must have, checked independently."""
    v, faces = batch.polyhedron(i)
    f0, f1 = batch.face_offsets[i], batch.face_offsets[i + 1]
    normals, support = batch.normals[f0:f1], batch.support[f0:f1]
    m = batch.directions.shape[0]
    size = batch.circumradius[i]
    tol = rel * size
    assert 4 <= len(faces) <= m
    assert len(v) >= 4
    # face directions: distinct, increasing, and the rotated directions of the set
    fd = batch.face_direction[f0:f1]
    assert np.all(np.diff(fd) > 0) and fd.min() >= 0 and fd.max() < m
    assert np.allclose(normals, batch.directions[fd] @ batch.rotation[i].T, atol=1e-12)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
    # convexity: every vertex satisfies every face inequality; faces lie in their planes
    assert np.all(v @ normals.T <= support + tol)
    for face, n, h in zip(faces, normals, support, strict=True):
        assert len(face) >= 3 and len(set(face.tolist())) == len(face)
        assert np.allclose(v[face] @ n, h, atol=tol)
        va = vector_area(v, face)
        # counter-clockwise from outside: the vector area points along the outward normal
        assert va @ n > -1e-12 * size * size
        assert np.linalg.norm(va - (va @ n) * n) <= 1e-9 * size * size  # parallel to n
    # outward: the reference point is inside every face plane, strictly
    assert np.all(support > 0)
    # the centroid lies at least a quarter of the width from every supporting plane
    width = support + np.max(-(v @ normals.T), axis=0)
    assert np.all(support >= width / 4.0 - tol)
    # a closed surface: vector areas sum to zero, Euler's formula holds
    total = sum(vector_area(v, face) for face in faces)
    assert np.linalg.norm(total) <= 1e-9 * size * size
    edges = {
        tuple(sorted((int(f[j]), int(f[(j + 1) % len(f)])))) for f in faces for j in range(len(f))
    }
    assert sum(len(f) for f in faces) == 2 * len(edges)  # every edge in exactly two faces
    assert len(v) - len(edges) + len(faces) == 2
    every = set().union(*(set(f.tolist()) for f in faces))
    assert every == set(range(len(v)))
    # volume and reference point, from an independent convex hull
    target = 4.0 / 3.0 * np.pi * radius**3
    hull_volume, centroid = hull_volume_and_centroid(v)
    assert abs(batch.volume[i] / target - 1) < rel
    assert abs(hull_volume / target - 1) < rel
    assert np.linalg.norm(centroid) <= 1e-9 * size
    # radii and the support along every direction of the set
    assert batch.circumradius[i] == np.max(np.linalg.norm(v, axis=1))
    assert batch.inradius[i] == np.min(support)
    rotated = batch.directions @ batch.rotation[i].T
    assert np.allclose(batch.direction_support[i], np.max(v @ rotated.T, axis=0), rtol=0, atol=tol)
