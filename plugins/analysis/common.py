"""Helpers shared by the analyzers: interior window, particle selection."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.domain import Domain
from regopack.packing import Packing


def interior_margin(packing: Packing, margin: float | None = None) -> float:
    """Exclusion margin from the walls: ``margin`` if given, else the scene's d_max.

    The paper excludes particles within one maximum particle diameter of a wall.
    ``d_max`` is read from the run's statistics, the scene's size section, or,
    failing both, twice the largest drawn radius.
    """
    if margin is not None:
        return float(margin)
    stat = packing.stats.get("interior_margin")
    if stat is not None and np.isfinite(stat):
        return float(stat)
    size: Any = packing.scene.get("size", {}) if isinstance(packing.scene, dict) else {}
    if isinstance(size, dict) and "d_max" in size:
        return float(size["d_max"])
    return 2.0 * float(np.max(packing.radius)) if packing.n_particles else 0.0


def interior_window(packing: Packing, margin: float) -> Domain:
    """Return the domain inset by ``margin`` from every wall (a periodic domain: all of it)."""
    return packing.domain.interior(margin)


def interior_mask(packing: Packing, margin: float) -> NDArray[np.bool_]:
    """Placed particles whose centre lies farther than ``margin`` from every wall."""
    inside = interior_window(packing, margin).contains(packing.centre)
    return inside & packing.placed


def eta_of(packing: Packing) -> float | None:
    """Return the packing control coefficient of the run, when the scene used one."""
    density = packing.scene.get("density", {}) if isinstance(packing.scene, dict) else {}
    value = density.get("eta") if isinstance(density, dict) else None
    return float(value) if value is not None else None
