"""Hand-made 3D packings with known contacts: lattices of axis-aligned cubes."""

from __future__ import annotations

import numpy as np

from regopack.geometry.domain import Box
from regopack.packing.core import Packing

_CUBE_VERTICES = np.array(
    [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], dtype=float
)
# faces -x, +x, -y, +y, -z, +z, counter-clockwise seen from outside (vertex index = 4x + 2y + z)
_CUBE_FACES = np.array(
    [0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3], dtype=np.int64
)
_CUBE_NORMALS = np.array(
    [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)], dtype=float
)


def cube_lattice(
    shape: tuple[int, int, int],
    gaps: tuple[float, float, float],
    side: float = 1.0,
    minerals: int = 1,
) -> Packing:
    """Axis-aligned cubes of ``side`` on a lattice with the given gaps along x, y and z.

    The box holds the lattice with a gap of 0.5 to every wall; particle
    ``k`` has the mineral ``k % minerals``.
    """
    nx, ny, nz = shape
    n = nx * ny * nz
    step = side + np.asarray(gaps, dtype=float)
    idx = np.array([(a, b, c) for a in range(nx) for b in range(ny) for c in range(nz)], float)
    centre = 0.5 + 0.5 * side + idx * step
    hi = centre.max(axis=0) + 0.5 * side + 0.5
    names = ("pyroxene", "glass", "olivine")[:minerals]
    return Packing(
        radius=np.full(n, side * (6 / np.pi) ** (1 / 3) / 2),
        mineral=np.arange(n, dtype=np.int64) % minerals,
        mineral_names=names,
        vertices=np.tile(_CUBE_VERTICES * side, (n, 1)),
        offsets=np.arange(n + 1, dtype=np.int64) * 8,
        face_vertices=np.tile(_CUBE_FACES, n),
        face_vertex_offsets=np.arange(6 * n + 1, dtype=np.int64) * 4,
        face_offsets=np.arange(n + 1, dtype=np.int64) * 6,
        normals=np.tile(_CUBE_NORMALS, (n, 1)),
        support=np.full(6 * n, 0.5 * side),
        rotation=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
        centre=centre,
        insertion_index=np.arange(n, dtype=np.int64),
        domain=Box(0.0, float(hi[0]), 0.0, float(hi[1]), 0.0, float(hi[2])),
    )


def sphere_lattice(shape: tuple[int, int, int], radius: float, gap: float) -> Packing:
    """Spheres of ``radius`` on a simple cubic lattice, ``gap`` apart, 0.5 from every wall."""
    nx, ny, nz = shape
    n = nx * ny * nz
    step = 2.0 * radius + gap
    idx = np.array([(a, b, c) for a in range(nx) for b in range(ny) for c in range(nz)], float)
    centre = 0.5 + radius + idx * step
    hi = centre.max(axis=0) + radius + 0.5
    box = Box(0.0, float(hi[0]), 0.0, float(hi[1]), 0.0, float(hi[2]))
    return Packing.of_spheres(centre, np.full(n, radius), box, mineral_names=("glass",))
