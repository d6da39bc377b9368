"""The envelope ``P ⊕ (-Q)`` as half-spaces only: what an interferer needs.

The free-surface kernel reads an interferer's envelope only as the
intersection of half-spaces ``n · x <= h``. Those planes are the candidate
directions of :func:`envelope.minkowski_envelope` (the faces of ``P``, the
faces of ``-Q`` and the directions where an edge arc of one Gauss map crosses
one of the other) with the support values ``h_P(n) + h_Q(-n)``, without the
face polygons. A candidate that is not a facet (a crossing at an arc's end,
or a face of ``P`` parallel to one of ``-Q``) is a supporting plane of the
envelope: it touches it and cuts nothing, so the intersection is the
envelope exactly.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.inserters.available_surface.envelope import (
    EdgeArcs,
    candidate_directions,
    edge_arcs,
)
from regopack.plugins.inserters.available_surface.polyhedron import Polyhedron

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@numba.njit(cache=True)
def minkowski_halfspaces(p: Polyhedron, q: Polyhedron) -> tuple[FloatArray, FloatArray]:
    """Half-spaces ``(normals, support)`` whose intersection is ``P ⊕ (-Q)``.

    Relative to ``P``'s reference point, as :func:`envelope.minkowski_envelope`.
    """
    return halfspaces_of_arcs(p, edge_arcs(p, 1.0), q, edge_arcs(q, -1.0))


@numba.njit(cache=True)
def halfspaces_of_arcs(
    p: Polyhedron, ep: EdgeArcs, q: Polyhedron, eq: EdgeArcs
) -> tuple[FloatArray, FloatArray]:
    """:func:`minkowski_halfspaces` from the edge arcs of ``P`` and of ``-Q``."""
    vp = p.vertices
    vq = q.vertices
    cand, _, _, _, nc = candidate_directions(p, ep, q, eq)
    normals = cand[:nc].copy()
    support = np.empty(nc)
    for c in range(nc):
        nx = normals[c, 0]
        ny = normals[c, 1]
        nz = normals[c, 2]
        support[c] = _largest_dot(nx, ny, nz, vp, 1.0) + _largest_dot(nx, ny, nz, vq, -1.0)
    return normals, support


@numba.njit(cache=True, inline="always")
def _largest_dot(nx: float, ny: float, nz: float, v: FloatArray, sign: float) -> float:
    """Return the largest ``sign * (n · v_i)`` over the rows of ``v``.

    Four running maxima over every fourth row, merged at the end: the same
    products and the same maximum as one running maximum (the order of a
    maximum does not change it), without one long chain of dependent
    comparisons.
    """
    k = v.shape[0]
    h0 = -np.inf
    h1 = -np.inf
    h2 = -np.inf
    h3 = -np.inf
    i = 0
    while i + 4 <= k:
        d0 = sign * (nx * v[i, 0] + ny * v[i, 1] + nz * v[i, 2])
        d1 = sign * (nx * v[i + 1, 0] + ny * v[i + 1, 1] + nz * v[i + 1, 2])
        d2 = sign * (nx * v[i + 2, 0] + ny * v[i + 2, 1] + nz * v[i + 2, 2])
        d3 = sign * (nx * v[i + 3, 0] + ny * v[i + 3, 1] + nz * v[i + 3, 2])
        h0 = d0 if d0 > h0 else h0
        h1 = d1 if d1 > h1 else h1
        h2 = d2 if d2 > h2 else h2
        h3 = d3 if d3 > h3 else h3
        i += 4
    while i < k:
        d0 = sign * (nx * v[i, 0] + ny * v[i, 1] + nz * v[i, 2])
        h0 = d0 if d0 > h0 else h0
        i += 1
    h0 = h1 if h1 > h0 else h0
    h2 = h3 if h3 > h2 else h2
    return h2 if h2 > h0 else h0
