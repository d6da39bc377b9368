"""Coordination numbers of a 3D packing: overall, interior, per mineral, Z(tol), rattlers.

The counting is that of 2D (:class:`regopack.plugins.analyzers.coordination.Coordination`)
on the contacts of :class:`~regopack.plugins.analyzers.contacts3d.Contacts3D`.
Rattlers are removed with ``d + 1 = 4`` contacts by default: a particle is
held in place by compressive contact forces only if its contact normals do
not all lie in one closed half-space, which takes at least four of them in
three dimensions.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

from pydantic import Field

from regopack.plugins.analyzers.common3d import as_packing3d
from regopack.plugins.analyzers.coordination import Coordination, CoordinationConfig
from regopack.registry.interfaces import Analyzer

RATTLER_MIN_CONTACTS_3D = 4
"""Contacts (among non-rattlers) that a particle needs in 3D not to be a rattler: d + 1."""


class Coordination3DConfig(CoordinationConfig):
    """Parameters of the 3D coordination analyzer."""

    rattler_min_contacts: int = Field(
        RATTLER_MIN_CONTACTS_3D,
        ge=1,
        le=100,
        description=(
            "A particle with fewer contacts (counting only non-rattlers, removed in turn) is "
            "a rattler: 4 (d + 1) in 3D."
        ),
    )


class Coordination3D(Coordination):
    """Z = 2 contacts / particles of a 3D packing; interior, per mineral, Z(tol), rattlers.

    As the 2D analyzer (same results and attributes), on the contacts of
    ``contacts3d``. Its ``particles`` table has the centre's three
    coordinates ``x, y, z`` and the counts ``contacts`` and
    ``contacts_mechanical`` (the 2D table's ``z`` and ``z_mechanical``).
    """

    name = "coordination3d"
    requires = ("contacts3d",)

    def __init__(self, config: Coordination3DConfig | None = None) -> None:
        super().__init__(config or Coordination3DConfig())

    def compute(self, packing: Any, context: Mapping[str, Analyzer]) -> Self:
        """Count contacts per particle at the contact tolerance and over the sweep."""
        return super().compute(as_packing3d(packing, self), context)  # type: ignore[arg-type]

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-particle table, the Z(tol) sweep and the count of particles per contact number."""
        out = super().tables()
        idx = self._placed_idx
        out["particles"] = {
            "particle": idx,
            "mineral": self._mineral[idx],
            "x": self._centre[idx, 0],
            "y": self._centre[idx, 1],
            "z": self._centre[idx, 2],
            "radius": self._radius[idx],
            "interior": self.interior[idx],
            "contacts": self.per_particle[idx],
            "rattler": self.rattler[idx],
            "contacts_mechanical": self.z_mechanical[idx],
        }
        return out
