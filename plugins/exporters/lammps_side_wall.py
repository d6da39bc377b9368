"""The side wall of a walled cylinder as LAMMPS bodies: a ring of fixed rounded plates.

LAMMPS' wall for bodies (``fix wall/body/polyhedron``) knows planes only, so the
``lammps`` exporter walls a cylinder's floor and lid with ``zplane`` and builds
its side wall from bodies of their own: thin rounded boxes (``body
rounded/polyhedron``) of an atom type of their own that no fix integrates, so
they never move and the grains meet them through the body pair style.

- **Around.** ``N`` plates per ring; the inner face of each plate's core lies
  on a plane at ``R + r`` from the axis (``R`` the cylinder's radius, ``r`` the
  plates' rounding radius), so the rounded surface touches the circle at the
  plate's middle: the plates *circumscribe* the cylinder, and a grain inside
  the cylinder overlaps no plate. Between two plates the rounded corner stands
  ``(R + r) (1 / cos(π / N) - 1)`` outside the circle; ``N`` is the least count
  that keeps this at most :data:`CORNER_GAP` × the smallest grain's equivalent
  diameter ``d_min`` (at least :data:`MIN_SEGMENTS`, and enough that no plate
  is wider than the largest grain's equivalent diameter ``d_max``).
- **Up.** The plates are stacked in ``M = ceil((H + 2 e) / d_max)`` layers
  from :data:`OVERHANG` × ``d_min`` (``e``) below the floor to ``e`` above the
  lid, so that each plate is about as large as the largest grain: LAMMPS sets
  the neighbour cutoff of a pair of types from their largest bodies, and one
  plate the height of the cylinder would make it (and every neighbour list)
  huge. The overhang keeps the plates' ends, rounded edges and horizontal
  edges away from the grains that rest on the floor or touch the lid: there
  they meet the flat inner faces only.
- **Thickness.** Each core is :data:`THICKNESS` × ``d_max`` thick (outward):
  LAMMPS tests contacts against faces whose body's centre lies on the other
  side, which a plate of zero thickness would not have.

Plates have the mass of a box of the grains' density, and an isotropic inertia
(the mean of the box's principal moments): they are not integrated, so neither
enters an equation of motion, and with a diagonal tensor LAMMPS keeps their
vertices in the box frame bit for bit. (With the true, rotated tensor LAMMPS
turns the vertices to principal axes and back, and an edge that is vertical or
horizontal in the box comes back tilted by a rounding error; LAMMPS' edge-edge
test then divides by that error and finds contacts far outside the edge.) For
the same reason the rotations of the plates facing along x or y are exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import Cylinder
from regopack.plugins.exporters.rounded_polyhedra import Core, erode_polyhedron

__all__ = ["CORNER_GAP", "MIN_SEGMENTS", "THICKNESS", "SideWall", "side_wall"]

FloatArray = NDArray[np.float64]

CORNER_GAP = 0.01
"""Farthest a corner between two plates of the side wall stands outside the cylinder, as a
fraction of the smallest grain's equivalent diameter (sets the number of plates around)."""

MIN_SEGMENTS = 16
"""Fewest plates around the side wall."""

THICKNESS = 0.25
"""Thickness of a plate's core, as a fraction of the largest grain's equivalent diameter."""

OVERHANG = 0.25
"""How far the plates reach below the floor and above the lid, as a fraction of the smallest
grain's equivalent diameter (their rounding and LAMMPS' contact range are 0.075 of it by
default)."""


