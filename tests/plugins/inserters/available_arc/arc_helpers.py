"""Helpers for the available-arc tests: build populations and states by hand."""

from __future__ import annotations

import numpy as np

from regopack.geometry.domain import Domain, Rectangle
from regopack.geometry.population import Population, ShapeBatch, concat_shapes
from regopack.packing.core import Packing
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.available_arc import AvailableArc, AvailableArcConfig
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.registry.interfaces import InsertionResult


def octagon_population(
    radius: np.ndarray, rng: np.random.Generator, psi: float = 0.5, a: float = 1 / 3, m: int = 8
) -> Population:
    """Population of random octagons with the given radii (one mineral)."""
    batch = RandomPolygon(OctagonConfig(psi=psi, a=a, m=m)).generate(radius, rng)
    return Population(
        radius=radius,
        mineral=np.zeros(len(radius), dtype=np.int64),
        mineral_names=("m",),
        shapes=batch,
    )


def mixed_population(
    radius: np.ndarray, rng: np.random.Generator, psis: tuple[float, ...] = (0.25, 1.0, 15.0)
) -> Population:
    """Population with one phase per ``psi`` drawn uniformly."""
    n = len(radius)
    mineral = rng.integers(0, len(psis), size=n).astype(np.int64)
    parts: list[tuple[np.ndarray, ShapeBatch]] = []
    for p, psi in enumerate(psis):
        idx = np.flatnonzero(mineral == p)
        parts.append((idx, RandomPolygon(OctagonConfig(psi=psi)).generate(radius[idx], rng)))
    return Population(
        radius=radius,
        mineral=mineral,
        mineral_names=tuple(f"p{p}" for p in range(len(psis))),
        shapes=concat_shapes(parts, n),
    )


def big_domain(scale: float = 1.0) -> Rectangle:
    return Rectangle(-1e3 * scale, 1e3 * scale, -1e3 * scale, 1e3 * scale)


def change5_population(
    n: int, seed: int, scale: float = 1.0
) -> tuple[Population, np.random.Generator]:
    """``n`` Chang'e-5 radii (times ``scale``) as a three-phase octagon population."""
    rng = np.random.default_rng(seed)
    radius = scale * Change5(Change5Config()).sample(n, rng)
    return mixed_population(radius, rng), rng


def pack(
    pop: Population, domain: Domain, rng: np.random.Generator, eta: float = 0.0, **cfg: object
) -> InsertionResult:
    """Run the available-arc inserter with the eta controller."""
    inserter = AvailableArc(AvailableArcConfig(**cfg))
    return inserter.pack(pop, domain, EtaController(EtaConfig(eta=eta)), rng)


def as_packing(pop: Population, res: InsertionResult, domain: Domain) -> Packing:
    """The packing of an insertion result."""
    return Packing.from_parts(pop, res, domain, {}, 0)
