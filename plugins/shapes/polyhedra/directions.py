"""Fixed sets of unit directions: the face normals every random polyhedron shares.

A direction set is a float64 ``(m, 3)`` array of unit vectors ``n_k``. A random
polyhedron (:func:`regopack.plugins.shapes.polyhedra.generator.random_polyhedra`) is
the intersection of the half-spaces ``n_k . x <= s_k`` over the set, so the set
must be *positively spanning*: the intersection of ``n_k . x <= 1`` must be
bounded, which holds exactly when the origin lies strictly inside the convex
hull of the directions (:func:`check_directions`).

The default, :func:`truncated_octahedron`, has the 14 face normals of the
truncated octahedron, the Voronoi cell of the body-centred cubic lattice.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull, QhullError

FloatArray = NDArray[np.float64]

UNIT_TOL = 1e-9
"""A direction is unit when its length differs from 1 by at most this."""
DISTINCT_TOL = 1e-9
"""Two directions are distinct when they differ by more than this (Euclidean distance)."""
DEPTH_MIN = 1e-9
"""The origin must lie at least this far inside the hull of the directions.

The depth is the inverse of the largest vertex distance of the polyhedron
``{x : n_k . x <= 1}`` (the polar of the hull), so this bounds that polyhedron
to a ball of radius ``1 / DEPTH_MIN``.
"""

__all__ = [
    "check_directions",
    "cube",
    "fibonacci",
    "hull_depth",
    "rhombic_dodecahedron",
    "truncated_octahedron",
]


def cube() -> FloatArray:
    """Return the 6 face normals of the cube: ``±x``, ``±y``, ``±z``.

    Returns
    -------
    ndarray
        ``(6, 3)`` unit vectors, in the order ``+x, -x, +y, -y, +z, -z``.

    Examples
    --------
    >>> cube().shape
    (6, 3)
    """
    eye = np.eye(3)
    return np.ascontiguousarray(np.stack([eye, -eye], axis=1).reshape(6, 3))


def truncated_octahedron() -> FloatArray:
    """Return the 14 face normals of the truncated octahedron (the default direction set).

    Six normals of the square faces along ``±x, ±y, ±z`` (as :func:`cube`),
    then eight normals of the hexagonal faces along ``(±1, ±1, ±1) / √3``.

    Returns
    -------
    ndarray
        ``(14, 3)`` unit vectors.

    Examples
    --------
    >>> d = truncated_octahedron()
    >>> d.shape, bool(np.allclose(np.linalg.norm(d, axis=1), 1.0))
    ((14, 3), True)
    """
    signs = np.array([(x, y, z) for x in (1, -1) for y in (1, -1) for z in (1, -1)], float)
    return np.ascontiguousarray(np.vstack([cube(), signs / math.sqrt(3.0)]))


def rhombic_dodecahedron() -> FloatArray:
    """Return the 12 face normals of the rhombic dodecahedron, ``(±1, ±1, 0) / √2`` permuted.

    Returns
    -------
    ndarray
        ``(12, 3)`` unit vectors: the four of the ``xy`` plane, then ``xz``, then ``yz``.

    Examples
    --------
    >>> rhombic_dodecahedron().shape
    (12, 3)
    """
    rows = []
    for i, j in ((0, 1), (0, 2), (1, 2)):
        for si in (1.0, -1.0):
            for sj in (1.0, -1.0):
                v = np.zeros(3)
                v[i], v[j] = si, sj
                rows.append(v / math.sqrt(2.0))
    return np.ascontiguousarray(np.array(rows))


def fibonacci(m: int) -> FloatArray:
    """Return ``m`` quasi-uniform directions on the unit sphere (the Fibonacci spiral).

    Direction ``k`` has height ``z_k = 1 - (2k + 1) / m`` and azimuth
    ``k · π (3 - √5)`` (the golden angle); the set is deterministic.

    Parameters
    ----------
    m
        Number of directions, at least 4 (fewer cannot bound a polyhedron).

    Returns
    -------
    ndarray
        ``(m, 3)`` unit vectors.

    Raises
    ------
    ValueError
        If ``m < 4``.

    Examples
    --------
    >>> d = fibonacci(20)
    >>> d.shape, bool(np.allclose(np.linalg.norm(d, axis=1), 1.0))
    ((20, 3), True)
    """
    if isinstance(m, bool) or not isinstance(m, int | np.integer) or m < 4:
        raise ValueError(f"fibonacci directions need an integer m >= 4, got {m!r}")
    k = np.arange(int(m), dtype=np.float64)
    z = 1.0 - (2.0 * k + 1.0) / m
    rho = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = k * (math.pi * (3.0 - math.sqrt(5.0)))
    d = np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)
    return np.ascontiguousarray(d / np.linalg.norm(d, axis=1)[:, None])


def hull_depth(d: FloatArray) -> float:
    """Distance from the origin to the boundary of the convex hull of ``d`` (negative if outside).

    Parameters
    ----------
    d
        ``(m, 3)`` points that span space (at least four, not coplanar).

    Returns
    -------
    float
        The smallest distance from the origin to a facet plane of the hull,
        positive when the origin is strictly inside.

    Raises
    ------
    ValueError
        If the points are coplanar (the hull is flat).
    """
    try:
        hull = ConvexHull(d)
    except QhullError:
        raise ValueError("the directions lie in a plane and cannot bound a polyhedron") from None
    # facet planes: normal . x + offset <= 0 inside, normals of unit length
    return float(np.min(-hull.equations[:, 3]))


def check_directions(d: ArrayLike) -> FloatArray:
    """Validate a direction set and return it as a contiguous float64 ``(m, 3)`` array.

    The directions must be finite unit vectors (to :data:`UNIT_TOL`), pairwise
    distinct (farther apart than :data:`DISTINCT_TOL`) and positively spanning:
    the origin lies strictly inside their convex hull (at least
    :data:`DEPTH_MIN` inside), which is the condition for the half-spaces
    ``n_k . x <= 1`` to bound a polyhedron.

    Parameters
    ----------
    d
        Candidate directions, shape ``(m, 3)`` with ``m >= 4``.

    Returns
    -------
    ndarray
        The directions as float64, C-contiguous.

    Raises
    ------
    ValueError
        With a one-line message naming the first condition that fails.

    Examples
    --------
    >>> check_directions(cube()).shape
    (6, 3)
    >>> check_directions(cube()[:5])
    Traceback (most recent call last):
    ...
    ValueError: the directions are not positively spanning: ...
    """
    arr = np.asarray(d, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"directions must have shape (m, 3), got {arr.shape}")
    m = arr.shape[0]
    if m < 4:
        raise ValueError(f"at least 4 directions are needed to bound a polyhedron, got {m}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("the directions contain a NaN or an infinite value")
    length = np.linalg.norm(arr, axis=1)
    bad = np.flatnonzero(np.abs(length - 1.0) > UNIT_TOL)
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"direction {k} is not a unit vector (length {length[k]:.17g})")
    gap = np.linalg.norm(arr[:, None, :] - arr[None, :, :], axis=2)
    gap[np.diag_indices(m)] = np.inf
    if gap.min() <= DISTINCT_TOL:
        i, j = np.unravel_index(int(np.argmin(gap)), gap.shape)
        raise ValueError(f"directions {min(i, j)} and {max(i, j)} are not distinct")
    depth = hull_depth(arr)
    if depth < DEPTH_MIN:
        raise ValueError(
            "the directions are not positively spanning: the origin is not strictly inside "
            f"their convex hull (depth {depth:.3g}), so the half-spaces n.x <= 1 are unbounded"
        )
    return np.ascontiguousarray(arr)
