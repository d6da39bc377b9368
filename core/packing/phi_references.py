"""Packing fractions of well-known random packings, to read a 3D packing's φ against.

Each reference is a label, the fraction (or its range) and the kind of
particles it holds for; a 3D run's summary lists them beside its φ (the
table printed by ``regopack run`` and ``summary.json``). They are figures
from the literature, not computed here: a polydisperse packing of angular
particles has no single reference, and these bracket where it may fall.
"""

from __future__ import annotations

from typing import NamedTuple


class PhiReference(NamedTuple):
    """A reference packing fraction (``low == high`` for a single value)."""

    label: str
    low: float
    high: float
    particles: str

    def text(self) -> str:
        """Return the reference as ``label value`` (a range as ``low–high``)."""
        value = f"{self.low:.2f}" if self.low == self.high else f"{self.low:.2f}–{self.high:.2f}"
        return f"{self.label} {value}"


PHI_REFERENCES_3D: tuple[PhiReference, ...] = (
    PhiReference("random sequential addition", 0.36, 0.40, "convex polyhedra"),
    PhiReference("Williams–Philipse", 0.61, 0.61, "spheres"),
    PhiReference("random close packing", 0.64, 0.64, "monodisperse spheres"),
)
"""The references of a 3D packing's φ, loosest first."""


def references_3d() -> list[dict[str, object]]:
    """Return the 3D references as plain records (for a run's ``summary.json``)."""
    return [r._asdict() for r in PHI_REFERENCES_3D]


def references_row() -> str:
    """Return the 3D references as one line of the run's table."""
    return "; ".join(f"{r.text()} ({r.particles})" for r in PHI_REFERENCES_3D)
