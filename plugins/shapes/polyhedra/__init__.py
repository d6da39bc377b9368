"""Random convex polyhedra with a shape coefficient psi: the geometry for 3D packings.

- :mod:`~regopack.plugins.shapes.polyhedra.directions`: fixed unit direction sets
  (the truncated octahedron's 14 by default) and their validation;
- :mod:`~regopack.plugins.shapes.polyhedra.generator`: :func:`random_polyhedra`;
- :mod:`~regopack.plugins.shapes.polyhedra.batch`: :class:`PolyhedronBatch`;
- :mod:`~regopack.plugins.shapes.polyhedra.rotations`: uniform random rotations;
- :mod:`~regopack.plugins.shapes.polyhedra.kernel`: the compiled vertex enumeration;
- :mod:`~regopack.plugins.shapes.polyhedra.shape`: the ``polyhedron`` shape plugin.
"""

from __future__ import annotations

from regopack.plugins.shapes.polyhedra.batch import PolyhedronBatch
from regopack.plugins.shapes.polyhedra.directions import (
    check_directions,
    cube,
    fibonacci,
    rhombic_dodecahedron,
    truncated_octahedron,
)
from regopack.plugins.shapes.polyhedra.generator import polyhedra_from_support, random_polyhedra
from regopack.plugins.shapes.polyhedra.rotations import random_rotations

__all__ = [
    "PolyhedronBatch",
    "check_directions",
    "cube",
    "fibonacci",
    "polyhedra_from_support",
    "random_polyhedra",
    "random_rotations",
    "rhombic_dodecahedron",
    "truncated_octahedron",
]
