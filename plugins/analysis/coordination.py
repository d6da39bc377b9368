"""Coordination numbers: overall, interior, per mineral, and against the tolerance (SPEC §5–6)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.errors import ConfigError
from regopack.interfaces import Analyzer
from regopack.packing import Packing
from regopack.plugins.analysis.common import eta_of
from regopack.plugins.analysis.contacts import Contacts

FloatArray = NDArray[np.float64]


def _default_sweep() -> list[float]:
    return [round(float(v), 6) for v in np.linspace(0.02, 0.5, 20)]


class CoordinationConfig(BaseModel):
    """Parameters of the coordination analyzer."""

    model_config = ConfigDict(extra="forbid")

    tols: list[float] = Field(
        default_factory=_default_sweep,
        min_length=1,
        description=(
            "Tolerances of the Z(tol) sweep (each at most the contacts analyzer's tol_max)."
        ),
    )


class Coordination(Analyzer):
    """Z = 2 contacts / particles, over the domain and the interior; per mineral; Z(tol).

    Interior statistics count, for every particle whose centre is farther than
    the exclusion margin from every wall, all its contacts (with any particle).
    """

    name = "coordination"
    requires = ("contacts",)

    def __init__(self, config: CoordinationConfig | None = None) -> None:
        self.config = config or CoordinationConfig()
        self._results: dict[str, Any] | None = None

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Count contacts per particle at the contact tolerance and over the sweep."""
        contacts = context["contacts"]
        assert isinstance(contacts, Contacts)
        placed = packing.placed
        interior = contacts.interior
        z = contacts.count_per_particle()
        self.per_particle = z
        self.interior = interior
        self._placed_idx = np.flatnonzero(placed).astype(np.int64)
        self._mineral = packing.mineral
        self._centre = packing.centre
        self._radius = packing.radius
        names = packing.mineral_names
        per_mineral: dict[str, float | None] = {}
        counts: dict[str, int] = {}
        dist: dict[str, list[int]] = {}
        for m, name in enumerate(names):
            sel = interior & (packing.mineral == m)
            counts[name] = int(sel.sum())
            per_mineral[name] = float(z[sel].mean()) if sel.any() else None
            dist[name] = np.bincount(z[sel], minlength=1).tolist() if sel.any() else []
        tol_max = contacts.config.tol_max
        sweep = set(self.config.tols)
        above = sorted(t for t in sweep if t > tol_max)
        if above and "tols" in self.config.model_fields_set:
            raise ConfigError(
                f"coordination.tols: {above[0]:g} exceeds contacts.tol_max = {tol_max:g}; "
                "raise contacts.tol_max or drop the larger tolerances"
            )
        # the default sweep stops at the contacts analyzer's tol_max
        tols = sorted({t for t in sweep if t <= tol_max} | {contacts.config.tol})
        sweep_domain: list[float] = []
        sweep_interior: list[float] = []
        for tol in tols:
            zt = contacts.count_per_particle(tol)
            sweep_domain.append(float(zt[placed].mean()) if placed.any() else float("nan"))
            sweep_interior.append(float(zt[interior].mean()) if interior.any() else float("nan"))
        self.tols = np.asarray(tols)
        self.z_tol_domain = np.asarray(sweep_domain)
        self.z_tol_interior = np.asarray(sweep_interior)
        self._results = {
            "tol": contacts.config.tol,
            "eta": eta_of(packing),
            "interior_margin": contacts.margin,
            "z_domain": float(z[placed].mean()) if placed.any() else None,
            "z_interior": float(z[interior].mean()) if interior.any() else None,
            "n_interior": int(interior.sum()),
            "rattlers_interior": int(np.sum(z[interior] == 0)),
            "z_per_mineral": per_mineral,
            "n_per_mineral": counts,
            "z_distribution_per_mineral": dist,
            "z_distribution": np.bincount(z[interior], minlength=1).tolist()
            if interior.any()
            else [],
            "tol_sweep": [float(t) for t in tols],
            "z_domain_sweep": sweep_domain,
            "z_interior_sweep": sweep_interior,
        }
        return self

    def results(self) -> dict[str, Any]:
        """Scalars and small lists (JSON): Z overall, interior, per mineral, and Z(tol)."""
        if self._results is None:
            raise RuntimeError("call compute() first")
        return dict(self._results)

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-particle table and the Z(tol) sweep.

        ``particles`` has one row per placed particle: its index in the packing,
        mineral index, centre, equivalent radius, whether it is interior, and
        its contact count ``z`` at the contact tolerance. ``z_tol`` has the
        columns ``tol, z_domain, z_interior``.
        """
        if self._results is None:
            raise RuntimeError("call compute() first")
        idx = self._placed_idx
        return {
            "particles": {
                "particle": idx,
                "mineral": self._mineral[idx],
                "x": self._centre[idx, 0],
                "y": self._centre[idx, 1],
                "radius": self._radius[idx],
                "interior": self.interior[idx],
                "z": self.per_particle[idx],
            },
            "z_tol": {
                "tol": self.tols,
                "z_domain": self.z_tol_domain,
                "z_interior": self.z_tol_interior,
            },
        }
