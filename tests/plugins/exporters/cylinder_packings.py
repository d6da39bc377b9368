"""Small packings in a walled cylinder for the tests of the 3D exporters.

Two rings of particles touch the side wall, the lower ring the floor too (the
upper one floats a little above it); one particle touches the lid. Under
gravity tilted sideways everything presses on the side wall: without it (or
with a wall of the wrong radius or centre) particles leave the cylinder.
"""

from __future__ import annotations

import numpy as np
from packings3d import _cube_arrays

from regopack.geometry.domain import Cylinder
from regopack.packing.core import Packing

CYLINDER = Cylinder(1.5, -2.0, 5.0, 0.0, 10.0)
"""Radius 5, height 10, its axis off the origin (a wall centred on the origin is wrong)."""

RING = 8
"""Particles of each ring."""


def _ring(rho: float, z: float, turn: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Centres of a ring of radius ``rho`` about the axis at height ``z``, and their angles."""
    c = CYLINDER
    t = 2.0 * np.pi * np.arange(RING) / RING + turn
    return np.column_stack([c.cx + rho * np.cos(t), c.cy + rho * np.sin(t), np.full(RING, z)]), t


def cylinder_spheres() -> Packing:
    """Unit spheres on the floor against the side wall, spheres of radius 0.8 above them
    against the side wall, one of radius 1.2 on the floor at the axis and one of radius
    0.8 under the lid (18 spheres)."""
    c = CYLINDER
    low, _ = _ring(c.radius - 1.0, 1.0)
    high, _ = _ring(c.radius - 0.8, 3.5, np.pi / RING)
    centre = np.vstack([low, high, [[c.cx, c.cy, 1.2], [c.cx + 1.0, c.cy, c.zmax - 0.8]]])
    radius = np.concatenate([np.ones(RING), np.full(RING, 0.8), [1.2, 0.8]])
    return Packing.of_spheres(centre, radius, c)  # type: ignore[return-value]


def _turned(points: np.ndarray, angle: float) -> np.ndarray:
    """``points`` turned by ``angle`` about z."""
    ca, sa = np.cos(angle), np.sin(angle)
    return points @ np.array([[ca, sa, 0.0], [-sa, ca, 0.0], [0.0, 0.0, 1.0]])


def cylinder_cubes(half: float = 0.6, turn: float = 0.0) -> Packing:
    """Cubes of half-side ``half`` facing the axis: a ring on the floor whose outer corners
    touch the side wall, a ring above it turned by half a step that touches it too, and a
    cube under the lid (17 cubes), all turned by ``turn`` about the axis.

    With ``turn = 0`` some cubes have edges parallel to x or y; LAMMPS turns them to their
    principal axes and back, and its edge-edge contact test, which divides by an edge's x
    extent unless that is exactly 0, mistakes the rounding error left there for a real
    extent (and finds contacts beyond the edge). Packings that regopack makes turn their
    grains at random; the LAMMPS tests turn these cubes too.
    """
    c = CYLINDER
    rho = np.sqrt(c.radius**2 - half**2) - half  # the outer corners on the circle
    low, t_low = _ring(rho, half, turn)
    high, t_high = _ring(rho, 3.0 * half + 0.4, np.pi / RING + turn)
    ct, st = np.cos(turn), np.sin(turn)
    top = np.array([[c.cx + 1.0 * ct, c.cy + 1.0 * st, c.zmax - half]])
    centres = np.vstack([low, high, top])
    angles = np.concatenate([t_low, t_high, [turn]])
    n = centres.shape[0]
    cube = _cube_arrays(half)
    return Packing(
        radius=np.full(n, half * (6 / np.pi) ** (1 / 3)),
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("cube",),
        vertices=np.vstack([_turned(cube["vertices"], a) for a in angles]),
        offsets=np.arange(n + 1) * 8,
        face_vertices=np.tile(cube["face_vertices"], n),
        face_vertex_offsets=np.arange(6 * n + 1) * 4,
        face_offsets=np.arange(n + 1) * 6,
        normals=np.vstack([_turned(cube["normals"], a) for a in angles]),
        support=np.tile(cube["support"], n),
        rotation=np.array([[np.cos(a / 2), 0.0, 0.0, np.sin(a / 2)] for a in angles]),
        centre=centres,
        insertion_index=np.arange(n),
        domain=c,
    )
