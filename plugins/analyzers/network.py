"""The contact network: edges weighted by contact area, and the fabric of contact normals.

The anisotropy of the fabric comes with its sampling error, a jackknife over
spatial blocks (:func:`block_jackknife`): deterministic, and honest about the
correlation of neighbouring contacts, which share particles.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import Measured, interior_window
from regopack.plugins.analyzers.contacts import Contacts
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]


DEFAULT_BLOCKS = {2: 4, 3: 2}
"""Blocks per axis of the anisotropy's jackknife, by dimension: 4 × 4 = 16 in 2D, 2³ = 8 in 3D."""


class NetworkConfig(BaseModel):
    """Parameters of the network analyzer (the contacts are the contacts analyzer's)."""

    model_config = ConfigDict(extra="forbid", strict=True)

    blocks: int | None = Field(
        None,
        ge=2,
        le=32,
        description=(
            "Blocks per axis of the grid over the interior window whose jackknife gives the "
            "anisotropy's sampling error; default: 4 in 2D (16 blocks), 2 in 3D (8 blocks)."
        ),
    )


def fabric_tensor(normals: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    """Fabric tensor ``F = <n n^T>`` of 3D unit normals, its deviator and scalar anisotropy.

    ``F`` has trace 1; for an isotropic set ``F = I / 3``. The deviator is
    ``F' = F - I / 3`` and the anisotropy ``a = (15 / 2) sqrt(3/2 F':F')``:
    the contact-normal density ``E(n) = (1 + a_ij n_i n_j) / (4 pi)`` with
    ``a_ij = (15/2) F'_ij`` reproduces ``F``, and ``a`` is its amplitude
    (``a_1 - a_3`` for an axisymmetric ``a_ij``). 0 for an isotropic set,
    7.5 for normals all along one axis. NaN without normals.

    Examples
    --------
    >>> f, dev, a = fabric_tensor(np.eye(3))
    >>> np.allclose(f, np.eye(3) / 3), round(a, 12)
    (True, 0.0)
    """
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    if n.shape[0] == 0:
        nan = np.full((3, 3), np.nan)
        return nan, nan, float("nan")
    f = n.T @ n / n.shape[0]
    dev = f - np.eye(3) * np.trace(f) / 3.0
    return f, dev, anisotropy_of(f)


def anisotropy_of(fabric: FloatArray) -> float:
    """Scalar anisotropy of a fabric tensor of trace 1 (0 for an isotropic one).

    ``2 (l1 - l2) / (l1 + l2)`` of the eigenvalues ``l1 >= l2`` in 2D (2 for
    normals all along one axis); :func:`fabric_tensor`'s ``(15 / 2)
    sqrt(3/2 F':F')`` in 3D (7.5 for normals all along one axis).

    Examples
    --------
    >>> anisotropy_of(np.diag([0.6, 0.4])), anisotropy_of(np.eye(3) / 3)
    (0.3999999999999999, 0.0)
    """
    f = np.asarray(fabric, dtype=np.float64)
    if f.shape[0] == 3:
        dev = f - np.eye(3) * np.trace(f) / 3.0
        return 7.5 * float(np.sqrt(1.5 * np.sum(dev * dev)))
    vals = np.linalg.eigvalsh(f)
    l2, l1 = float(vals[0]), float(vals[1])
    return 2.0 * (l1 - l2) / (l1 + l2) if l1 + l2 > 0 else float("nan")


def principal_direction(fabric: FloatArray) -> list[float]:
    """Return the unit eigenvector of the largest eigenvalue of ``fabric`` (largest component > 0).

    Examples
    --------
    >>> principal_direction(np.diag([0.3, 0.7]))
    [0.0, 1.0]
    """
    _, vecs = np.linalg.eigh(np.asarray(fabric, dtype=np.float64))
    v = vecs[:, -1]
    if v[int(np.argmax(np.abs(v)))] < 0:
        v = -v
    return [float(c) + 0.0 for c in v]


def block_of(points: FloatArray, bounds: FloatArray, blocks: int) -> NDArray[np.int64]:
    """Index of the block of every point in a grid of ``blocks`` per axis over ``bounds``.

    ``bounds`` is ``[xmin, xmax, ymin, ymax(, zmin, zmax)]``; the blocks are
    of equal size, and a point outside the box goes to the nearest block.
    """
    pts = np.asarray(points, dtype=np.float64)
    d = pts.shape[1] if pts.ndim == 2 else len(bounds) // 2
    lo, hi = np.asarray(bounds[0::2], dtype=np.float64), np.asarray(bounds[1::2], dtype=np.float64)
    span = np.where(hi > lo, hi - lo, 1.0)
    with np.errstate(invalid="ignore"):
        cell = np.floor((pts.reshape(-1, d) - lo) / span * blocks)
    cell = np.clip(np.nan_to_num(cell), 0, blocks - 1).astype(np.int64)
    index = np.zeros(cell.shape[0], dtype=np.int64)
    for a in range(d):
        index = index * blocks + cell[:, a]
    return index


def block_jackknife(normals: FloatArray, block: NDArray[np.int64]) -> tuple[float | None, int]:
    """Return the sampling error of the anisotropy of ``normals``, leaving out a block at a time.

    With ``B`` blocks that hold normals, ``a_b`` the anisotropy
    (:func:`anisotropy_of`) of the fabric of all normals but those of block
    ``b`` and ``a_.`` their mean, the error is
    ``sqrt((B - 1) / B sum_b (a_b - a_.)^2)`` (the delete-a-group jackknife).
    Blocks much larger than a particle hold nearly independent parts of the
    network, so the error accounts for the correlation of nearby contacts;
    no random numbers are drawn. ``None`` with fewer than two blocks.

    Returns
    -------
    error, blocks
        The error and ``B``.
    """
    n = np.asarray(normals, dtype=np.float64)
    if n.shape[0] == 0:
        return None, 0
    d = n.shape[1]
    used, inverse = np.unique(block, return_inverse=True)
    b = len(used)
    outer = (n[:, :, None] * n[:, None, :]).reshape(-1, d * d)
    sums = np.zeros((b, d * d))
    np.add.at(sums, inverse, outer)
    counts = np.bincount(inverse, minlength=b).astype(np.float64)
    if b < 2:
        return None, b
    total, count = sums.sum(axis=0), counts.sum()
    left = np.array(
        [anisotropy_of(((total - sums[k]) / (count - counts[k])).reshape(d, d)) for k in range(b)]
    )
    return float(np.sqrt((b - 1) / b * np.sum((left - left.mean()) ** 2))), b


def _plane_fabric(normals: FloatArray) -> dict[str, Any]:
    """Fabric of 2D normals and its anisotropy ``2 (l1 - l2) / (l1 + l2)`` (0: isotropic)."""
    fabric = normals.T @ normals / max(len(normals), 1)
    a = anisotropy_of(fabric)
    return {"fabric": fabric.tolist(), "anisotropy": a if math.isfinite(a) else None}


def _solid_fabric(normals: FloatArray) -> dict[str, Any]:
    """Fabric of 3D normals, its eigenvalues (largest first), deviator and anisotropy."""
    fabric, dev, a = fabric_tensor(normals)
    vals = np.linalg.eigvalsh(fabric) if len(normals) else np.full(3, np.nan)
    return {
        "fabric": fabric.tolist(),
        "fabric_eigenvalues": [float(v) for v in vals[::-1]],
        "fabric_deviator": dev.tolist(),
        "anisotropy": None if np.isnan(a) else a,
    }


class Network(Measured):
    """Contact graph (edges ``i - j`` weighted by A_c) and the fabric tensor of the normals.

    The fabric tensor ``F = <n n^T>`` is taken over the ``n_fabric_contacts``
    contacts whose two particles are both interior. Its anisotropy is 0 for
    an isotropic network: ``2 (l1 - l2) / (l1 + l2)`` in 2D,
    :func:`fabric_tensor`'s in 3D, which also reports the eigenvalues and the
    deviator. ``principal_direction`` is the unit eigenvector of the largest
    eigenvalue.

    ``anisotropy_error`` is the anisotropy's sampling error: the interior
    window's bounding box is cut into ``blocks`` equal blocks per axis (16 in
    2D, 8 in 3D by default), every contact goes to the block of its contact
    point, and :func:`block_jackknife` leaves out one block at a time
    (``error_blocks`` counts the blocks that hold contacts). Blocks, not
    single contacts, are left out because contacts that share a particle or
    a neighbourhood are not independent: a jackknife over contacts would
    take them for independent and understate the error. The error is
    deterministic and scale-free.
    """

    name = "network"
    requires = ("contacts",)

    def __init__(self, config: NetworkConfig | None = None) -> None:
        self.config = config or NetworkConfig()

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Build the edge list and the fabric tensor."""
        contacts = context["contacts"]
        assert isinstance(contacts, Contacts)
        solid = packing.domain.dimension == 3
        self.edges = np.column_stack([contacts.i, contacts.j])
        self.weight = contacts.area
        both = contacts.interior[contacts.i] & contacts.interior[contacts.j]
        degree = np.bincount(self.edges.ravel(), minlength=packing.n_particles)[packing.placed]
        res: dict[str, Any] = {
            "tol": contacts.tol,
            "n_edges": int(self.edges.shape[0]),
            "n_nodes": packing.n_placed,
            "n_fabric_contacts": int(both.sum()),
            "isolated": int(np.sum(degree == 0)),
        }
        normals = contacts.normal[both]
        res.update((_solid_fabric if solid else _plane_fabric)(normals))
        res.update(self._error(packing, contacts, normals, contacts.point[both]))
        self._results = {**res, "total_contact_area": float(self.weight.sum())}
        return self

    def _error(
        self, packing: Packing, contacts: Contacts, normals: FloatArray, points: FloatArray
    ) -> dict[str, Any]:
        """Measure the anisotropy's block jackknife error and the fabric's principal direction."""
        window = interior_window(packing, contacts.margin)
        if window.periodic:
            points = window.wrap(points)
        blocks = self.config.blocks or DEFAULT_BLOCKS[packing.dimension]
        error, used = block_jackknife(normals, block_of(points, window.bounds(), blocks))
        fabric = normals.T @ normals / len(normals) if len(normals) else None
        return {
            "anisotropy_error": error,
            "error_blocks": used,
            "principal_direction": None if fabric is None else principal_direction(fabric),
        }

    def tables(self) -> dict[str, dict[str, Any]]:
        """Edge list with weights."""
        self._need()
        return {"network": {"i": self.edges[:, 0], "j": self.edges[:, 1], "area": self.weight}}
