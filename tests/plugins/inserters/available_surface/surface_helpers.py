"""Helpers for the available-surface tests: polyhedra, rotations and independent checks."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection
from scipy.spatial.transform import Rotation

from regopack.plugins.inserters.available_surface.envelope import (
    minkowski_envelope,
    polyhedron_edges,
)
from regopack.plugins.inserters.available_surface.polyhedron import (
    Polyhedron,
    polyhedron_from_points,
)


def rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random rotation matrix."""
    return Rotation.random(random_state=rng).as_matrix()


def random_points(rng: np.random.Generator, n: int = 24, scale: float = 1.0) -> np.ndarray:
    """``n`` points at radius in ``[0.5, 1] * scale`` in uniformly random directions."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * rng.uniform(0.5, 1.0, size=(n, 1)) * scale


def random_polyhedron(
    rng: np.random.Generator,
    n: int = 24,
    scale: float = 1.0,
    aspect: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> Polyhedron:
    """Convex hull of random points, stretched by ``aspect`` and randomly rotated."""
    while True:
        pts = random_points(rng, n, 1.0) * np.asarray(aspect)
        pts = pts @ rotation(rng).T * scale
        try:
            return polyhedron_from_points(pts)
        except ValueError:  # the origin fell outside: draw again
            continue


def box(half: tuple[float, float, float] | float, rot: np.ndarray | None = None) -> Polyhedron:
    """An axis-aligned box (or one rotated by ``rot``) centred on its reference point."""
    h = np.broadcast_to(np.asarray(half, dtype=np.float64), (3,))
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
    if rot is not None:
        corners = corners @ rot.T
    return polyhedron_from_points(corners)


def tetrahedron(size: float = 1.0, rot: np.ndarray | None = None) -> Polyhedron:
    """A regular tetrahedron with circumradius ``size * sqrt(3)``, centred."""
    pts = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64) * size
    if rot is not None:
        pts = pts @ rot.T
    return polyhedron_from_points(pts)


def transformed(poly: Polyhedron, scale: float = 1.0, rot: np.ndarray | None = None) -> Polyhedron:
    """``poly`` scaled about its reference point and rotated."""
    r = np.eye(3) if rot is None else rot
    return Polyhedron(
        vertices=poly.vertices @ r.T * scale,
        normals=np.ascontiguousarray(poly.normals @ r.T),
        support=poly.support * scale,
        face_vertices=poly.face_vertices,
        face_offsets=poly.face_offsets,
    )


def differences(p: Polyhedron, q: Polyhedron) -> np.ndarray:
    """All vertex differences ``p_i - q_j`` (the envelope is their convex hull)."""
    return (p.vertices[:, None, :] - q.vertices[None, :, :]).reshape(-1, 3)


def circumradius(poly: Polyhedron) -> float:
    return float(np.max(np.linalg.norm(poly.vertices, axis=1)))


def check_closed_surface(poly: Polyhedron, tol: float) -> None:
    """Euler's formula, shared edges, planar convex counter-clockwise faces."""
    v = len(poly.vertices)
    f = len(poly.normals)
    e = len(poly.face_vertices) // 2
    assert v - e + f == 2
    polyhedron_edges(poly.face_vertices, poly.face_offsets, v)  # raises if not closed
    assert np.allclose(np.linalg.norm(poly.normals, axis=1), 1.0, atol=1e-12)
    assert len(np.unique(poly.face_vertices)) == v
    for i in range(f):
        loop = poly.vertices[poly.face_vertices[poly.face_offsets[i] : poly.face_offsets[i + 1]]]
        assert len(loop) >= 3
        # on the face's plane
        assert np.max(np.abs(loop @ poly.normals[i] - poly.support[i])) <= tol
        # convex and counter-clockwise about the normal: every turn is to the left
        a = loop
        b = np.roll(loop, -1, axis=0)
        c = np.roll(loop, -2, axis=0)
        turns = np.cross(b - a, c - b) @ poly.normals[i]
        assert np.all(turns > 0.0)
    # every vertex inside every face plane (convexity)
    assert np.max(poly.vertices @ poly.normals.T - poly.support) <= tol


def contact_distance(p: Polyhedron, q: Polyhedron, u: np.ndarray) -> float:
    """Distance along the unit direction ``u`` at which ``q``'s centre makes ``q`` touch ``p``."""
    env = minkowski_envelope(p, q)
    cos = env.normals @ u
    return float(np.min(env.support[cos > 0] / cos[cos > 0]))


