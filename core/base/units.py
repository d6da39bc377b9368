"""The length unit of a scene and the particle length that scales default lengths.

regopack computes in whatever unit the scene's lengths are written in; the
scene's optional ``length_unit`` (default ``"µm"``) only names it, for the
labels of figures and tables and for the exports. A packing whose embedded
scene has no ``length_unit`` is in micrometres.

Every default length of an analyzer or exporter (contact tolerances, bin
widths, ranges of g(r), slab thicknesses, zoom ranges) is a multiple of the
packing's reference diameter ``d_min`` (:func:`reference_diameter`), so that a
packing and its copy scaled by any factor analyse alike. Each default is
computed as its value at the built-in scenes' scale times
:func:`length_scale`, ``d_min / 2``: at the built-in scenes' ``d_min = 2`` the
factor is exactly 1 and the defaults are exactly the numbers they always were
(``tol = 0.05`` is ``d_min / 40``). A length that the user sets is used as given.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypeGuard

import numpy as np

from regopack.base.errors import ConfigError

__all__ = [
    "BUILTIN_D_MIN",
    "DECADES",
    "DEFAULT_LENGTH_UNIT",
    "LENGTH_UNITS",
    "METRES",
    "check_length_unit",
    "conversion",
    "decimals",
    "length_scale",
    "length_unit",
    "reference_diameter",
]

DEFAULT_LENGTH_UNIT = "µm"
"""Unit of a scene or packing that names none."""

DECADES: dict[str, int] = {"m": 0, "cm": -2, "mm": -3, "µm": -6, "nm": -9}
"""The length units a scene may name, and each one as a power of ten of the metre."""

METRES: dict[str, float] = {unit: 10.0**decade for unit, decade in DECADES.items()}
"""The length units a scene may name, and each one in metres."""

LENGTH_UNITS: tuple[str, ...] = tuple(METRES)
"""The length units a scene may name (``"um"`` and ``"μm"`` are read as ``"µm"``)."""

_ALIASES = {"um": "µm", "μm": "µm"}

BUILTIN_D_MIN = 2.0
"""``size.d_min`` of the built-in scenes: the reference diameter at which
:func:`length_scale` is 1 and every relative default equals its former fixed value."""


def _allowed() -> str:
    return ", ".join(repr(u) for u in LENGTH_UNITS) + " ('um' for 'µm')"


def check_length_unit(value: Any, source: str | None = None) -> str:
    """Return ``value`` as one of :data:`LENGTH_UNITS`; refuse anything else in one line.

    Parameters
    ----------
    value
        The unit as written (``"um"`` and the Greek ``"μm"`` give ``"µm"``).
    source
        Where the value comes from (a file, an option); it starts the message.

    Raises
    ------
    ConfigError
        When ``value`` is not a known length unit.

    Examples
    --------
    >>> check_length_unit("um"), check_length_unit("mm")
    ('µm', 'mm')
    >>> check_length_unit("ft", "scene.toml")
    Traceback (most recent call last):
    ...
    regopack.base.errors.ConfigError: scene.toml: length_unit = 'ft': not a length unit; \
allowed: 'm', 'cm', 'mm', 'µm', 'nm' ('um' for 'µm')
    """
    unit = _ALIASES.get(value, value) if isinstance(value, str) else value
    if isinstance(unit, str) and unit in METRES:
        return unit
    where = f"{source}: " if source else ""
    shown = repr(value) if isinstance(value, str) else f"{value!r} ({type(value).__name__})"
    raise ConfigError(
        f"{where}length_unit = {shown[:60]}: not a length unit; allowed: {_allowed()}"
    )


def _scene_of(packing: Any) -> Mapping[str, Any]:
    scene = packing if isinstance(packing, Mapping) else getattr(packing, "scene", None)
    return scene if isinstance(scene, Mapping) else {}


def length_unit(packing: Any) -> str:
    """Return the length unit of a packing (or of a scene given as a dictionary).

    The embedded scene's ``length_unit``, or ``"µm"`` when it names none.

    Raises
    ------
    ConfigError
        When the embedded scene names something that is not a length unit.

    Examples
    --------
    >>> length_unit({"length_unit": "mm"}), length_unit({})
    ('mm', 'µm')
    """
    value = _scene_of(packing).get("length_unit", DEFAULT_LENGTH_UNIT)
    return check_length_unit(value, "the packing's scene")


def _positive(value: Any) -> TypeGuard[float]:
    """Tell whether ``value`` is a finite positive number (not a bool)."""
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    return math.isfinite(value) and value > 0


def reference_diameter(packing: Any) -> float:
    """Return the reference diameter ``d_min`` that scales the default lengths of a packing.

    The packing's statistic ``reference_diameter`` when it has one (a section
    of a 3D packing keeps the 3D ``d_min``: its smallest cut can be a sliver);
    else the embedded scene's ``size.d_min`` when it is a positive number (the
    smallest diameter the size distribution draws); else the smallest
    equivalent diameter ``2 r`` among the packing's particles; else (no
    particle) :data:`BUILTIN_D_MIN`.

    Examples
    --------
    >>> from regopack.testing import packing_from_polygons
    >>> square = packing_from_polygons([[(0, 0), (2, 0), (2, 2), (0, 2)]])
    >>> round(reference_diameter(square), 6)  # a 2 x 2 square: area 4 = pi (d/2)^2
    2.256758
    """
    stats = getattr(packing, "stats", None)
    stat = stats.get("reference_diameter") if isinstance(stats, Mapping) else None
    if _positive(stat):
        return float(stat)
    size = _scene_of(packing).get("size")
    if isinstance(size, Mapping):
        d_min = size.get("d_min")
        if _positive(d_min):
            return float(d_min)
    radius = getattr(packing, "radius", None)
    if radius is not None:
        r = np.asarray(radius, dtype=np.float64)
        r = r[np.isfinite(r) & (r > 0)]
        if r.size:
            return 2.0 * float(r.min())
    return BUILTIN_D_MIN


def length_scale(packing: Any) -> float:
    """Return ``reference_diameter(packing) / 2``, the factor of every relative default length.

    Exactly 1 at the built-in scenes' ``d_min = 2``, so that their defaults
    are the fixed numbers they always were.
    """
    return reference_diameter(packing) / BUILTIN_D_MIN


def decimals(scale: float, at_builtin: int) -> int:
    """Return the decimals that show a length as ``at_builtin`` decimals do at the built-in scale.

    A length printed with a fixed number of decimals is rounded to an absolute
    step (0.01 for 2 decimals); scaled with the packing's :func:`length_scale`
    the step stays the same fraction of ``d_min``, so a packing written in
    millimetres shows as many significant digits as one in micrometres.

    Examples
    --------
    >>> decimals(1.0, 2), decimals(1e-3, 2), decimals(1e3, 2), decimals(0.5, 2)
    (2, 5, 0, 3)
    """
    if not (math.isfinite(scale) and scale > 0):
        return at_builtin
    return max(0, at_builtin - math.floor(math.log10(scale)))


def conversion(unit: str, to: str) -> float:
    """Return the factor that turns lengths in ``unit`` into lengths in ``to`` (a power of ten).

    Examples
    --------
    >>> conversion("mm", "µm"), conversion("µm", "mm"), conversion("nm", "nm")
    (1000.0, 0.001, 1.0)
    """
    return float(10.0 ** (DECADES[unit] - DECADES[to]))
