"""The fabric block of a run summary: contacts, Z and Z_m, rattlers and the fabric's anisotropy.

Every run (2D and 3D) reports, under ``fabric`` in its summary, what a DEM
user needs to know of the contact network of the packing before simulating
it: how many contacts there are, the mean coordination number Z, the
mechanical one Z_m of the particles left after removing rattlers, the share
of rattlers among the placed particles, and the anisotropy of the fabric
tensor of the contact normals with its sampling error and principal
direction. The numbers come from the registered analyzers ``contacts``,
``coordination`` and ``network`` (the core does not import them), with
their default parameters, unless the scene's own analyses computed them
already: those are reused. ``outputs.fabric = false`` leaves the block out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from regopack.registry.interfaces import Analyzer
from regopack.scenes.analysis_plan import dimensions_of, run_analyses

if TYPE_CHECKING:
    from regopack.packing.core import Packing
    from regopack.registry.manager import Registry

__all__ = ["FABRIC_ANALYSES", "fabric_rows", "fabric_summary"]

FABRIC_ANALYSES: tuple[str, ...] = ("contacts", "coordination", "network")
"""Analyzers whose results make the fabric block (by their registered names)."""

_FROM_NETWORK = {
    "tol": "tol",
    "n_contacts": "n_edges",
    "n_fabric_contacts": "n_fabric_contacts",
}
_FROM_COORDINATION = {
    "z": "z_domain",
    "z_mechanical": "z_mechanical",
    "rattlers": "rattlers",
    "rattler_fraction": "rattler_fraction",
    "rattler_min_contacts": "rattler_min_contacts",
}
_FROM_FABRIC = {
    "anisotropy": "anisotropy",
    "anisotropy_error": "anisotropy_error",
    "error_blocks": "error_blocks",
    "principal_direction": "principal_direction",
}
"""Keys of the block and the analyzer results they are taken from."""


def _missing(registry: Registry, dimension: int) -> str | None:
    """Why the fabric cannot be measured with ``registry``, or ``None`` when it can."""
    for name in FABRIC_ANALYSES:
        if ("analysis", name) not in registry:
            return f"no analyzer {name!r} is registered"
        if dimension not in dimensions_of(registry, name):
            return f"the analyzer {name!r} does not analyse {dimension}D packings"
    return None


def fabric_summary(
    packing: Packing, registry: Registry, computed: Mapping[str, Analyzer] | None = None
) -> dict[str, Any]:
    """Return the fabric block of a run summary of ``packing``.

    Parameters
    ----------
    packing
        The packing of the run.
    registry
        Where the analyzers of :data:`FABRIC_ANALYSES` are looked up.
    computed
        Analyzers the run computed already (its scene's analyses), by the name
        their results are filed under; those of :data:`FABRIC_ANALYSES` among
        them are reused, with the parameters they were computed with.

    Returns
    -------
    dict
        ``tol`` (the contact tolerance), ``n_contacts``, ``n_fabric_contacts``
        (between two interior particles, the fabric's), ``z`` (mean contacts of
        the placed particles), ``z_mechanical`` (of the non-rattlers, among
        themselves), ``rattlers``, ``rattler_fraction`` (of the placed
        particles), ``rattler_min_contacts``, ``anisotropy``,
        ``anisotropy_error`` (block jackknife), ``error_blocks`` and
        ``principal_direction`` (unit vector). ``{"skipped": reason}`` when
        the registry lacks an analyzer.
    """
    why = _missing(registry, packing.dimension)
    if why is not None:
        return {"skipped": why}
    done = run_analyses(
        packing,
        registry,
        [(name, {}) for name in FABRIC_ANALYSES],
        warn=False,
        computed=computed,
    )
    network = done["network"].results()
    coordination = done["coordination"].results()
    block = {key: network.get(src) for key, src in _FROM_NETWORK.items()}
    block.update({key: coordination.get(src) for key, src in _FROM_COORDINATION.items()})
    block.update({key: network.get(src) for key, src in _FROM_FABRIC.items()})
    return block


def _plain(value: Any, spec: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return format(value, spec)


CHANCE: dict[int, float] = {2: 2.0, 3: 7.5}
"""Root-mean-square anisotropy of ``n`` independent isotropic normals, times ``sqrt(n)``.

The anisotropy is a norm of the deviator of the fabric, positive whatever
the normals: ``n`` normals drawn from an isotropic distribution have
``E[a**2] = 4 / n`` in 2D (``a = 2 (l1 - l2)``) and ``56.25 / n`` in 3D
(``a = 7.5 sqrt(3/2 F':F')``, ``E[F':F'] = 2 / (3 n)``).
"""


def _by_chance(block: Mapping[str, Any], dimension: int) -> float:
    """Return the anisotropy that as many isotropic normals as the fabric has show by chance."""
    n = block.get("n_fabric_contacts")
    if not isinstance(n, int) or n <= 0:
        return 0.0
    return CHANCE[dimension] / math.sqrt(n)


def _direction(block: Mapping[str, Any]) -> str:
    """`` (vertical)``, `` (horizontal)`` or `` (40° from vertical)``; empty when not significant.

    The direction is shown only when the anisotropy exceeds twice its error
    and twice what isotropic normals as many as the fabric's give by chance
    (:data:`CHANCE`): the anisotropy is never below that noise, so its error
    alone does not tell a fabric from an isotropic one (three isotropic
    networks in five pass twice the error in 3D).
    The vertical is the last axis (y in 2D, z in 3D).
    """
    a, err = block.get("anisotropy"), block.get("anisotropy_error")
    v = block.get("principal_direction")
    if a is None or err is None or not v or not a > 2.0 * err:
        return ""
    if not a > 2.0 * _by_chance(block, len(v)):
        return ""
    angle = math.degrees(math.acos(min(1.0, abs(float(v[-1])))))
    if angle <= 15.0:
        return " (vertical)"
    if angle >= 75.0:
        return " (horizontal)"
    return f" ({angle:.0f}° from vertical)"


def fabric_rows(block: Mapping[str, Any]) -> list[tuple[str, str]]:
    """Return the rows of the fabric block in the printed summary of a run.

    The anisotropy shows three decimals, or as many as the first digit of
    its error needs; the direction as :func:`_direction` says.

    Examples
    --------
    >>> block = {"anisotropy": 0.1812, "anisotropy_error": 0.0043, "z": 3.93,
    ...          "principal_direction": [0.1, 0.995], "z_mechanical": 4.21,
    ...          "rattler_fraction": 0.2234}
    >>> for row in fabric_rows(block):
    ...     print(row)
    ('fabric anisotropy', '0.181 ± 0.004 (vertical)')
    ('Z / Z_m / rattlers', '3.93 / 4.21 / 22.3 %')
    """
    if "skipped" in block:
        return [("fabric", f"skipped: {block['skipped']}")]
    a, err = block.get("anisotropy"), block.get("anisotropy_error")
    digits = 3
    if isinstance(err, float) and 0.0 < err < 1e-3:
        digits = min(6, -math.floor(math.log10(err)))
    value = _plain(a, f".{digits}f")
    if a is not None and err is not None:
        value += f" ± {_plain(err, f'.{digits}f')}"
    share = block.get("rattler_fraction")
    rattlers = "n/a" if share is None else f"{100.0 * share:.1f} %"
    v = block.get("principal_direction")
    n = block.get("n_fabric_contacts")
    if a is not None and v and len(v) in CHANCE and isinstance(n, int) and n > 0:
        if not a > 2.0 * _by_chance(block, len(v)):
            # a norm is never below what random normals give: this one says nothing
            value += f" (no more than chance gives {n} contact{'s' if n != 1 else ''})"
    return [
        ("fabric anisotropy", value + _direction(block)),
        (
            "Z / Z_m / rattlers",
            f"{_plain(block.get('z'), '.2f')} / {_plain(block.get('z_mechanical'), '.2f')} "
            f"/ {rattlers}",
        ),
    ]
