"""Rigid motions of a packing's particles: the packing as a simulation left it.

A DEM code moves and turns the particles it was given; :func:`moved` applies
such motions to a :class:`~regopack.packing.core.Packing` of either
dimension and returns the moved packing, which every analysis reads as it reads the packing itself
(contacts, φ, Z, the fabric, g(r)), so that a sample can be compared before
and after settling.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import PackingError
from regopack.packing.core import Packing

__all__ = ["moved", "quaternion_of"]

FloatArray = NDArray[np.float64]


def quaternion_of(turn: FloatArray) -> FloatArray:
    """Return the unit quaternions ``(w, x, y, z)`` of rotation matrices ``turn`` (``(k, 3, 3)``).

    Examples
    --------
    >>> quarter = np.array([[[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]])  # 90° about z
    >>> quaternion_of(quarter).round(6).tolist()
    [[0.707107, 0.0, 0.0, 0.707107]]
    """
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(turn).as_quat()
    out: FloatArray = np.ascontiguousarray(xyzw[:, [3, 0, 1, 2]])
    return out


def moved(
    packing: Packing[Any],
    index: NDArray[np.int64],
    shift: FloatArray,
    turn: FloatArray | None = None,
    pivot: FloatArray | None = None,
    stats: dict[str, float] | None = None,
) -> Packing[Any]:
    """Return ``packing`` with particles ``index`` moved by ``shift`` and turned by ``turn``.

    Parameters
    ----------
    packing
        A packing of dimension ``d`` (2 or 3).
    index
        Draw indices of the particles that move (placed particles, each once).
    shift
        ``(k, d)`` displacement of each one's pivot, in the packing's lengths.
    turn
        ``(k, d, d)`` rotation matrices, each about its particle's pivot; none:
        the particles keep their orientation.
    pivot
        ``(k, d)`` point of each particle, relative to its reference point
        (``centre``), that moves by ``shift`` and about which it turns (its
        centroid, as DEM codes turn bodies); none: the reference point.
    stats
        Entries added to the packing's ``stats`` (e.g. the run's steps).

    Returns
    -------
    Packing
        The same particles, draw order, minerals and domain; the centres of
        the moved particles in a periodic box are wrapped into it. The
        vertices, face normals and supports of each turned polyhedron are
        turned, and its ``rotation`` composed with the turn; in 2D the
        outline is turned and the turn's angle added to ``orientation``
        (modulo 2π, in ``[0, 2π)`` as the shapes draw it).

    Raises
    ------
    PackingError
        One line, when an index is no placed particle or is given twice, or
        an array has the wrong shape or a number that is not finite, or a
        turn is not a rotation.

    Examples
    --------
    >>> from regopack.geometry.domain import Box
    >>> p = Packing.of_spheres([[1.0, 1, 1], [3, 1, 1]], [1.0, 1.0], Box(0, 4, 0, 2, 0, 2))
    >>> moved(p, np.array([1]), np.array([[0.0, 0, -0.5]])).centre.tolist()
    [[1.0, 1.0, 1.0], [3.0, 1.0, 0.5]]
    """
    dim = packing.dimension
    index = np.asarray(index, dtype=np.int64)
    k = index.size
    shift = np.asarray(shift, dtype=np.float64)
    checks: list[tuple[str, FloatArray, tuple[int, ...]]] = [("shift", shift, (k, dim))]
    if turn is not None:
        turn = np.asarray(turn, dtype=np.float64)
        checks.append(("turn", turn, (k, dim, dim)))
    if pivot is not None:
        pivot = np.asarray(pivot, dtype=np.float64)
        checks.append(("pivot", pivot, (k, dim)))
    for name, array, shape in checks:
        if array.shape != shape:
            raise PackingError(f"moved: {name} has shape {array.shape}, expected {shape}")
        if not np.isfinite(array).all():
            raise PackingError(f"moved: {name} has a number that is not finite")
    extent = float(np.ptp(packing.domain.bounds().reshape(dim, 2), axis=1).max())
    if k and np.abs(shift).max() > 1e12 * extent:
        raise PackingError(
            f"moved: a shift of {np.abs(shift).max():.3g} is beyond 1e12 times the domain's "
            f"size ({extent:.3g})"
        )
    placed = packing.placed
    if k and (index.min() < 0 or index.max() >= placed.size or not placed[index].all()):
        raise PackingError("moved: an index is not a placed particle")
    if np.unique(index).size != k:
        raise PackingError("moved: a particle is given twice")
    if turn is not None:
        error = np.abs(np.einsum("kij,kil->kjl", turn, turn) - np.eye(dim)).max(initial=0.0)
        if error > 1e-6 or (k and np.linalg.det(turn).min() <= 0):
            raise PackingError("moved: a turn is not a rotation matrix")
    g = np.zeros((k, dim)) if pivot is None else pivot
    centre = packing.centre.copy()
    centre[index] += shift
    if turn is not None:
        # the reference point moves with the particle, so it stays inside it: turned
        # about the pivot it lands at g - R g from where the pivot's shift takes it,
        # and the outline turns about the reference point
        centre[index] += g - np.einsum("kij,kj->ki", turn, g)
    box = packing.domain
    if box.periodic:
        lo, hi = box.bounds().reshape(dim, 2).T
        centre[index] = lo + np.mod(centre[index] - lo, hi - lo)
    changes: dict[str, Any] = {
        "centre": centre,
        "stats": {**packing.stats, **(stats or {})},
    }
    if turn is not None:
        changes.update(
            _turned(packing, index, turn) if dim == 3 else _turned2(packing, index, turn)
        )
    return dataclasses.replace(packing, **changes)


def _turned2(
    packing: Packing[Any], index: NDArray[np.int64], turn: FloatArray
) -> dict[str, FloatArray]:
    """Outlines and orientations of the 2D packing with ``index`` turned about their centres."""
    vertices = _rows_turned(packing.vertices, packing.offsets, index, turn)
    orientation = packing.orientation.copy()
    if orientation.size:
        angle = np.arctan2(turn[:, 1, 0], turn[:, 0, 0])
        # the shapes draw their orientations in [0, 2 pi): a turned one stays there
        turned = np.mod(orientation[index] + angle, 2.0 * np.pi)
        orientation[index] = np.where(turned >= 2.0 * np.pi, 0.0, turned)  # mod's rounding
    return {"vertices": vertices, "orientation": orientation}


def _turned(
    packing: Packing[Any], index: NDArray[np.int64], turn: FloatArray
) -> dict[str, FloatArray]:
    """Vertices, normals and rotations of the packing with ``index`` turned about their centres.

    A face plane ``n · x = s`` through the reference point's frame keeps its
    offset ``s`` when the solid turns about that point.
    """
    vertices = _rows_turned(packing.vertices, packing.offsets, index, turn)
    normals = packing.normals
    if packing.face_offsets.size:
        normals = _rows_turned(normals, packing.face_offsets, index, turn)
    rotation = packing.rotation.copy()
    if rotation.shape[0]:
        q = quaternion_of(turn)
        rotation[index] = _compose(q, rotation[index])
    return {"vertices": vertices, "normals": normals, "rotation": rotation}


def _rows_turned(
    values: FloatArray, offsets: NDArray[np.int64], index: NDArray[np.int64], turn: FloatArray
) -> FloatArray:
    """Return ``values`` with particle ``index[m]``'s rows turned by ``turn[m]``, vectorised.

    Particle ``j`` owns rows ``offsets[j]`` to ``offsets[j + 1] - 1``; each row
    ``v`` becomes ``turn[m] @ v``, its terms summed in axis order.
    """
    out = values.copy()
    counts = offsets[index + 1] - offsets[index]
    if not counts.sum():
        return out
    starts = np.repeat(offsets[index] - np.cumsum(counts) + counts, counts)
    rows = starts + np.arange(int(counts.sum()))
    r = np.repeat(turn, counts, axis=0)
    v = values[rows]
    turned = r[:, :, 0] * v[:, 0:1]
    for a in range(1, v.shape[1]):
        turned = turned + r[:, :, a] * v[:, a : a + 1]
    out[rows] = turned
    return out


def _compose(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton products ``a b`` of unit quaternions ``(w, x, y, z)``, row by row."""
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    out: FloatArray = np.column_stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )
    return out
