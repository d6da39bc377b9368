"""Coordination numbers: overall, interior, per mineral, and against the tolerance (SPEC §5–6).

The counting is the same in 2D and 3D, on the contacts of
:class:`~regopack.plugins.analyzers.contacts.Contacts`. Rattlers are removed
with ``d + 1`` contacts in 3D by default: a particle is held in place by
compressive contact forces only if its contact normals do not all lie in one
closed half-space, which takes at least four of them in three dimensions.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError
from regopack.base.units import length_scale
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import Measured, eta_of
from regopack.plugins.analyzers.contacts import Contacts
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def default_sweep(scale: float = 1.0) -> list[float]:
    """Return the default tolerances of the Z(tol) sweep: 20 from d_min / 100 to d_min / 4.

    ``scale`` is the packing's :func:`~regopack.base.units.length_scale` (``d_min / 2``):
    the values are 0.02 to 0.5, rounded to 6 decimals, times ``scale``, which
    at the built-in scenes' ``d_min = 2`` are exactly the rounded values.
    """
    return [round(float(v), 6) * scale for v in np.linspace(0.02, 0.5, 20)]


class CoordinationConfig(BaseModel):
    """Parameters of the coordination analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    tols: list[float] | None = Field(
        None,
        min_length=1,
        description=(
            "Tolerances of the Z(tol) sweep (each at most the contacts analyzer's tol_max); "
            "default: 20 from d_min / 100 to d_min / 4 (0.02 to 0.5 at the built-in scenes' "
            "d_min = 2), those above tol_max left out."
        ),
    )
    rattler_min_contacts: int | None = Field(
        None,
        ge=1,
        le=100,
        description=(
            "A particle with fewer contacts (counting only non-rattlers, removed in turn) is "
            "a rattler; default: 2 in 2D and 3D (frictional particles: two opposite "
            "contact forces can hold one); d + 1 (3 in 2D, 4 in 3D) for frictionless ones."
        ),
    )


def remove_rattlers(
    i: IntArray, j: IntArray, members: BoolArray, min_contacts: int
) -> tuple[BoolArray, IntArray, int]:
    """Remove rattlers from a contact graph, repeatedly, until none is left.

    A member with fewer than ``min_contacts`` contacts with other members is
    a rattler. Removing it lowers its neighbours' counts, which may make
    rattlers of them, so removal goes on in rounds until every member left has
    at least ``min_contacts`` contacts with the others left (the remaining
    graph is the ``min_contacts``-core of the contact graph).

    Parameters
    ----------
    i, j
        The two particles of every contact.
    members
        Mask of the particles that take part (the placed ones); contacts with
        other particles are ignored.
    min_contacts
        Threshold of the contact count.

    Returns
    -------
    rattler, z_mechanical, rounds
        Mask of the rattlers; every particle's contacts with non-rattlers (0
        for rattlers and non-members); the number of removal rounds.

    Examples
    --------
    A triangle with a particle hanging from one corner:

    >>> i, j = np.array([0, 1, 2, 2]), np.array([1, 2, 0, 3])
    >>> rattler, z, rounds = remove_rattlers(i, j, np.ones(4, bool), 2)
    >>> rattler.tolist(), z.tolist(), rounds
    ([False, False, False, True], [2, 2, 2, 0], 1)
    """
    n = int(members.shape[0])
    i = np.asarray(i, dtype=np.int64)
    j = np.asarray(j, dtype=np.int64)
    keep = members[i] & members[j]
    i, j = i[keep], j[keep]
    z = np.bincount(i, minlength=n) + np.bincount(j, minlength=n)
    ends = np.concatenate([i, j])
    order = np.argsort(ends, kind="stable")
    neighbour = np.concatenate([j, i])[order]
    start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(ends, minlength=n), out=start[1:])
    alive = members.copy()
    front = np.flatnonzero(alive & (z < min_contacts))
    rounds = 0
    while front.size:
        rounds += 1
        alive[front] = False
        count = start[front + 1] - start[front]
        first = np.repeat(np.cumsum(count) - count, count)
        rows = np.repeat(start[front], count) + np.arange(int(count.sum())) - first
        hit = neighbour[rows]
        hit = hit[alive[hit]]
        z -= np.bincount(hit, minlength=n)
        touched = np.unique(hit)
        front = touched[z[touched] < min_contacts]
    z[~alive] = 0
    return members & ~alive, z.astype(np.int64), rounds


RATTLER_MIN_CONTACTS = {2: 2, 3: 2}
"""Default contacts (among non-rattlers) that a particle needs not to be a rattler, by dimension."""


