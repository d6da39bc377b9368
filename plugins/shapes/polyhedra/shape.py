"""The ``polyhedron`` shape: random convex polyhedra with a shape coefficient psi (3D).

The 3D counterpart of the octagon. Every particle shares a fixed set of ``m``
unit directions ``n_k`` (:mod:`~regopack.plugins.shapes.polyhedra.directions`; by
default the 14 face normals of the truncated octahedron) and draws support
distances ``s_k = b_k (1 + a σ_k |2 ξ_k - 1|^ψ)``; the polyhedron is the
intersection of the half-spaces ``n_k . x <= s_k``
(:func:`~regopack.plugins.shapes.polyhedra.generator.polyhedra_from_support`),
centred on its volume centroid, scaled to the volume ``4/3 pi r^3`` and turned
by a uniformly random rotation.

The base distances ``b_k`` are those of the regular solid of the direction
set, so that ``psi -> inf`` gives it: for the truncated octahedron the
hexagonal faces lie at ``sqrt(3) / 2`` of the square faces' distance (the
Archimedean solid, the Voronoi cell of the body-centred cubic lattice); the
cube and the rhombic dodecahedron have all faces at one distance; a
Fibonacci set (no regular solid) uses equal distances.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.geometry.solids import SolidBatch
from regopack.plugins.shapes.coefficients import Amplitude, ShapeCoefficient
from regopack.plugins.shapes.polyhedra.directions import (
    cube,
    fibonacci,
    rhombic_dodecahedron,
    truncated_octahedron,
)
from regopack.plugins.shapes.polyhedra.generator import polyhedra_from_support, raw_support
from regopack.plugins.shapes.polyhedra.rotations import quaternion_matrices
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import SolidGenerator
from regopack.registry.plugin_types import ShapeSpec

FloatArray = NDArray[np.float64]

FIBONACCI_DEFAULT = 20
"""Directions of the 'fibonacci' set when ``m`` is not given."""

DirectionSet = Literal["truncated-octahedron", "cube", "rhombic-dodecahedron", "fibonacci"]


def _truncated_octahedron_base() -> FloatArray:
    return np.concatenate([np.ones(6), np.full(8, math.sqrt(3.0) / 2.0)])


DIRECTION_SETS: dict[str, tuple[Callable[[int], FloatArray], Callable[[int], FloatArray]]] = {
    "truncated-octahedron": (
        lambda m: truncated_octahedron(),
        lambda m: _truncated_octahedron_base(),
    ),
    "cube": (lambda m: cube(), lambda m: np.ones(6)),
    "rhombic-dodecahedron": (lambda m: rhombic_dodecahedron(), lambda m: np.ones(12)),
    "fibonacci": (fibonacci, np.ones),
}
"""Direction set and base support distances (those of its regular solid), given ``m``."""


class PolyhedronConfig(BaseModel):
    """Parameters of the random convex polyhedron with shape coefficient psi."""

    model_config = ConfigDict(extra="forbid", strict=True)

    psi: ShapeCoefficient = Field(
        1.0,
        description=(
            "Shape coefficient psi (> 0): larger is more regular, psi -> inf gives the "
            "regular solid of the direction set."
        ),
    )
    a: Amplitude = Field(
        1.0 / 3.0,
        description=(
            "Perturbation amplitude a in (0, 1]: support distances lie within ±a of the "
            "regular solid's, relatively."
        ),
    )
    directions: DirectionSet = Field(
        "truncated-octahedron",
        description=(
            "Face directions: 'truncated-octahedron' (14, the default), 'cube' (6), "
            "'rhombic-dodecahedron' (12) or 'fibonacci' (m quasi-uniform directions)."
        ),
    )
    m: int | None = Field(
        None,
        ge=4,
        le=64,
        description=(
            "Number of directions of the 'fibonacci' set (4 to 64; default 20); only with that set."
        ),
    )

    @model_validator(mode="after")
    def _m_only_for_fibonacci(self) -> PolyhedronConfig:
        if self.m is not None and self.directions != "fibonacci":
            raise ValueError(f"m applies only to directions = 'fibonacci', not {self.directions!r}")
        return self


class RandomPolyhedron(SolidGenerator):
    """Random convex polyhedra of volume ``4/3 pi r^3`` (see the module docstring).

    The random numbers of a batch of ``n`` particles come from ``rng`` in this
    order, each as one call: the signs ``rng.integers(0, 2, (n, m))``, the
    ``ξ`` ``rng.random((n, m))``, the rotations ``rng.standard_normal((n, 4))``
    (normalised quaternions, uniform on the rotations).

    Examples
    --------
    >>> import numpy as np
    >>> batch = RandomPolyhedron().generate(np.array([1.0, 2.0]), np.random.default_rng(0))
    >>> len(batch), bool(np.allclose(batch.volume, 4 / 3 * np.pi * np.array([1.0, 8.0])))
    (2, True)
    """

    def __init__(self, config: PolyhedronConfig | None = None) -> None:
        self.config = config or PolyhedronConfig()
        make, base = DIRECTION_SETS[self.config.directions]
        self.directions = make(FIBONACCI_DEFAULT if self.config.m is None else self.config.m)
        self.base = np.asarray(base(self.directions.shape[0]), dtype=np.float64)

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> SolidBatch:
        """One random polyhedron per radius."""
        r = np.asarray(radius, dtype=np.float64)
        if r.ndim != 1:
            raise ValueError(f"radius must be one-dimensional, not of shape {r.shape}")
        n, m = int(r.shape[0]), int(self.directions.shape[0])
        sign = (2 * rng.integers(0, 2, size=(n, m)) - 1).astype(np.float64)
        xi = rng.random((n, m))
        q = rng.standard_normal((n, 4))
        q[np.all(q == 0.0, axis=1), 0] = 1.0  # probability zero; the identity
        if n == 0:
            return _empty()
        support = self.base * raw_support(sign, xi, self.config.psi, self.config.a)
        batch = polyhedra_from_support(support, r, self.directions, quaternion_matrices(q))
        q = q / np.linalg.norm(q, axis=1)[:, None]
        return SolidBatch(
            vertices=batch.vertices,
            offsets=batch.vertex_offsets,
            face_vertices=batch.face_vertices,
            face_vertex_offsets=batch.face_vertex_offsets,
            face_offsets=batch.face_offsets,
            normals=batch.normals,
            support=batch.support,
            rotation=q,
        )


def _empty() -> SolidBatch:
    return SolidBatch(
        vertices=np.zeros((0, 3)),
        offsets=np.zeros(1, dtype=np.int64),
        face_vertices=np.zeros(0, dtype=np.int64),
        face_vertex_offsets=np.zeros(1, dtype=np.int64),
        face_offsets=np.zeros(1, dtype=np.int64),
        normals=np.zeros((0, 3)),
        support=np.zeros(0),
        rotation=np.zeros((0, 4)),
    )


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``polyhedron`` shape."""
    return [
        ShapeSpec(
            name="polyhedron",
            config_model=PolyhedronConfig,
            factory=RandomPolyhedron,
            description="Random convex polyhedron with shape coefficient psi (3D octagon).",
            dimension=3,
        )
    ]
