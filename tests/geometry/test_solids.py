"""Solid batches: consistency checks, volumes, circumradii and interleaving by phase."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from regopack.geometry.solids import SolidBatch, concat_solids, sphere_volume


def _cube(half: float, rot: tuple[float, float, float, float] = (1.0, 0, 0, 0)) -> SolidBatch:
    """An axis-aligned cube of half-side ``half`` about the origin, as one solid."""
    v = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])
    faces, normals = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            idx = np.flatnonzero(v[:, axis] * sign > 0)
            n = np.zeros(3)
            n[axis] = sign
            # order the face's corners counter-clockwise seen from outside
            c = v[idx].mean(axis=0)
            u = np.cross(n, [1.0, 0, 0] if axis != 0 else [0, 1.0, 0])
            w = np.cross(n, u)
            ang = np.arctan2((v[idx] - c) @ w, (v[idx] - c) @ u)
            loop = idx[np.argsort(ang)]
            p = v[loop]
            if np.dot(np.cross(p[1] - p[0], p[2] - p[0]), n) < 0:
                loop = loop[::-1]
            faces.append(loop)
            normals.append(n)
    fvo = np.concatenate([[0], np.cumsum([len(f) for f in faces])]).astype(np.int64)
    return SolidBatch(
        vertices=v,
        offsets=np.array([0, 8]),
        face_vertices=np.concatenate(faces).astype(np.int64),
        face_vertex_offsets=fvo,
        face_offsets=np.array([0, 6]),
        normals=np.array(normals),
        support=np.full(6, half),
        rotation=np.array([rot]),
    )


def _spheres(r: list[float]) -> SolidBatch:
    n = len(r)
    return SolidBatch(
        vertices=np.zeros((n, 3)),
        offsets=np.arange(n + 1),
        face_vertices=np.zeros(0, dtype=np.int64),
        face_vertex_offsets=np.zeros(1, dtype=np.int64),
        face_offsets=np.zeros(n + 1, dtype=np.int64),
        normals=np.zeros((0, 3)),
        support=np.zeros(0),
        rotation=np.tile([1.0, 0, 0, 0], (n, 1)),
        rounding=np.array(r, dtype=float),
    )


def test_cube_volume_and_circumradius() -> None:
    cube = _cube(0.5)
    assert cube.volume[0] == pytest.approx(1.0, rel=1e-12)
    assert cube.circumradius[0] == pytest.approx(np.sqrt(3) / 2)
    verts, loops = cube.solid(0)
    assert verts.shape == (8, 3) and len(loops) == 6
    assert ConvexHull(verts).volume == pytest.approx(cube.volume[0])


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_volume_scales_as_the_cube_of_length(scale: float) -> None:
    assert _cube(0.5 * scale).volume[0] == pytest.approx(scale**3, rel=1e-12)


def test_sphere_volume_and_radius() -> None:
    s = _spheres([1.0, 2.0])
    assert s.volume.tolist() == pytest.approx(sphere_volume(np.array([1.0, 2.0])).tolist())
    assert s.circumradius.tolist() == [1.0, 2.0]


def test_inconsistent_arrays_are_refused() -> None:
    cube = _cube(0.5)
    with pytest.raises(ValueError, match="rotation"):
        SolidBatch(**{**cube.__dict__, "rotation": np.zeros((2, 4))})
    with pytest.raises(ValueError, match="vertices"):
        SolidBatch(**{**cube.__dict__, "vertices": np.zeros((8, 2))})
    with pytest.raises(ValueError, match="normals"):
        SolidBatch(**{**cube.__dict__, "support": np.zeros(5)})


def test_concat_interleaves_phases_back_into_particle_order() -> None:
    a = _cube(0.5)
    b = _spheres([3.0, 4.0])
    merged = concat_solids([(np.array([1]), a), (np.array([0, 2]), b)], 3)
    assert len(merged) == 3
    assert merged.rounding is not None
    assert merged.rounding.tolist() == [3.0, 0.0, 4.0]
    assert merged.volume[1] == pytest.approx(1.0)
    assert merged.volume[[0, 2]].tolist() == pytest.approx(
        sphere_volume(np.array([3.0, 4.0])).tolist()
    )
    verts, loops = merged.solid(1)
    assert np.array_equal(verts, a.vertices) and len(loops) == 6
    assert merged.solid(0)[1] == [] and merged.solid(2)[1] == []


def _hulls(seed: int, n: int) -> tuple[SolidBatch, list[float]]:
    """``n`` random convex hulls (triangulated faces, 5 to 30 points each) as one batch."""
    rng = np.random.default_rng(seed)
    verts, loops, normals, support, vcount, fcount, volumes = [], [], [], [], [], [], []
    for _ in range(n):
        pts = rng.normal(size=(int(rng.integers(5, 31)), 3)) * rng.uniform(0.1, 10.0)
        hull = ConvexHull(pts)
        v = pts[hull.vertices]
        local = {int(g): k for k, g in enumerate(hull.vertices)}
        for tri, eq in zip(hull.simplices, hull.equations, strict=True):
            loop = np.array([local[int(g)] for g in tri])
            p = v[loop]
            if np.dot(np.cross(p[1] - p[0], p[2] - p[0]), eq[:3]) < 0:
                loop = loop[::-1]
            loops.append(loop)
            normals.append(eq[:3])
            support.append(-eq[3])
        verts.append(v)
        vcount.append(len(v))
        fcount.append(len(hull.simplices))
        volumes.append(hull.volume)
    batch = SolidBatch(
        vertices=np.concatenate(verts),
        offsets=np.concatenate([[0], np.cumsum(vcount)]).astype(np.int64),
        face_vertices=np.concatenate(loops).astype(np.int64),
        face_vertex_offsets=np.arange(0, 3 * len(loops) + 1, 3, dtype=np.int64),
        face_offsets=np.concatenate([[0], np.cumsum(fcount)]).astype(np.int64),
        normals=np.array(normals),
        support=np.array(support),
        rotation=np.tile([1.0, 0, 0, 0], (n, 1)),
    )
    return batch, volumes


@pytest.mark.parametrize("seed", range(4))
def test_volumes_of_random_hulls_agree_with_qhull(seed: int) -> None:
    """Every particle's volume, all faces at once, is Qhull's (each face belongs to its owner)."""
    batch, volumes = _hulls(seed, 7)
    assert batch.volume.tolist() == pytest.approx(volumes, rel=1e-12)


@pytest.mark.parametrize("m", [0, 1, 4, 7])
def test_the_head_of_a_batch_keeps_its_first_solids(m: int) -> None:
    batch, volumes = _hulls(5, 7)
    head = batch.head(m)
    assert len(head) == m
    for j in range(m):
        verts, loops = head.solid(j)
        want_verts, want_loops = batch.solid(j)
        assert np.array_equal(verts, want_verts)
        assert [loop.tolist() for loop in loops] == [loop.tolist() for loop in want_loops]
    assert head.volume.tolist() == pytest.approx(volumes[:m])
    faces = int(batch.face_offsets[m])
    assert np.array_equal(head.normals, batch.normals[:faces])
    assert np.array_equal(head.support, batch.support[:faces])
    assert head.rounding is None
    spheres = _spheres([1.0, 2.0, 3.0]).head(2)
    assert spheres.rounding is not None and spheres.rounding.tolist() == [1.0, 2.0]
    with pytest.raises(ValueError, match="between 0 and 7"):
        batch.head(8)
