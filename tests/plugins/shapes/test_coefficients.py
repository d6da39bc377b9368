"""The octagon and the polyhedron share the bounds of their support coefficients."""

from __future__ import annotations

import pytest
from pydantic import BaseModel, ValidationError

from regopack.plugins.shapes.octagon import OctagonConfig
from regopack.plugins.shapes.polyhedra.shape import PolyhedronConfig


@pytest.mark.parametrize("model", [OctagonConfig, PolyhedronConfig])
@pytest.mark.parametrize(
    "field, good, bad",
    [("psi", [1e-9, 1e6], [0.0, 1.000001e6, float("inf")]), ("a", [1e-9, 1.0], [0.0, 1.01])],
)
def test_psi_and_a_have_the_same_bounds_in_2d_and_3d(
    model: type[BaseModel], field: str, good: list[float], bad: list[float]
) -> None:
    for value in good:
        assert getattr(model(**{field: value}), field) == value
    for value in bad:
        with pytest.raises(ValidationError, match=field):
            model(**{field: value})
