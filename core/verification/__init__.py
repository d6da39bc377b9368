"""Verification of a packing against independent oracles.

Shapely checks polygons; Qhull and linear programming check polyhedra.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.verification.polygons import CONFIRM_GRID as CONFIRM_GRID
    from regopack.verification.polygons import VerifyReport as VerifyReport
    from regopack.verification.polygons import assert_valid_packing as assert_valid_packing
    from regopack.verification.polygons import verify as verify
    from regopack.verification.summary import verify_packing as verify_packing
    from regopack.verification.summary import verify_summary as verify_summary

__all__ = ["CONFIRM_GRID", "VerifyReport", "assert_valid_packing", "verify"]

_SOURCES = {
    **dict.fromkeys(__all__, "regopack.verification.polygons"),
    "verify_packing": "regopack.verification.summary",
    "verify_summary": "regopack.verification.summary",
}
__all__ += ["verify_packing", "verify_summary"]

__getattr__, __dir__ = lazy_exports(globals(), _SOURCES)
