"""Random convex polyhedra with a shape coefficient psi (the 3D counterpart of the octagon).

Each particle shares a fixed set of ``m`` unit directions ``n_k``
(:mod:`regopack.plugins.shapes.polyhedra.directions`; by default the 14 face normals
of the truncated octahedron) and draws raw support distances

    s_k = 1 + a σ_k |2 ξ_k - 1|^ψ,   σ_k = ±1 with equal probability,  ξ_k ~ U[0, 1),

as the octagon does (SPEC §2). The polyhedron is the intersection of the
half-spaces ``n_k . x <= s_k``: convex, and containing the origin because
``s_k >= 1 - a >= 0``. Its vertices are enumerated exactly
(:mod:`regopack.plugins.shapes.polyhedra.kernel`), every ``s_k`` is replaced by the
true support value ``max_v n_k . v`` (a direction whose plane did not touch
the polyhedron now touches it at an edge or a vertex), the polyhedron is
translated so that its volume centroid is the reference point, scaled to the
volume ``(4/3) π r³`` and turned by a uniformly random rotation. Larger ψ is
more regular; ψ → ∞ gives the polyhedron with all support distances equal.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.plugins.shapes.polyhedra.batch import PolyhedronBatch
from regopack.plugins.shapes.polyhedra.directions import check_directions, truncated_octahedron
from regopack.plugins.shapes.polyhedra.kernel import (
    NO_VOLUME,
    OK,
    direction_triples,
    enumerate_polyhedra,
    face_bases,
)
from regopack.plugins.shapes.polyhedra.rotations import random_rotations

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SUPPORT_FLOOR = 1e-9
"""Raw support distances are raised to at least this (only ``a = 1`` can go below).

