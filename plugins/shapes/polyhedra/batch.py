"""A batch of convex polyhedra in ragged (flat + offsets) form."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["PolyhedronBatch"]


@dataclass(frozen=True, eq=False)
class PolyhedronBatch:
    """Convex polyhedra of ``n`` particles, each relative to its own reference point.

    Particle ``i`` owns the vertices ``vertex_offsets[i]:vertex_offsets[i + 1]``
    and the faces ``face_offsets[i]:face_offsets[i + 1]``. Face ``f`` lies in
    the plane ``{x : normals[f] . x = support[f]}`` and lists its vertices in
    ``face_vertices[face_vertex_offsets[f]:face_vertex_offsets[f + 1]]``, as
    indices local to its particle (``0`` is the particle's first vertex),
    counter-clockwise as seen from outside. Only proper faces (at least three
    vertices, positive area) are listed; a direction of the set along which
    the polyhedron has only an edge or a vertex has a support value in
    :attr:`direction_support` but no face.

    Attributes
    ----------
    vertices
        ``(V, 3)`` vertices of all particles, relative to each particle's
        reference point, its volume centroid.
    vertex_offsets
        ``(n + 1,)`` start of each particle's vertices, then ``V``.
    normals
        ``(F, 3)`` unit outward face normals.
    support
        ``(F,)`` distance from the reference point to each face plane (positive).
    face_offsets
        ``(n + 1,)`` start of each particle's faces, then ``F``.
    face_vertices
        Vertex indices of all faces, one face after another.
    face_vertex_offsets
        ``(F + 1,)`` start of each face's vertex indices, then their total.
    face_direction
        ``(F,)`` index into :attr:`directions` of each face's normal (before
        rotation); a particle's faces are in increasing order of it.
    volume
        ``(n,)`` volume, ``(4/3) π r³`` for the equivalent radius ``r``.
    circumradius
        ``(n,)`` largest distance from the reference point to a vertex.
    inradius
        ``(n,)`` smallest support value: the radius of the largest ball
        centred at the reference point that fits inside.
    directions
        ``(m, 3)`` the direction set, in the particles' own frame.
    rotation
        ``(n, 3, 3)`` rotation of each particle: its face normals are
        ``rotation[i] @ directions[face_direction]``.
    direction_support
        ``(n, m)`` support value along every rotated direction,
        ``max_v (rotation[i] @ directions[k]) . v`` over the particle's
        vertices, also for the directions that have no proper face.
    """

    vertices: FloatArray
    vertex_offsets: IntArray
    normals: FloatArray
    support: FloatArray
    face_offsets: IntArray
    face_vertices: IntArray
    face_vertex_offsets: IntArray
    face_direction: IntArray
    volume: FloatArray
    circumradius: FloatArray
    inradius: FloatArray
    directions: FloatArray
    rotation: FloatArray
    direction_support: FloatArray

    def __len__(self) -> int:
        return int(self.vertex_offsets.shape[0] - 1)

    def vertices_of(self, i: int) -> FloatArray:
        """Vertices of particle ``i`` relative to its reference point, ``(k, 3)``."""
        return self.vertices[self.vertex_offsets[i] : self.vertex_offsets[i + 1]]

    def faces_of(self, i: int) -> list[IntArray]:
        """Faces of particle ``i`` as indices into :meth:`vertices_of`.

        One integer array per proper face, counter-clockwise as seen from outside.
        """
        fvo = self.face_vertex_offsets
        return [
            self.face_vertices[fvo[f] : fvo[f + 1]]
            for f in range(int(self.face_offsets[i]), int(self.face_offsets[i + 1]))
        ]

    def polyhedron(self, i: int) -> tuple[FloatArray, list[IntArray]]:
        """Vertices and faces of particle ``i``.

        Parameters
        ----------
        i
            Particle index, ``0 <= i < len(self)``.

        Returns
        -------
        vertices
            ``(k, 3)`` vertices relative to the particle's reference point.
        faces
            One integer array per proper face: indices into ``vertices``,
            counter-clockwise as seen from outside.
        """
        if not 0 <= i < len(self):
            raise IndexError(f"particle {i} out of range for a batch of {len(self)}")
        return self.vertices_of(i), self.faces_of(i)
