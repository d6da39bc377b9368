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
    kp = vp.shape[0]
    kq = vq.shape[0]
    cand, _, _, _, nc = candidate_directions(p, ep, q, eq)
    normals = cand[:nc].copy()
    support = np.empty(nc)
    for c in range(nc):
        hp = -np.inf
        for i in range(kp):
            v = normals[c, 0] * vp[i, 0] + normals[c, 1] * vp[i, 1] + normals[c, 2] * vp[i, 2]
            if v > hp:
                hp = v
        hq = -np.inf
        for j in range(kq):
            v = -(normals[c, 0] * vq[j, 0] + normals[c, 1] * vq[j, 1] + normals[c, 2] * vq[j, 2])
            if v > hq:
                hq = v
        support[c] = hp + hq
    return normals, support