With ``a = 1`` a draw can give ``s_k = 0`` (the origin on the boundary) and two
opposite directions could both give 0 (a flat polyhedron); the floor keeps the
origin strictly inside and the volume positive. The vertex enumeration needs
no interior point, so the floor is the only guard this limit requires.
"""

__all__ = ["SUPPORT_FLOOR", "polyhedra_from_support", "random_polyhedra", "raw_support"]


def raw_support(sign: FloatArray, xi: FloatArray, psi: float, a: float) -> FloatArray:
    """Raw support distances ``max(1 + a σ |2 ξ - 1|^ψ, SUPPORT_FLOOR)``.

    Parameters
    ----------
    sign
        ``(n, m)`` values ``σ = ±1``.
    xi
        ``(n, m)`` uniform numbers in ``[0, 1)``.
    psi
        Shape coefficient ψ > 0.
    a
        Perturbation amplitude in ``[0, 1]``.

    Returns
    -------
    ndarray
        ``(n, m)`` support distances in ``[max(1 - a, SUPPORT_FLOOR), 1 + a]``.

    Examples
    --------
    >>> raw_support(np.array([[1.0, -1.0]]), np.array([[0.0, 0.5]]), psi=1.0, a=0.5)
    array([[1.5, 1. ]])
    """
    s = 1.0 + a * sign * np.abs(2.0 * xi - 1.0) ** psi
    return np.maximum(s, SUPPORT_FLOOR)


def _radius(radius: ArrayLike) -> FloatArray:
    r = np.asarray(radius, dtype=np.float64)
    if r.ndim != 1:
        raise ValueError(f"radius must be a 1-D array, got shape {r.shape}")
    if not np.all(np.isfinite(r) & (r > 0.0)):
        raise ValueError("every radius must be finite and positive")
    return r


def polyhedra_from_support(
    support: ArrayLike,
    radius: ArrayLike,
    directions: ArrayLike | None = None,
    rotation: ArrayLike | None = None,
) -> PolyhedronBatch:
    """Polyhedra ``{x : n_k . x <= support[i, k]}``, centred, scaled and rotated.

    The deterministic part of :func:`random_polyhedra`: vertices and proper
    faces of each intersection of half-spaces, true support values along
    every direction, the volume centroid as reference point, the scale that
    makes the volume ``(4/3) π r³``, then the rotation.

    Parameters
    ----------
    support
        ``(n, m)`` finite plane offsets; each polyhedron must have a positive
        volume (it need not contain the origin).
    radius
        ``(n,)`` equivalent radius of each particle.
    directions
        ``(m, 3)`` direction set (validated by
        :func:`~regopack.plugins.shapes.polyhedra.directions.check_directions`);
        the truncated octahedron's by default.
    rotation
        ``(n, 3, 3)`` rotation matrices; none (the identity) by default.

    Returns
    -------
    PolyhedronBatch
        The polyhedra.

    Raises
    ------
    ValueError
        If an input has the wrong shape or a bad value, or a polyhedron is
        empty or flat.

    Examples
    --------
    Equal supports give the truncated octahedron with all 14 faces:

    >>> batch = polyhedra_from_support(np.ones((1, 14)), np.array([1.0]))
    >>> len(batch.faces_of(0)), batch.vertices_of(0).shape
    (14, (24, 3))
    """
    d = check_directions(truncated_octahedron() if directions is None else directions)
    r = _radius(radius)
    n, m = r.shape[0], d.shape[0]
    s = np.ascontiguousarray(np.asarray(support, dtype=np.float64))
    if s.shape != (n, m):
        raise ValueError(f"support must have shape (n, m) = {(n, m)}, got {s.shape}")
    if not np.all(np.isfinite(s)):
        raise ValueError("every support value must be finite")
    if rotation is None:
        rot = np.broadcast_to(np.eye(3), (n, 3, 3))
    else:
        rot = np.asarray(rotation, dtype=np.float64)
        if rot.shape != (n, 3, 3):
            raise ValueError(f"rotation must have shape {(n, 3, 3)}, got {rot.shape}")
    tri = direction_triples(d)
    u, w = face_bases(d)
    # a convex polyhedron with F <= m faces has at most 2F - 4 vertices and 3F - 6 edges
    vcap, fcap = 2 * m, 6 * m
    nvert, verts, nface, fdir, fsize, fverts, hsup, vol, cen, status = enumerate_polyhedra(
        s, d, tri.members, tri.inverse, tri.kappa, u, w, vcap, fcap
    )
    bad = np.flatnonzero(status != OK)
    if bad.size:
        i = int(bad[0])
        if status[i] == NO_VOLUME:
            raise ValueError(f"polyhedron {i} is empty or flat: its support values bound no volume")
        raise RuntimeError(
            f"polyhedron {i}: the vertex enumeration failed (status {int(status[i])}); "
            "its support values are nearly degenerate for this direction set"
        )
    # r times the cube root of a number without a unit: a radius scaled by a power of two
    # scales every length by exactly that power (the cube root of r**3 / vol would not:
    # libm's cbrt rounds x and x * 2**(3k) differently when their exponents differ in sign)
    scale = r * np.cbrt(4.0 / 3.0 * math.pi / vol)
    local = (verts - cen[:, None, :]) * scale[:, None, None]
    vmask = np.arange(vcap) < nvert[:, None]
    world = np.einsum("nij,nvj->nvi", rot, local)
    distance = np.where(vmask, np.linalg.norm(world, axis=2), 0.0)
    dir_support = (hsup - cen @ d.T) * scale[:, None]
    fmask = np.arange(m) < nface[:, None]
    face_direction = fdir[fmask]
    owner = np.repeat(np.arange(n), nface)
    normals = np.einsum("fij,fj->fi", rot[owner], d[face_direction])
    face_support = dir_support[owner, face_direction]
    sizes = fsize[fmask]
    fvmask = np.arange(fcap) < fsize.sum(axis=1)[:, None]
    inradius = np.where(fmask, np.take_along_axis(dir_support, np.maximum(fdir, 0), 1), np.inf)
    zero = np.zeros(1, dtype=np.int64)
    return PolyhedronBatch(
        vertices=np.ascontiguousarray(world[vmask]),
        vertex_offsets=np.concatenate([zero, np.cumsum(nvert)]),
        normals=np.ascontiguousarray(normals.reshape(-1, 3)),
        support=face_support,
        face_offsets=np.concatenate([zero, np.cumsum(nface)]),
        face_vertices=np.ascontiguousarray(fverts[fvmask]),
        face_vertex_offsets=np.concatenate([zero, np.cumsum(sizes)]),
        face_direction=face_direction,
        volume=vol * scale * scale * scale,  # products, not pow: exact under powers of two
        circumradius=distance.max(axis=1, initial=0.0),
        inradius=inradius.min(axis=1, initial=np.inf),
        directions=d,
        rotation=np.ascontiguousarray(rot),
        direction_support=dir_support,
    )


def random_polyhedra(
    rng: np.random.Generator,
    radius: ArrayLike,
    psi: float,
    a: float,
    directions: ArrayLike | None = None,
) -> PolyhedronBatch:
    """Draw one random convex polyhedron per radius.

    The random numbers of the whole batch come from ``rng`` in this order,
    each as one call: the signs ``σ``, ``rng.integers(0, 2, size=(n, m))``
    mapped to ``±1``; then ``ξ``, ``rng.random((n, m))``; then the rotations,
    ``rng.standard_normal((n, 4))`` (quaternions, see
    :func:`~regopack.plugins.shapes.polyhedra.rotations.random_rotations`). The
    raw supports (:func:`raw_support`) go to :func:`polyhedra_from_support`.

    Parameters
    ----------
    rng
        The random generator.
    radius
        ``(n,)`` equivalent radius of each particle: its volume is ``(4/3) π r³``.
    psi
        Shape coefficient ψ, finite and > 0: larger is more regular.
    a
        Perturbation amplitude in ``[0, 1]``: raw supports lie within ``±a`` of 1.
    directions
        ``(m, 3)`` direction set; the truncated octahedron's 14 by default.

    Returns
    -------
    PolyhedronBatch
        The polyhedra, each relative to its volume centroid.

    Raises
    ------
    ValueError
        If ``psi``, ``a``, ``radius`` or ``directions`` is invalid.

    Examples
    --------
    >>> batch = random_polyhedra(np.random.default_rng(0), np.array([1.0, 2.0]), psi=0.5, a=1 / 3)
    >>> len(batch), bool(np.allclose(batch.volume, 4 / 3 * np.pi * np.array([1.0, 8.0])))
    (2, True)
    """
    if not (math.isfinite(psi) and psi > 0.0):
        raise ValueError(f"psi must be finite and > 0, got {psi!r}")
    if not 0.0 <= a <= 1.0:
        raise ValueError(f"a must lie in [0, 1], got {a!r}")
    d = check_directions(truncated_octahedron() if directions is None else directions)
    r = _radius(radius)
    n, m = r.shape[0], d.shape[0]
    sign = (2 * rng.integers(0, 2, size=(n, m)) - 1).astype(np.float64)
    xi = rng.random((n, m))
    rot = random_rotations(rng, n)
    return polyhedra_from_support(raw_support(sign, xi, psi, a), r, d, rot)
