"""Convex solids of a three-dimensional population: polyhedra and spheres.

A :class:`SolidBatch` is the 3D counterpart of :class:`regopack.geometry.population.ShapeBatch`:
every particle is a convex polyhedron given by its vertices and faces,
relative to its reference point (which lies strictly inside), possibly grown
by a sphere of radius ``rounding``. A sphere of radius ``r`` is the single
vertex ``(0, 0, 0)`` rounded by ``r``, with no faces.

The equivalent radius of a solid is that of the sphere of equal volume.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["SolidBatch", "concat_solids", "sphere_volume"]


def sphere_volume(radius: FloatArray | float) -> FloatArray:
    """Volume ``4/3 pi r^3`` of spheres of radius ``radius``."""
    r = np.asarray(radius, dtype=np.float64)
    out: FloatArray = (4.0 / 3.0) * np.pi * r * r * r
    return out


@dataclass(frozen=True)
class SolidBatch:
    """Convex solids of a batch of particles, in ragged (flat + offsets) form.

    Attributes
    ----------
    vertices
        ``(M, 3)`` vertices of all particles, relative to each particle's
        reference point.
    offsets
        ``(n + 1,)``: particle ``j``'s vertices are ``vertices[offsets[j]:offsets[j + 1]]``.
    face_vertices
        Vertex loops of all faces, counter-clockwise seen from outside; the
        indices are local to the particle (``0`` is its first vertex).
    face_vertex_offsets
        ``(F + 1,)``: face ``f``'s loop runs from ``face_vertices[face_vertex_offsets[f]]``
        to just before ``face_vertices[face_vertex_offsets[f + 1]]``.
    face_offsets
        ``(n + 1,)``: particle ``j``'s faces are ``face_offsets[j]`` to ``face_offsets[j + 1] - 1``.
    normals
        ``(F, 3)`` unit outward normal of every face.
    support
        ``(F,)`` plane offset of every face: face ``f`` lies in the plane
        ``normals[f] . x = support[f]``.
    rotation
        ``(n, 4)`` unit quaternion ``(w, x, y, z)`` that turned each particle from
        its generator's frame into the packing's.
    rounding
        ``(n,)`` radius of the sphere that rounds each solid, or ``None`` for
        sharp polyhedra.
    """

    vertices: FloatArray
    offsets: IntArray
    face_vertices: IntArray
    face_vertex_offsets: IntArray
    face_offsets: IntArray
    normals: FloatArray
    support: FloatArray
    rotation: FloatArray
    rounding: FloatArray | None = None

    dimension = 3
    """Spatial dimension of the solids."""

    def __post_init__(self) -> None:
        n = self.offsets.shape[0] - 1
        problems = []
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            problems.append(f"vertices of shape {self.vertices.shape}, not (M, 3)")
        if self.face_offsets.shape != (n + 1,):
            problems.append(f"face_offsets of shape {self.face_offsets.shape}, not ({n + 1},)")
        faces = int(self.face_vertex_offsets.shape[0]) - 1
        if self.normals.shape != (faces, 3) or self.support.shape != (faces,):
            problems.append(
                f"normals {self.normals.shape} and support {self.support.shape} for {faces} faces"
            )
        if self.rotation.shape != (n, 4):
            problems.append(f"rotation of shape {self.rotation.shape}, not ({n}, 4)")
        if self.rounding is not None and self.rounding.shape != (n,):
            problems.append(f"rounding of shape {self.rounding.shape}, not ({n},)")
        if problems:
            raise ValueError("inconsistent solid batch: " + "; ".join(problems))

    def __len__(self) -> int:
        return int(self.offsets.shape[0] - 1)

    @classmethod
    def of_spheres(cls, radius: ArrayLike) -> SolidBatch:
        """Spheres of radii ``radius``: each the vertex ``(0, 0, 0)`` rounded by its radius.

        Raises
        ------
        ValueError
            When ``radius`` is not one-dimensional.
        """
        r = np.array(radius, dtype=np.float64)
        if r.ndim != 1:
            raise ValueError(f"radius must be one-dimensional, not of shape {r.shape}")
        n = int(r.shape[0])
        return cls(
            vertices=np.zeros((n, 3)),
            offsets=np.arange(n + 1, dtype=np.int64),
            face_vertices=np.zeros(0, dtype=np.int64),
            face_vertex_offsets=np.zeros(1, dtype=np.int64),
            face_offsets=np.zeros(n + 1, dtype=np.int64),
            normals=np.zeros((0, 3)),
            support=np.zeros(0),
            rotation=np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (n, 1)),
            rounding=r,
        )

    def head(self, m: int) -> SolidBatch:
        """Return the solids of the first ``m`` particles (``0 <= m <= len(self)``)."""
        if not 0 <= m <= len(self):
            raise ValueError(f"m must be between 0 and {len(self)}, not {m}")
        faces = int(self.face_offsets[m])
        loops = self.face_vertex_offsets[: faces + 1]
        return SolidBatch(
            vertices=self.vertices[: int(self.offsets[m])],
            offsets=self.offsets[: m + 1],
            face_vertices=self.face_vertices[: int(loops[-1])],
            face_vertex_offsets=loops,
            face_offsets=self.face_offsets[: m + 1],
            normals=self.normals[:faces],
            support=self.support[:faces],
            rotation=self.rotation[:m],
            rounding=None if self.rounding is None else self.rounding[:m],
        )

    def take(self, indices: ArrayLike) -> SolidBatch:
        """Return the solids of particles ``indices`` (in that order, repeats allowed)."""
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        if idx.shape[0] and (idx.min() < 0 or idx.max() >= len(self)):
            raise IndexError(f"particle indices must lie in [0, {len(self)})")
        rows, offsets = _ragged_rows(self.offsets, idx)
        faces, face_offsets = _ragged_rows(self.face_offsets, idx)
        loops, loop_offsets = _ragged_rows(self.face_vertex_offsets, faces)
        return SolidBatch(
            vertices=self.vertices[rows],
            offsets=offsets,
            face_vertices=self.face_vertices[loops],
            face_vertex_offsets=loop_offsets,
            face_offsets=face_offsets,
            normals=self.normals[faces],
            support=self.support[faces],
            rotation=self.rotation[idx],
            rounding=None if self.rounding is None else self.rounding[idx],
        )

    def solid(self, j: int) -> tuple[FloatArray, list[IntArray]]:
        """Vertices of particle ``j`` and its faces as loops of local vertex indices."""
        verts = self.vertices[self.offsets[j] : self.offsets[j + 1]]
        loops = [
            self.face_vertices[self.face_vertex_offsets[f] : self.face_vertex_offsets[f + 1]]
            for f in range(int(self.face_offsets[j]), int(self.face_offsets[j + 1]))
        ]
        return verts, loops

    @property
    def rounding_radius(self) -> FloatArray:
        """Rounding radius of every particle (zeros for sharp polyhedra)."""
        if self.rounding is None:
            return np.zeros(len(self), dtype=np.float64)
        return np.asarray(self.rounding, dtype=np.float64)

    @property
    def circumradius(self) -> FloatArray:
        """Largest distance from each particle's reference point to its surface."""
        d = np.sqrt(np.einsum("ij,ij->i", self.vertices, self.vertices))
        counts = np.diff(self.offsets)
        out = np.zeros(len(self), dtype=np.float64)
        nonempty = counts > 0
        out[nonempty] = np.maximum.reduceat(d, self.offsets[:-1][nonempty])
        return out + self.rounding_radius

    @property
    def volume(self) -> FloatArray:
        """Volume of every particle, all faces at once.

        A polyhedron's is the sum of the cones from its reference point over
        its faces, ``(A_f . n_f) b_f / 3`` with the area vector
        ``A_f = 1/2 sum_k p_k x p_(k+1)`` of the face's vertex loop; a
        sphere's is ``4/3 pi r^3``. A rounded polyhedron (whose volume would
        need Steiner's formula) raises ``NotImplementedError``.
        """
        n = len(self)
        rho = self.rounding_radius
        faces = np.diff(self.face_offsets)
        if np.any((faces > 0) & (rho > 0)):
            raise NotImplementedError("the volume of a rounded polyhedron")
        out = (4.0 / 3.0) * np.pi * rho**3
        if self.normals.shape[0] == 0:
            return np.asarray(out, dtype=np.float64)
        sizes = np.diff(self.face_vertex_offsets)
        owner = np.repeat(np.repeat(np.arange(n), faces), sizes)
        v = self.vertices[self.offsets[owner] + self.face_vertices]
        nxt = np.arange(v.shape[0]) + 1
        nxt[self.face_vertex_offsets[1:] - 1] = self.face_vertex_offsets[:-1]
        area = 0.5 * np.add.reduceat(np.cross(v, v[nxt]), self.face_vertex_offsets[:-1])
        cone = np.einsum("ij,ij->i", area, self.normals) * self.support / 3.0
        face_owner = np.repeat(np.arange(n), faces)
        out = out + np.bincount(face_owner, weights=cone, minlength=n)
        return np.asarray(out, dtype=np.float64)