@dataclass(frozen=True)
class SideWall:
    """The plates of a cylinder's side wall, in the packing's length unit.

    Attributes
    ----------
    segments, layers
        Plates around (``N``) and up (``M``); plate ``k`` is in layer
        ``k // N`` and faces the axis at the angle ``2π (k % N) / N``.
    rounding
        Rounding radius ``r`` of every plate.
    distance
        Distance from the axis of the plane of every core's inner face
        (``R + r``): the rounded surface touches the circle.
    core
        The core of the plate at angle 0, its vertices relative to its centre.
    centre
        ``(N M, 3)`` centre (of mass) of each plate.
    rotation
        ``(N, 3, 3)`` turn about z from the plate at angle 0 to each plate of a layer.
    volume
        Volume of one plate's core.
    moment
        Moment of inertia written for every plate per unit density (about
        any axis: the mean principal moment of the core).
    overhang
        How far the cores reach below the floor and above the lid.
    """

    segments: int
    layers: int
    rounding: float
    distance: float
    core: Core
    centre: FloatArray
    rotation: FloatArray
    volume: float
    moment: float
    overhang: float

    @property
    def count(self) -> int:
        """Number of plates."""
        return self.segments * self.layers

    @property
    def corner_gap(self) -> float:
        """How far the corners between plates stand outside the cylinder."""
        return self.distance * (1.0 / math.cos(math.pi / self.segments) - 1.0)

    def vertices(self, k: int) -> FloatArray:
        """Core vertices of plate ``k`` relative to its centre, in the box frame."""
        out: FloatArray = self.core.vertices @ self.rotation[k % self.segments].T
        return out

    @property
    def reach(self) -> float:
        """Farthest distance from the axis of any point of a rounded plate."""
        v = self.core.vertices
        return float(np.hypot(v[:, 0] + self.centre_distance, v[:, 1]).max()) + self.rounding

    @property
    def centre_distance(self) -> float:
        """Distance of every plate's centre from the axis."""
        return self.distance + 0.5 * self.thickness

    @property
    def thickness(self) -> float:
        """Thickness of a plate's core."""
        return float(np.ptp(self.core.vertices[:, 0]))


def segment_count(distance: float, gap: float, width: float) -> int:
    """Least number of plates around whose corners stand at most ``gap`` outside the circle.

    Parameters
    ----------
    distance
        Distance of the plates' inner planes from the axis.
    gap
        Largest distance of a corner outside the circle of radius ``distance``.
    width
        Widest a plate may be.

    Examples
    --------
    >>> segment_count(5.0, 0.015, 1.5)
    41
    """
    for_gap = math.ceil(math.pi / math.acos(distance / (distance + gap)))
    for_width = math.ceil(math.pi / math.atan(0.5 * width / distance))
    return max(MIN_SEGMENTS, for_gap, for_width)


def side_wall(domain: Cylinder, rounding: float, d_min: float, d_max: float) -> SideWall:
    """Lay out the plates of the side wall of ``domain`` (see the module documentation).

    Parameters
    ----------
    domain
        The walled cylinder.
    rounding
        Rounding radius of the plates.
    d_min, d_max
        Smallest and largest equivalent diameters of the grains.

    Examples
    --------
    >>> wall = side_wall(Cylinder(0.0, 0.0, 5.0, 0.0, 10.0), 0.04, 1.5, 1.5)
    >>> wall.segments, wall.layers, wall.count, round(wall.corner_gap / 1.5, 4)
    (41, 8, 328, 0.0099)
    """
    distance = domain.radius + rounding
    segments = segment_count(distance, CORNER_GAP * d_min, d_max)
    overhang = OVERHANG * d_min
    layers = max(1, math.ceil((domain.height + 2.0 * overhang) / d_max))
    half_width = distance * math.tan(math.pi / segments)
    half_height = 0.5 * (domain.height + 2.0 * overhang) / layers
    half_thick = 0.5 * THICKNESS * d_max
    normals = np.vstack([np.eye(3), -np.eye(3)])
    halves = np.array([half_thick, half_width, half_height])
    core = erode_polyhedron(normals, np.concatenate([halves, halves]), 0.0)
    assert core is not None  # a box of positive extents
    t = 2.0 * np.pi * np.arange(segments) / segments
    ct, st = np.cos(t), np.sin(t)
    ct[np.abs(ct) < 1e-12] = 0.0  # exact for the plates that face along x or y
    st[np.abs(st) < 1e-12] = 0.0
    rotation = np.zeros((segments, 3, 3))
    rotation[:, 0, 0], rotation[:, 0, 1], rotation[:, 1, 0], rotation[:, 1, 1] = ct, -st, st, ct
    rotation[:, 2, 2] = 1.0
    rho = distance + half_thick
    z = domain.zmin - overhang + (2.0 * np.arange(layers) + 1.0) * half_height
    centre = np.column_stack(
        [
            np.tile(domain.cx + rho * ct, layers),
            np.tile(domain.cy + rho * st, layers),
            np.repeat(z, segments),
        ]
    )
    volume = float(8.0 * np.prod(halves))
    squares = halves**2
    moment = float(np.mean(volume / 3.0 * (squares.sum() - squares)))
    return SideWall(
        segments=segments,
        layers=layers,
        rounding=rounding,
        distance=distance,
        core=core,
        centre=centre,
        rotation=rotation,
        volume=volume,
        moment=moment,
        overhang=overhang,
    )
