"""Contacts at a tolerance and the equivalent contact shape (SPEC §5), in 2D and 3D.

Each particle grows by ``tol / 2`` along its normals; two particles are in
contact at ``tol`` when the grown particles share area (2D) or volume (3D).
The search of each dimension is its own module: polygons and disks with the
bow-shaped model (:mod:`~regopack.plugins.analyzers.polygon_contacts`),
polyhedra and spheres with the equivalent spherical cap
(:mod:`~regopack.plugins.analyzers.solid_contacts`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self, overload

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    FoundContacts,
    contact_tolerances,
    eta_of,
    interior_margin,
    interior_mask,
)
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class ContactsConfig(BaseModel):
    """Parameters of the contact analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    tol: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Contact tolerance tol (length unit): each outline (or solid) grows by tol/2 along "
            "its normals; default: d_min / 40 (0.05 at the built-in scenes' d_min = 2)."
        ),
    )
    tol_max: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Largest tolerance of later sweeps: pairs that touch up to tol_max are kept; "
            "default: the larger of d_min / 4 (0.5 at d_min = 2) and tol."
        ),
    )
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )

    @model_validator(mode="after")
    def _check(self) -> ContactsConfig:
        if self.tol is not None and self.tol_max is not None and self.tol_max < self.tol:
            raise ValueError(f"tol_max ({self.tol_max}) must be at least tol ({self.tol})")
        return self


class _Column:
    """A column of the contacts at ``tol``, read as an attribute of :class:`Contacts`.

    A column that the packing's dimension does not have raises ``AttributeError``.
    """

    def __init__(self, doc: str, dtype: type[np.generic] = np.float64) -> None:
        self.__doc__ = doc
        self.dtype = dtype

    def __set_name__(self, owner: type, name: str) -> None:
        self.key = name

    @overload
    def __get__(self, contacts: None, owner: type | None = None) -> _Column: ...
    @overload
    def __get__(self, contacts: Contacts, owner: type | None = None) -> NDArray[Any]: ...
    def __get__(self, contacts: Contacts | None, owner: type | None = None) -> Any:
        if contacts is None:
            return self
        return np.asarray(contacts._column(self.key), dtype=self.dtype)


def _median(a: FloatArray) -> float | None:
    return float(np.median(a)) if a.shape[0] else None