class Coordination(Measured):
    """Z = 2 contacts / particles, over the domain and the interior; per mineral; Z(tol).

    Interior statistics count, for every particle whose centre is farther than
    the exclusion margin from every wall, all its contacts (with any particle).
    Rattlers are removed from the contact graph of the placed particles by
    :func:`remove_rattlers`; the mechanical coordination number Z_m is the mean
    contact count of the particles left, counting only contacts among them.

    Attributes
    ----------
    per_particle
        ``(n,)`` contacts of every **drawn** particle, in draw order like every
        packing array (0 for a particle not placed): ``per_particle[packing.placed]``
        are those of the placed ones. The table ``particles`` has one row per
        placed particle instead, with its index in the column ``particle``.
    rattler, z_mechanical
        ``(n,)`` per drawn particle too: whether it is a rattler (never for a
        particle not placed), and its contacts among the non-rattlers.
    interior
        ``(n,)`` whether the particle is placed with its centre in the interior window.
    """

    name = "coordination"
    requires = ("contacts",)

    def __init__(self, config: CoordinationConfig | None = None) -> None:
        self.config = config or CoordinationConfig()

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Count contacts per particle at the contact tolerance and over the sweep."""
        contacts = context["contacts"]
        assert isinstance(contacts, Contacts)
        self._dimension = packing.domain.dimension
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
        tol_max = contacts.tol_max
        asked = self.config.tols
        sweep = set(default_sweep(length_scale(packing)) if asked is None else asked)
        above = sorted(t for t in sweep if t > tol_max)
        if above and asked is not None:
            source = contacts.name
            raise ConfigError(
                f"{self.name}.tols: {above[0]:g} exceeds {source}.tol_max = {tol_max:g}; "
                f"raise {source}.tol_max or drop the larger tolerances"
            )
        # the default sweep stops at the contacts analyzer's tol_max
        tols = sorted({t for t in sweep if t <= tol_max} | {contacts.tol})
        sweep_domain: list[float] = []
        sweep_interior: list[float] = []
        for tol in tols:
            zt = contacts.count_per_particle(tol)
            sweep_domain.append(float(zt[placed].mean()) if placed.any() else float("nan"))
            sweep_interior.append(float(zt[interior].mean()) if interior.any() else float("nan"))
        self.tols = np.asarray(tols)
        self.z_tol_domain = np.asarray(sweep_domain)
        self.z_tol_interior = np.asarray(sweep_interior)
        k = self.config.rattler_min_contacts or RATTLER_MIN_CONTACTS[self._dimension]
        rattler, zm, rounds = remove_rattlers(contacts.i, contacts.j, placed, k)
        self.rattler = rattler
        self.z_mechanical = zm
        solid = placed & ~rattler
        solid_in = interior & ~rattler
        self._z_counts = self._count_table(z, zm, placed, interior, solid_in, names)
        self._results = {
            "tol": contacts.tol,
            "eta": eta_of(packing),
            "interior_margin": contacts.margin,
            "z_domain": float(z[placed].mean()) if placed.any() else None,
            "z_interior": float(z[interior].mean()) if interior.any() else None,
            "n_interior": int(interior.sum()),
            "rattlers_interior": int(rattler[interior].sum()),
            "isolated_interior": int(np.sum(z[interior] == 0)),
            "rattler_min_contacts": k,
            "rattlers": int(rattler.sum()),
            "rattler_fraction": float(rattler.sum() / placed.sum()) if placed.any() else None,
            "rattler_fraction_interior": float(rattler[interior].mean())
            if interior.any()
            else None,
            "rattler_rounds": rounds,
            "n_mechanical": int(solid.sum()),
            "n_mechanical_interior": int(solid_in.sum()),
            "z_mechanical": float(zm[solid].mean()) if solid.any() else None,
            "z_mechanical_interior": float(zm[solid_in].mean()) if solid_in.any() else None,
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

    def _count_table(
        self,
        z: IntArray,
        zm: IntArray,
        placed: BoolArray,
        interior: BoolArray,
        solid_in: BoolArray,
        names: tuple[str, ...],
    ) -> dict[str, Any]:
        """Particles with each contact count: domain, interior, per mineral, rattler-free."""
        top = int(z[placed].max()) if placed.any() else 0
        size = top + 1

        def counts(values: IntArray, mask: BoolArray) -> IntArray:
            return np.bincount(values[mask], minlength=size)[:size].astype(np.int64)

        table: dict[str, Any] = {
            "z": np.arange(size, dtype=np.int64),
            "n_domain": counts(z, placed),
            "n_interior": counts(z, interior),
            "n_interior_mechanical": counts(zm, solid_in),
        }
        for m, name in enumerate(names):
            table[f"n_interior_{name}"] = counts(z, interior & (self._mineral == m))
        return table

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-particle table and the Z(tol) sweep.

        ``particles`` has one row per placed particle: its index in the packing,
        mineral index, centre, equivalent radius, whether it is interior, its
        contact count ``z`` at the contact tolerance, whether it is a rattler
        and its contacts with non-rattlers ``z_mechanical`` (in 3D, where ``z``
        is the centre's third coordinate, the counts are ``contacts`` and
        ``contacts_mechanical``). ``z_tol`` has the columns ``tol, z_domain,
        z_interior``; ``z_counts`` one row per contact count ``z``, with the
        number of particles that have it.
        """
        self._need()
        idx = self._placed_idx
        count, mechanical = (
            ("z", "z_mechanical") if self._dimension == 2 else ("contacts", "contacts_mechanical")
        )
        return {
            "particles": {
                "particle": idx,
                "mineral": self._mineral[idx],
                **{axis: self._centre[idx, a] for a, axis in enumerate("xyz"[: self._dimension])},
                "radius": self._radius[idx],
                "interior": self.interior[idx],
                count: self.per_particle[idx],
                "rattler": self.rattler[idx],
                mechanical: self.z_mechanical[idx],
            },
            "z_tol": {
                "tol": self.tols,
                "z_domain": self.z_tol_domain,
                "z_interior": self.z_tol_interior,
            },
            "z_counts": self._z_counts,
        }
