"""The contact network: edges weighted by contact area, and the fabric of contact normals."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from pydantic import BaseModel, ConfigDict

from regopack.packing.core import Packing
from regopack.plugins.analyzers.contacts import Contacts
from regopack.registry.interfaces import Analyzer


class NetworkConfig(BaseModel):
    """The network analyzer has no parameters; it uses the contacts analyzer's."""

    model_config = ConfigDict(extra="forbid", strict=True)


class Network(Analyzer):
    """Contact graph (edges ``i - j`` weighted by A_c) and the fabric tensor of the normals.

    The fabric tensor ``F = <n n^T>`` over the contacts whose two particles are
    both interior; its anisotropy ``2 (l1 - l2) / (l1 + l2)`` is 0 for an
    isotropic network.
    """

    name = "network"
    requires = ("contacts",)

    def __init__(self, config: NetworkConfig | None = None) -> None:
        self.config = config or NetworkConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Build the edge list and the fabric tensor."""
        contacts = context["contacts"]
        assert isinstance(contacts, Contacts)
        self.edges = np.column_stack([contacts.i, contacts.j])
        self.weight = contacts.area
        both = contacts.interior[contacts.i] & contacts.interior[contacts.j]
        n = contacts.normal[both]
        fabric = n.T @ n / max(len(n), 1)
        vals = np.linalg.eigvalsh(fabric)
        l2, l1 = float(vals[0]), float(vals[1])
        degree = np.bincount(self.edges.ravel(), minlength=packing.n_particles)[packing.placed]
        self._results = {
            "tol": contacts.config.tol,
            "n_edges": int(self.edges.shape[0]),
            "n_nodes": packing.n_placed,
            "isolated": int(np.sum(degree == 0)),
            "fabric": fabric.tolist(),
            "anisotropy": 2.0 * (l1 - l2) / (l1 + l2) if l1 + l2 > 0 else None,
            "total_contact_area": float(self.weight.sum()),
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars: edges, nodes, isolated particles, fabric tensor and its anisotropy."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)

    def tables(self) -> dict[str, dict[str, Any]]:
        """Edge list with weights."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return {"network": {"i": self.edges[:, 0], "j": self.edges[:, 1], "area": self.weight}}
