"""The coefficients of the random support distances of the octagon and polyhedron shapes.

Both shapes draw support distances ``1 + a sigma_k |2 xi_k - 1|^psi`` (the
polyhedron's times the base distance of its regular solid): the shape
coefficient ``psi`` and the perturbation amplitude ``a`` obey the same bounds
in both, which these annotated types hold once.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

__all__ = ["Amplitude", "ShapeCoefficient"]

ShapeCoefficient = Annotated[float, Field(gt=0, le=1e6, allow_inf_nan=False)]
"""Shape coefficient psi (> 0, at most 1e6): larger gives more regular shapes."""

Amplitude = Annotated[float, Field(gt=0, le=1, allow_inf_nan=False)]
"""Perturbation amplitude a of the support distances, in (0, 1]."""
