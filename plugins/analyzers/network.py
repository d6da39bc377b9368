"""The contact network: edges weighted by contact area, and the fabric of contact normals."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import Measured
from regopack.plugins.analyzers.contacts import Contacts
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]


class NetworkConfig(BaseModel):
    """The network analyzer has no parameters; it uses the contacts analyzer's."""

    model_config = ConfigDict(extra="forbid", strict=True)


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
    a = 7.5 * float(np.sqrt(1.5 * np.sum(dev * dev)))
    return f, dev, a


def _plane_fabric(normals: FloatArray) -> dict[str, Any]:
    """Fabric of 2D normals and its anisotropy ``2 (l1 - l2) / (l1 + l2)`` (0: isotropic)."""
    fabric = normals.T @ normals / max(len(normals), 1)
    vals = np.linalg.eigvalsh(fabric)
    l2, l1 = float(vals[0]), float(vals[1])
    return {
        "fabric": fabric.tolist(),
        "anisotropy": 2.0 * (l1 - l2) / (l1 + l2) if l1 + l2 > 0 else None,
    }


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

    The fabric tensor ``F = <n n^T>`` is taken over the contacts whose two
    particles are both interior. Its anisotropy is 0 for an isotropic
    network: ``2 (l1 - l2) / (l1 + l2)`` in 2D, :func:`fabric_tensor`'s in 3D,
    which also reports the eigenvalues, the deviator and ``n_fabric_contacts``.
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
        }
        if solid:
            res["n_fabric_contacts"] = int(both.sum())
        res["isolated"] = int(np.sum(degree == 0))
        res.update((_solid_fabric if solid else _plane_fabric)(contacts.normal[both]))
        self._results = {**res, "total_contact_area": float(self.weight.sum())}
        return self

    def tables(self) -> dict[str, dict[str, Any]]:
        """Edge list with weights."""
        self._need()
        return {"network": {"i": self.edges[:, 0], "j": self.edges[:, 1], "area": self.weight}}