def crowded_scene(
    rng: np.random.Generator,
    interferers: int,
    scale: float = 1.0,
    ratio: float = 0.6,
    gap: tuple[float, float] = (1.0, 1.3),
) -> dict:
    """A candidate ``P_k`` at a random centre, a new particle ``Q`` and interferers around.

    Each interferer ``P_j`` sits in a random direction at its contact
    distance from ``P_k`` times a factor in ``gap``. Returns the particles
    (relative to their centres), the centres and the envelopes.
    """
    centre = rng.uniform(-10.0, 10.0, 3) * scale
    pk = random_polyhedron(rng, 24, scale)
    q = random_polyhedron(rng, 16, scale * ratio)
    pjs = []
    centres = []
    for _ in range(interferers):
        pj = random_polyhedron(rng, int(rng.integers(8, 24)), scale * rng.uniform(0.6, 1.2))
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        pjs.append(pj)
        centres.append(centre + u * contact_distance(pk, pj, u) * rng.uniform(*gap))
    return {
        "pk": pk,
        "q": q,
        "centre": centre,
        "ek": minkowski_envelope(pk, q),
        "pjs": pjs,
        "centres": np.array(centres).reshape(-1, 3),
        "envelopes": [minkowski_envelope(pj, q) for pj in pjs],
    }


def face_samples(env: Polyhedron, face: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points uniform on face ``face`` of ``env`` (relative to its reference point)."""
    loop = env.vertices[env.face_vertices[env.face_offsets[face] : env.face_offsets[face + 1]]]
    a = loop[0]
    b = loop[1:-1]
    c = loop[2:]
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(areas), size=n, p=areas / areas.sum())
    u = rng.random((n, 2))
    flip = u.sum(axis=1) > 1.0
    u[flip] = 1.0 - u[flip]
    return a + u[:, :1] * (b[tri] - a) + u[:, 1:] * (c[tri] - a)


def free_mask(
    points: np.ndarray,
    envelopes: list[Polyhedron],
    centres: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    slack: float = 0.0,
) -> np.ndarray:
    """Which absolute ``points`` are free: in the box, in no open envelope interior.

    ``slack`` counts points up to that depth inside an envelope, or outside
    the box, as free.
    """
    free = np.all((points >= lo - slack) & (points <= hi + slack), axis=1)
    for env, c in zip(envelopes, centres, strict=True):
        inside = np.all((points - c) @ env.normals.T < env.support - slack, axis=1)
        free &= ~inside
    return free


def depth_on_boundary(points: np.ndarray, env: Polyhedron, centre: np.ndarray) -> np.ndarray:
    """Signed distance of each point to the boundary of ``env`` at ``centre`` (>0 outside)."""
    return np.max((points - centre) @ env.normals.T - env.support, axis=1)


def _joint_planes(a_vertices: np.ndarray, b_vertices: np.ndarray) -> tuple[np.ndarray, float]:
    """Face planes of both hulls, in coordinates centred on ``a`` and scaled to its size."""
    origin = a_vertices.mean(axis=0)
    size = float(np.max(np.linalg.norm(a_vertices - origin, axis=1)))
    a = (a_vertices - origin) / size
    b = (b_vertices - origin) / size
    return np.vstack([ConvexHull(a).equations, ConvexHull(b).equations]), size


def _deepest_point(eq: np.ndarray) -> tuple[np.ndarray, float]:
    """Maximise ``s`` subject to ``n·x + d + s <= 0`` (qhull's unit outward normals)."""
    a_ub = np.column_stack([eq[:, :3], np.ones(len(eq))])
    res = linprog(
        c=[0, 0, 0, -1],
        A_ub=a_ub,
        b_ub=-eq[:, 3],
        bounds=[(None, None)] * 4,
        options={"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10},
    )
    assert res.status == 0, res.message
    return res.x[:3], float(-res.fun)


def overlap_depth(a_vertices: np.ndarray, b_vertices: np.ndarray) -> float:
    """Depth of the deepest point common to two convex hulls, by linear programming.

    The largest ``s`` such that some point lies at least ``s`` inside every
    face plane of both hulls: positive when they overlap, zero when they
    touch, negative when they are apart.
    """
    eq, size = _joint_planes(a_vertices, b_vertices)
    return _deepest_point(eq)[1] * size


def overlap_volume(a_vertices: np.ndarray, b_vertices: np.ndarray) -> float:
    """Volume of the intersection of two convex hulls (0 when they only touch or are apart)."""
    eq, size = _joint_planes(a_vertices, b_vertices)
    inner, depth = _deepest_point(eq)
    if depth <= 1e-9:
        return 0.0
    return float(ConvexHull(HalfspaceIntersection(eq, inner).intersections).volume) * size**3