def _ragged_rows(offsets: IntArray, idx: IntArray) -> tuple[IntArray, IntArray]:
    """Rows of the segments ``idx`` of a ragged array (``offsets``), and their new offsets."""
    starts = offsets[idx]
    counts = offsets[idx + 1] - starts
    new = np.zeros(idx.shape[0] + 1, dtype=np.int64)
    np.cumsum(counts, out=new[1:])
    rows = np.arange(int(new[-1]), dtype=np.int64) + np.repeat(starts - new[:-1], counts)
    return rows, new


def join_solids(batches: Sequence[SolidBatch]) -> SolidBatch:
    """Return the solids of ``batches`` one after the other (rounded when any batch is)."""
    if not batches:
        return SolidBatch.of_spheres(np.zeros(0)).take(np.zeros(0, dtype=np.int64))

    def shifted(name: str) -> IntArray:
        parts = [np.zeros(1, dtype=np.int64)]
        base = 0
        for b in batches:
            off = getattr(b, name)
            parts.append(off[1:] - off[0] + base)
            base += int(off[-1] - off[0])
        return np.concatenate(parts)

    rounded = any(b.rounding is not None for b in batches)
    return SolidBatch(
        vertices=np.concatenate([b.vertices for b in batches]),
        offsets=shifted("offsets"),
        face_vertices=np.concatenate([b.face_vertices for b in batches]).astype(np.int64),
        face_vertex_offsets=shifted("face_vertex_offsets"),
        face_offsets=shifted("face_offsets"),
        normals=np.concatenate([b.normals for b in batches]),
        support=np.concatenate([b.support for b in batches]),
        rotation=np.concatenate([b.rotation for b in batches]),
        rounding=np.concatenate([b.rounding_radius for b in batches]) if rounded else None,
    )


