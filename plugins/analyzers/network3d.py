"""Contact network of a 3D packing and the fabric tensor of its contact normals."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from regopack.plugins.analyzers.common3d import as_packing3d
from regopack.plugins.analyzers.contacts3d import Contacts3D
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]


class Network3DConfig(BaseModel):
    """The 3D network analyzer has no parameters; it uses the contacts3d analyzer's."""

    model_config = ConfigDict(extra="forbid", strict=True)


def fabric_tensor(normals: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    """Fabric tensor ``F = <n n^T>`` of unit normals, its deviator and scalar anisotropy.

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


class Network3D(Analyzer):
    """Contact graph (edges ``i - j`` weighted by A_c) and the fabric of the contact normals.

    The fabric tensor is taken over the contacts whose two particles are both
    interior (see :func:`fabric_tensor`).
    """

    name = "network3d"
    requires = ("contacts3d",)

    def __init__(self, config: Network3DConfig | None = None) -> None:
        self.config = config or Network3DConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Build the edge list and the fabric tensor."""
        p3 = as_packing3d(packing, self)
        contacts = context["contacts3d"]
        assert isinstance(contacts, Contacts3D)
        self.edges = np.column_stack([contacts.i, contacts.j])
        self.weight = contacts.area
        both = contacts.interior[contacts.i] & contacts.interior[contacts.j]
        fabric, dev, a = fabric_tensor(contacts.normal[both])
        vals = np.linalg.eigvalsh(fabric) if both.any() else np.full(3, np.nan)
        degree = np.bincount(self.edges.ravel(), minlength=p3.n_particles)[p3.placed]
        self._results = {
            "tol": contacts.tol,
            "n_edges": int(self.edges.shape[0]),
            "n_nodes": p3.n_placed,
            "n_fabric_contacts": int(both.sum()),
            "isolated": int(np.sum(degree == 0)),
            "fabric": fabric.tolist(),
            "fabric_eigenvalues": [float(v) for v in vals[::-1]],
            "fabric_deviator": dev.tolist(),
            "anisotropy": None if np.isnan(a) else a,
            "total_contact_area": float(self.weight.sum()),
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars: edges, nodes, isolated particles, fabric tensor, deviator and anisotropy."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)

    def tables(self) -> dict[str, dict[str, Any]]:
        """Edge list with weights."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return {"network": {"i": self.edges[:, 0], "j": self.edges[:, 1], "area": self.weight}}
