"""The compiled analysis of a candidate: the face-plane test that drops interferers."""

from __future__ import annotations

import numpy as np
import pytest
from surface_helpers import random_polyhedron

from regopack.plugins.inserters.available_surface.analysis import (
    SEPARATION_EPS,
    Solids,
    _separated,
    solids_of,
)


def _face_gap_in_python(
    s: Solids, a: int, ca: np.ndarray, b: int, cb: np.ndarray, q: int, margin: float
) -> bool:
    """The face-plane test of :func:`_face_gap`, written out in Python."""
    va = s.vertex_offsets
    for f in range(s.face_offsets[a], s.face_offsets[a + 1]):
        nx, ny, nz = s.normals[f]
        far = nx * ca[0] + ny * ca[1] + nz * ca[2] + s.support[f]
        near_b = np.inf
        for v in range(va[b], va[b + 1]):
            x = s.vertices[v]
            near_b = min(near_b, nx * x[0] + ny * x[1] + nz * x[2])
        gap = nx * cb[0] + ny * cb[1] + nz * cb[2] + near_b - far
        if gap <= margin:
            continue
        d = [nx * x[0] + ny * x[1] + nz * x[2] for x in s.vertices[va[q] : va[q + 1]]]
        qmin, qmax = min(d), max(d)
        if gap > (qmax - qmin) + margin + SEPARATION_EPS * (abs(far) + abs(gap) + qmax - qmin):
            return True
    return False


@pytest.mark.parametrize("margin", [0.0, 0.02])
def test_separated_is_the_face_plane_test_both_ways(margin: float) -> None:
    rng = np.random.default_rng(11)
    polys = [random_polyhedron(rng, 22, rng.uniform(0.3, 1.0)) for _ in range(6)]
    s = solids_of(polys)
    radius = [float(np.linalg.norm(p.vertices, axis=1).max()) for p in polys]
    seen = {True: 0, False: 0}
    for _ in range(400):
        k, j, i = rng.choice(len(polys), size=3)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        ck = rng.normal(size=3)
        cj = ck + u * rng.uniform(0.3, 1.2) * (radius[k] + radius[j] + 2.0 * radius[i])
        expected = _face_gap_in_python(s, k, ck, j, cj, i, margin) or _face_gap_in_python(
            s, j, cj, k, ck, i, margin
        )
        assert _separated(s, k, j, i, ck, cj, margin) == expected
        seen[expected] += 1
    assert min(seen.values()) > 40  # both answers are tried