def concat_solids(parts: list[tuple[IntArray, SolidBatch]], n: int) -> SolidBatch:
    """Interleave solid batches generated per phase back into particle order.

    Parameters
    ----------
    parts
        ``(indices, batch)`` pairs: ``batch`` holds the solids of the particles
        ``indices`` (ascending) of the population.
    n
        Total number of particles.
    """
    owner = np.full(n, -1, dtype=np.int64)
    local = np.zeros(n, dtype=np.int64)
    for b, (idx, _) in enumerate(parts):
        owner[idx] = b
        local[idx] = np.arange(len(idx))
    rounded = any(batch.rounding is not None for _, batch in parts)
    verts, loops = [], []
    vcount = np.zeros(n, dtype=np.int64)
    fcount = np.zeros(n, dtype=np.int64)
    lcount = []
    normals, support = [], []
    rotation = np.zeros((n, 4))
    rounding = np.zeros(n) if rounded else None
    for j in range(n):
        batch = parts[int(owner[j])][1]
        q = int(local[j])
        verts.append(batch.vertices[batch.offsets[q] : batch.offsets[q + 1]])
        vcount[j] = batch.offsets[q + 1] - batch.offsets[q]
        f0, f1 = int(batch.face_offsets[q]), int(batch.face_offsets[q + 1])
        fcount[j] = f1 - f0
        normals.append(batch.normals[f0:f1])
        support.append(batch.support[f0:f1])
        for f in range(f0, f1):
            a, b = int(batch.face_vertex_offsets[f]), int(batch.face_vertex_offsets[f + 1])
            loops.append(batch.face_vertices[a:b])
            lcount.append(b - a)
        rotation[j] = batch.rotation[q]
        if rounding is not None:
            rounding[j] = batch.rounding_radius[q]
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(vcount, out=offsets[1:])
    face_offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(fcount, out=face_offsets[1:])
    fvo = np.zeros(len(lcount) + 1, dtype=np.int64)
    np.cumsum(np.asarray(lcount, dtype=np.int64), out=fvo[1:])
    return SolidBatch(
        vertices=np.concatenate(verts) if verts else np.zeros((0, 3)),
        offsets=offsets,
        face_vertices=(np.concatenate(loops) if loops else np.zeros(0)).astype(np.int64),
        face_vertex_offsets=fvo,
        face_offsets=face_offsets,
        normals=np.concatenate(normals) if normals else np.zeros((0, 3)),
        support=np.concatenate(support) if support else np.zeros(0),
        rotation=rotation,
        rounding=rounding,
    )