class Contacts(Analyzer):
    """Contact pairs, their thresholds, and the region of every contact at ``tol``.

    After :meth:`compute`, ``pairs`` holds every pair (``i < j``, particle
    indices of the packing) whose grown particles overlap at ``tol_max`` and
    ``threshold`` the tolerance above which each pair is in contact (in 3D
    ``pair_normal`` its unit contact normal, from ``i`` to ``j``). The
    properties ``i, j, area, width, depth, normal, point`` describe the
    contacts at ``tol``; so do, in 2D, ``radius`` and ``theta`` of the
    equivalent circular segment and, in 3D, ``volume``, ``cap_radius`` and
    ``thickness`` of the equivalent spherical cap (a property of the other
    dimension raises ``AttributeError``).
    """

    name = "contacts"

    def __init__(self, config: ContactsConfig | None = None) -> None:
        self.config = config or ContactsConfig()
        self._asked = self.config
        self._found: FoundContacts | None = None

    @property
    def tol(self) -> float:
        """The contact tolerance used: ``config.tol``, or its default for the packing."""
        self._need()
        assert self.config.tol is not None
        return float(self.config.tol)

    @property
    def tol_max(self) -> float:
        """The largest tolerance kept: ``config.tol_max``, or its default for the packing."""
        self._need()
        assert self.config.tol_max is not None
        return float(self.config.tol_max)

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Find the candidate pairs, their thresholds, and the regions at ``tol``."""
        tol, tol_max = contact_tolerances(self._asked.tol, self._asked.tol_max, packing, self.name)
        # after compute, the config holds the tolerances used
        self.config = self._asked.model_copy(update={"tol": tol, "tol_max": tol_max})
        self.packing = packing
        if packing.dimension == 3:
            from regopack.plugins.analyzers.solid_contacts import find_contacts as find_solid

            self._found = find_solid(packing, tol, tol_max, self.name)
        else:
            from regopack.plugins.analyzers.polygon_contacts import find_contacts

            self._found = find_contacts(packing, tol, tol_max)
        self.pairs, self.threshold = self._found.pairs, self._found.threshold
        if self._found.pair_normal is not None:
            self.pair_normal = self._found.pair_normal
        self.margin = interior_margin(packing, self.config.margin)
        self.interior = interior_mask(packing, self.margin)
        return self

    def _need(self) -> FoundContacts:
        if self._found is None:
            raise RuntimeError("call compute() first")
        return self._found

    def _column(self, key: str) -> FloatArray:
        columns = self._need().columns
        if key not in columns:
            dimension = self.packing.domain.dimension
            raise AttributeError(f"{self.name}: contacts of a {dimension}D packing have no {key}")
        return columns[key]

    i = _Column("First particle of each contact at ``tol``.", np.int64)
    j = _Column("Second particle of each contact at ``tol``.", np.int64)
    area = _Column("Contact area A_c: of the overlap of the grown particles (projected, in 3D).")
    width = _Column("Contact width b_c: the longest chord of the region (its projection, in 3D).")
    depth = _Column("Depth delta of the equivalent circular segment, or height of the cap.")
    radius = _Column("Radius R_c of the equivalent circular segment (2D).")
    theta = _Column("Central angle of the equivalent circular segment (2D).")
    volume = _Column("Contact volume V_c: the volume shared by the two grown solids (3D).")
    cap_radius = _Column("Sphere radius of the equivalent spherical cap (3D).")
    thickness = _Column("Mean thickness V_c / A_c of the contact region along the normal (3D).")

    @property
    def normal(self) -> FloatArray:
        """Unit contact normal, from i to j, ``(n, d)``: perpendicular to the chord in 2D."""
        return self._need().normal

    @property
    def point(self) -> FloatArray:
        """Midpoint of the chord (2D) or centroid of the region (3D) of each contact, ``(n, d)``."""
        return self._need().point

    def count_per_particle(self, tol: float | None = None) -> IntArray:
        """Count the contacts of every particle at ``tol`` (default: the analyzer's tol)."""
        if tol is None:
            i, j = self._column("i"), self._column("j")
        else:
            if tol > self.tol_max:
                raise ValueError(f"tol = {tol} exceeds tol_max = {self.tol_max}")
            sel = self.threshold < tol
            i, j = self.pairs[sel, 0], self.pairs[sel, 1]
        n = self.packing.n_particles
        return np.bincount(i, minlength=n) + np.bincount(j, minlength=n)

    def results(self) -> dict[str, Any]:
        """Scalars: contacts, tol, medians of A_c, b_c, depth and the quantities of the dimension.

        2D: R_c, the mean depth over width and the share of depths below tol;
        3D: V_c, the thickness and the total contact area.
        """
        n = int(self.area.shape[0])
        out = {
            "tol": self.tol,
            "tol_max": self.tol_max,
            "eta": eta_of(self.packing),
            "interior_margin": self.margin,
            "n_contacts": n,
            "n_candidate_pairs": int(self.pairs.shape[0]),
            "median_area": _median(self.area),
        }
        if self.packing.dimension == 3:
            return out | {
                "median_volume": _median(self.volume),
                "median_width": _median(self.width),
                "median_depth": _median(self.depth),
                "median_thickness": _median(self.thickness),
                "total_contact_area": float(self.area.sum()),
            }
        return out | {
            "median_width": _median(self.width),
            "median_radius": _median(self.radius),
            "median_depth": _median(self.depth),
            "mean_depth_over_width": float(np.mean(self.depth / self.width)) if n else None,
            "share_depth_below_tol": float(np.mean(self.depth < self.tol)) if n else None,
        }

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-contact table ``contacts``: the columns of the dimension, normal and point."""
        found = self._need()
        axes = "xyz"[: self.packing.domain.dimension]
        return {
            "contacts": {
                **found.columns,
                **{f"normal_{a}": found.normal[:, k] for k, a in enumerate(axes)},
                **{f"point_{a}": found.point[:, k] for k, a in enumerate(axes)},
            }
        }
