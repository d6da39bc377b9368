"""3D packings shared by the tests of the 3D analyzers (built once per session)."""

from __future__ import annotations

from typing import Any

import pytest

from regopack.packing.core import Packing

SCENE3D: dict[str, Any] = {
    "name": "analysis3d",
    "seed": 3,
    "count": "auto",
    "domain": {"kind": "box", "width": 24.0, "height": 24.0, "depth": 24.0},
    "size": {"kind": "uniform", "d_min": 3.0, "d_max": 6.0},
    "phases": [
        {"name": "pyroxene", "fraction": 0.6, "shape": {"kind": "polyhedron", "psi": 0.5}},
        {"name": "glass", "fraction": 0.4, "shape": {"kind": "polyhedron", "psi": 2.0}},
    ],
    "insertion": {"kind": "available-surface"},
    "density": {"kind": "eta"},
}
"""A 24-µm box of random polyhedra (about 130 placed, 25 of them interior)."""


@pytest.fixture(scope="session")
def packing3d() -> Packing:
    import regopack

    packing = regopack.pack(SCENE3D, verify=False)
    assert packing.dimension == 3
    return packing


@pytest.fixture(scope="session")
def analysed3d(packing3d: Packing) -> Any:
    """The default 3D analyses of :func:`packing3d` (an ``AnalysisResults``)."""
    import regopack

    return regopack.analyze(packing3d)
