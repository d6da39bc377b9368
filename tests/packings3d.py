"""Small 3D packings for the tests of the 3D exporters, packed once per test session."""

from __future__ import annotations

import functools

import numpy as np

import regopack
from regopack.geometry.domain import Box
from regopack.packing.core import Packing

PHASES = (("plagioclase", 0.5, 1.0), ("pyroxene", 0.3, 3.0), ("glass", 0.2, 0.5))


def scene3d(side: float = 20.0, directions: str = "truncated-octahedron", seed: int = 1) -> dict:
    """A walled box of Chang'e-5 sizes and three minerals, as a user writes it."""
    return {
        "name": "box3d",
        "seed": seed,
        "count": "auto",
        "domain": {"kind": "box", "width": side, "height": side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0, "d0": 16.0, "alpha": 6.9},
        "phases": [
            {
                "name": name,
                "fraction": fraction,
                "shape": {"kind": "polyhedron", "psi": psi, "directions": directions},
            }
            for name, fraction, psi in PHASES
        ],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }


@functools.cache
def packing3d(side: float = 20.0, directions: str = "truncated-octahedron") -> Packing:
    """The packing of :func:`scene3d` (about 60 polyhedra in a 20 µm box); do not change it."""
    packing = regopack.pack(scene3d(side, directions), verify=False)
    assert packing.dimension == 3
    return packing


CUBE_LOOPS = ([0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3])
"""Faces of the cube whose vertex ``4x + 2y + z`` is ``(±1, ±1, ±1)``, outward."""


def cube_and_sphere(rounded: bool = True) -> Packing:
    """A cube of side 2 at (3, 3, 3) and a sphere of radius 1 at (7, 3, 3) in a 10 µm box."""
    import numpy as np

    from regopack.geometry.domain import Box

    cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    normals = np.array([cube[loop].mean(axis=0) for loop in CUBE_LOOPS])
    n = 2 if rounded else 1
    return Packing(
        radius=np.array([(6 / np.pi) ** (1 / 3), 1.0][:n]),
        mineral=np.arange(n),
        mineral_names=("cube", "sphere")[:n],
        vertices=np.vstack([cube, np.zeros((1, 3))][:n]),
        offsets=np.array([0, 8, 9][: n + 1]),
        face_vertices=np.concatenate(CUBE_LOOPS),
        face_vertex_offsets=np.arange(0, 25, 4),
        face_offsets=np.array([0, 6, 6][: n + 1]),
        normals=normals,
        support=np.ones(6),
        rotation=np.tile([1.0, 0, 0, 0], (n, 1)),
        centre=np.array([[3.0, 3, 3], [7, 3, 3]][:n]),
        insertion_index=np.arange(n),
        domain=Box(0, 10, 0, 10, 0, 10),
        rounding=np.array([0.0, 1.0]) if rounded else None,
    )


@functools.cache
def spheres3d(side: float = 15.0) -> Packing:
    """Spheres of the sizes of :func:`scene3d` packed in a walled box; do not change it."""
    scene = scene3d(side)
    for phase in scene["phases"]:
        phase["shape"] = {"kind": "sphere"}
    packing = regopack.pack(scene, verify=False)
    assert packing.dimension == 3
    return packing


def _cube_arrays(half: float) -> dict[str, np.ndarray]:
    """One axis-aligned cube of half-side ``half``: vertices and faces as in a solid batch."""
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * half
    # vertex index = 4 * (x > 0) + 2 * (y > 0) + (z > 0); loops counter-clockwise from outside
    loops = [
        [0, 1, 3, 2],  # x = -h
        [4, 6, 7, 5],  # x = +h
        [0, 4, 5, 1],  # y = -h
        [2, 3, 7, 6],  # y = +h
        [0, 2, 6, 4],  # z = -h
        [1, 5, 7, 3],  # z = +h
    ]
    normals = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], float)
    return {
        "vertices": v,
        "face_vertices": np.array(loops, dtype=np.int64).ravel(),
        "normals": normals,
        "support": np.full(6, half),
    }


def cube_packing(centres: list[list[float]], half: float = 0.5, **kw: object) -> Packing:
    """Cubes at ``centres`` (NaN rows: not placed) in a 10-µm box."""
    n = len(centres)
    cube = _cube_arrays(half)
    placed = ~np.isnan(np.asarray(centres, float)).any(axis=1)
    index = np.full(n, -1)
    index[placed] = np.arange(int(placed.sum()))
    args: dict[str, object] = {
        "radius": np.full(n, half * (6 / np.pi) ** (1 / 3)),
        "mineral": np.zeros(n, dtype=np.int64),
        "mineral_names": ("glass",),
        "vertices": np.tile(cube["vertices"], (n, 1)),
        "offsets": np.arange(n + 1) * 8,
        "face_vertices": np.tile(cube["face_vertices"], n),
        "face_vertex_offsets": np.arange(6 * n + 1) * 4,
        "face_offsets": np.arange(n + 1) * 6,
        "normals": np.tile(cube["normals"], (n, 1)),
        "support": np.tile(cube["support"], n),
        "rotation": np.tile([1.0, 0, 0, 0], (n, 1)),
        "centre": np.asarray(centres, float),
        "insertion_index": index,
        "domain": Box(0, 10, 0, 10, 0, 10),
    }
    args.update(kw)
    return Packing(**args)  # type: ignore[arg-type]
