"""One verification entry for a packing of either dimension, and its line in a run's summary.

:func:`verify_packing` checks a packing with the oracle of its dimension:
:func:`regopack.verification.polygons.verify` (shapely) for polygons,
:func:`regopack.verification.polyhedra.verify_polyhedra` and
:func:`~regopack.verification.polyhedra.verify_spheres` (Qhull and HiGHS) for
solids. :func:`verify_summary` turns the report into the ``verify`` entry of
``summary.json``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box, Cylinder
from regopack.packing.core import Packing
from regopack.verification.polygons import VerifyReport, verify
from regopack.verification.polyhedra import Report3D, verify_polyhedra, verify_spheres

__all__ = ["verify_packing", "verify_summary"]


def verify_packing(packing: Packing, rel_tol: float = 1e-9) -> VerifyReport | Report3D:
    """Check ``packing`` for overlaps and wall violations with its dimension's oracle.

    ``rel_tol`` is the overlap, as a fraction of the smaller particle's area
    or volume, above which a pair counts as overlapping.

    Raises
    ------
    ConfigError
        For rounded polyhedra, which the oracle does not check yet.
    """
    if packing.dimension == 3:
        return _verify_solids(packing, rel_tol)
    return verify(packing, rel_tol=rel_tol)


def _verify_solids(packing: Packing[Box | Cylinder], rel_tol: float) -> Report3D:
    placed = packing.placed_in_order()
    box = packing.domain
    solids = packing.solids
    bounds = box.bounds()
    lo, hi = bounds[0::2].tolist(), bounds[1::2].tolist()
    # a cylinder's walls: its axis and radius, the floor and lid at the bounding box's z
    cylinder = (box.cx, box.cy, box.radius) if isinstance(box, Cylinder) else None
    if packing.rounded:
        if solids.normals.shape[0] != 0:
            raise ConfigError("verify: rounded polyhedra are not verified yet")
        report = verify_spheres(
            packing.centre[placed] + solids.vertices[solids.offsets[placed]],
            solids.rounding_radius[placed],
            lo,
            hi,
            periodic=box.periodic,
            rel_tol=rel_tol,
            cylinder=cylinder,
        )
    else:
        report = verify_polyhedra(
            [packing.world_vertices(int(j)) for j in placed],
            None,
            lo,
            hi,
            periodic=box.periodic,
            rel_tol=rel_tol,
            cylinder=cylinder,
        )
    ix = [int(j) for j in placed]

    def pair(p: tuple[int, int]) -> tuple[int, int]:
        a, b = sorted((ix[p[0]], ix[p[1]]))
        return (a, b)

    return dataclasses.replace(
        report,
        overlapping_pairs=tuple(sorted(pair(p) for p in report.overlapping_pairs)),
        worst_pair=None if report.worst_pair is None else pair(report.worst_pair),
        worst_outside=None
        if report.worst_outside is None
        else (ix[report.worst_outside[0]], report.worst_outside[1]),
    )


def verify_summary(packing: Packing) -> dict[str, Any]:
    """Return the ``verify`` entry of a run's summary.

    ``ok``, ``overlap_pairs`` (pairs overlapping by more than 1e-9 of the
    smaller area or volume), ``worst_overlap`` (the largest overlap as a
    fraction of the smaller particle, 0 when none) and ``outside``
    (particles leaving the domain); ``skipped`` with the reason instead for
    rounded polyhedra.
    """
    if packing.dimension == 3:
        if packing.rounded and packing.solids.normals.shape[0] != 0:
            return {"skipped": "rounded polyhedra are not verified yet"}
        solid = _verify_solids(packing, 1e-9)
        worst = solid.worst_overlap_fraction
        n_pairs, n_outside, ok = solid.n_overlapping_pairs, solid.n_outside, solid.ok
    else:
        plane = verify(packing)
        worst = plane.worst_overlap[2] if plane.worst_overlap is not None else 0.0
        n_pairs, n_outside, ok = plane.n_overlapping_pairs, plane.n_outside, plane.ok
    return {
        "ok": bool(ok),
        "overlap_pairs": int(n_pairs),
        "worst_overlap": float(worst),
        "outside": int(n_outside),
    }
