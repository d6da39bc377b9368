"""What the 3D exporters share: the placed solids, their triangles, volumes and inertia.

Every solid of a 3D :class:`~regopack.packing.core.Packing` is a convex
polyhedron whose faces are planar loops, counter-clockwise seen from outside,
around a reference point strictly inside. :func:`fan_triangles` splits each
loop into a fan of triangles from its first vertex (which keeps their
orientation), and :func:`mass_properties` sums the tetrahedra that those
triangles span with the reference point: the exact volume, centroid and
second moments of the polyhedron.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ExportError
from regopack.geometry.domain import Box
from regopack.packing.core import Packing, _atomic_file

__all__ = [
    "PlacedSolid",
    "fan_triangles",
    "mass_properties",
    "placed_solids",
    "write_bytes",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SPHERE_EXPORTERS = " (gsd, image, lammps, liggghts and yade write spheres)"
"""What a refusal of spheres adds: the built-in exporters that write them."""

_CANONICAL = (np.ones((3, 3)) + np.eye(3)) / 120.0
"""``∫ x xᵀ dV`` over the tetrahedron with vertices 0, e1, e2, e3 (its volume is 1/6)."""


@dataclass(frozen=True)
class PlacedSolid:
    """One placed polyhedron of a packing.

    Attributes
    ----------
    index
        Draw index of the particle (row of the packing's arrays).
    local
        ``(k, 3)`` vertices relative to the particle's reference point (its centre).
    loops
        Faces as loops of indices into ``local``, counter-clockwise seen from outside.
    centre
        Position of the reference point in the packing.
    rounding
        Radius of a sphere (its one vertex is its centre, it has no faces);
        0 for a polyhedron.
    """

    index: int
    local: FloatArray
    loops: list[IntArray]
    centre: FloatArray
    rounding: float = 0.0

    @property
    def world(self) -> FloatArray:
        """Vertices in the packing's frame."""
        out: FloatArray = self.local + self.centre
        return out


def placed_solids(packing: Packing[Box], exporter: str, spheres: bool = False) -> list[PlacedSolid]:
    """Return the placed polyhedra (and, with ``spheres``, spheres) in draw order.

    Raises
    ------
    ExportError
        One line, when some placed particle is a sphere (or another rounded
        solid) that the exporter ``exporter`` does not write.
    """
    solids = packing.solids
    rho = solids.rounding_radius
    out = []
    for j in np.flatnonzero(packing.placed).tolist():
        local, loops = solids.solid(j)
        if rho[j] > 0 and not (spheres and not loops):
            what = "a rounded polyhedron" if loops else "a sphere"
            allowed = "sharp polyhedra and spheres" if spheres else "sharp polyhedra"
            raise ExportError(
                f"particle {j}: {what}; the {exporter} export writes {allowed} only"
                + ("" if spheres or loops else SPHERE_EXPORTERS)
            )
        out.append(PlacedSolid(int(j), local, loops, packing.centre[j], float(rho[j])))
    return out


def fan_triangles(loops: list[IntArray]) -> IntArray:
    """``(t, 3)`` vertex indices of the fans that split each loop from its first vertex.

    A loop of ``m`` vertices gives ``m - 2`` triangles, in the loop's turning
    sense, so outward loops give outward triangles.

    Examples
    --------
    >>> fan_triangles([np.array([0, 1, 2, 3]), np.array([3, 2, 4])]).tolist()
    [[0, 1, 2], [0, 2, 3], [3, 2, 4]]
    """
    rows = [
        np.column_stack([np.full(len(loop) - 2, loop[0]), loop[1:-1], loop[2:]]) for loop in loops
    ]
    if not rows:
        return np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(rows).astype(np.int64)


def mass_properties(
    local: FloatArray, loops: list[IntArray]
) -> tuple[float, FloatArray, FloatArray]:
    """Volume, centroid and second-moment tensor of a polyhedron of unit density.

    Parameters
    ----------
    local
        ``(k, 3)`` vertices, relative to a point inside the polyhedron.
    loops
        Outward faces as loops of indices into ``local``.

    Returns
    -------
    volume, centroid, moments
        ``moments = ∫ (x - c)(x - c)ᵀ dV`` about the centroid ``c``; the
        inertia tensor is ``trace(moments) I - moments``.

    Examples
    --------
    >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    >>> faces = [np.array(f) for f in ([0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1],
    ...                                 [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3])]
    >>> v, c, m = mass_properties(cube, faces)
    >>> round(v, 12), c.round(12).tolist(), np.diag(m).round(3).tolist()
    (8.0, [0.0, 0.0, 0.0], [2.667, 2.667, 2.667])
    """
    tri = local[fan_triangles(loops)]  # (t, 3 vertices, 3 coordinates)
    det = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    volume = float(det.sum() / 6.0)
    centroid: FloatArray = (det[:, None] * tri.sum(axis=1)).sum(axis=0) / (24.0 * volume)
    # ∫ x xᵀ over the tetrahedron (0, a, b, c) = det · A C Aᵀ with A = [a b c]
    a = tri.transpose(0, 2, 1)  # columns a, b, c
    second = np.einsum("t,tik,kl,tjl->ij", det, a, _CANONICAL, a)
    moments: FloatArray = second - volume * np.outer(centroid, centroid)
    return volume, centroid, moments


def write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (a temporary file beside it, renamed)."""
    try:
        with _atomic_file(path) as fh:
            fh.write(data)
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err
