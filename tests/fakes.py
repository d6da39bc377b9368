"""Small fake plugins for testing the core without the real plugins.

They use the built-in plugin names and accept the same parameters as the
built-in scenes, so the built-in scenes resolve against them.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from regopack.geometry.domain import Rectangle
from regopack.geometry.population import Population, ShapeBatch
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import (
    DensityController,
    InsertionResult,
    InsertionStrategy,
    ProgressCallback,
    ShapeGenerator,
    SizeDistribution,
)
from regopack.registry.plugin_types import (
    DensityControllerSpec,
    InserterSpec,
    ShapeSpec,
    SizeDistributionSpec,
)
from regopack.testing import make_registry


class SizeConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")
    d_min: float = Field(2.0, gt=0, description="smallest diameter")
    d_max: float = Field(40.0, gt=0, description="largest diameter")
    d0: float = Field(16.0, description="ignored")
    alpha: float = Field(6.9, description="ignored")


class UniformDiameter(SizeDistribution):
    """Diameters uniform on [d_min, d_max]."""

    def __init__(self, cfg: SizeConfig) -> None:
        self.lo, self.hi = cfg.d_min, cfg.d_max

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return 0.5 * rng.uniform(self.lo, self.hi, size=n)

    @property
    def mean_area(self) -> float:
        a, b = self.lo, self.hi
        return math.pi / 4 * (a * a + a * b + b * b) / 3

    @property
    def r_min(self) -> float:
        return self.lo / 2

    @property
    def r_max(self) -> float:
        return self.hi / 2


class ShapeConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")
    psi: float = Field(1.0, gt=0, allow_inf_nan=False, description="ignored roundness")
    a: float = Field(1 / 3, gt=0, le=1, description="ignored amplitude")
    m: int = Field(8, ge=3, description="number of edges")


class RegularPolygon(ShapeGenerator):
    """Regular m-gons of area pi r^2 with a random orientation."""

    def __init__(self, cfg: ShapeConfig) -> None:
        self.m = cfg.m

    def generate(self, radius: np.ndarray, rng: np.random.Generator) -> ShapeBatch:
        n, m = len(radius), self.m
        theta0 = rng.uniform(0, 2 * np.pi / m, size=n)
        # circumradius R of a regular m-gon of area pi r^2
        big_r = radius * np.sqrt(2 * np.pi / (m * np.sin(2 * np.pi / m)))
        ang = theta0[:, None] + 2 * np.pi * np.arange(m)[None, :] / m
        v = np.stack([big_r[:, None] * np.cos(ang), big_r[:, None] * np.sin(ang)], axis=-1)
        offsets = np.arange(0, m * n + 1, m, dtype=np.int64)
        return ShapeBatch(v.reshape(-1, 2), offsets, theta0)


class GridConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")
    t: float = Field(0.999, description="ignored")
    interference: Literal["exact", "tau"] = Field("exact", description="ignored")
    tau: float = Field(0.65, description="ignored")
    first: Literal["center", "random"] = Field("center", description="ignored")
    search: Literal["indexed", "scan"] = Field("indexed", description="ignored")
    fail_after: int | None = Field(None, description="raise KeyboardInterrupt after this many")


class GridInserter(InsertionStrategy):
    """Places particles on a square grid of cells wide enough for the largest one."""

    def __init__(self, cfg: GridConfig) -> None:
        self.fail_after = cfg.fail_after

    def pack(
        self,
        population: Population,
        domain: Rectangle,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        n = len(population)
        cell = 2 * float(population.circumradius.max()) if n else 1.0
        nx, ny = int(domain.width // cell), int(domain.height // cell)
        centre = np.full((n, 2), np.nan)
        index = np.full(n, -1, dtype=np.int64)
        placed = 0
        for i in range(n):
            if self.fail_after is not None and i >= self.fail_after:
                raise KeyboardInterrupt
            if placed < nx * ny:
                cx, cy = divmod(placed, ny)
                centre[i] = (domain.xmin + (cx + 0.5) * cell, domain.ymin + (cy + 0.5) * cell)
                index[i] = placed
                placed += 1
            if progress is not None and (i % 50 == 0 or i == n - 1):
                progress(i + 1, placed, n)
        return InsertionResult(centre, index, {"cells": float(nx * ny)})


class EtaConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")
    eta: float = Field(0.0, ge=0, description="ignored")


class Identity(DensityController):
    identity = True

    def __init__(self, cfg: EtaConfig) -> None:
        self.eta = cfg.eta

    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        return arcs


class FakePlugin:
    """Provides change5, octagon, available-arc and eta fakes."""

    @hookimpl
    def regopack_size_distributions(self):  # type: ignore[no-untyped-def]
        return [SizeDistributionSpec("change5", SizeConfig, UniformDiameter, "fake sizes")]

    @hookimpl
    def regopack_shapes(self):  # type: ignore[no-untyped-def]
        return [ShapeSpec("octagon", ShapeConfig, RegularPolygon, "fake shapes")]

    @hookimpl
    def regopack_inserters(self):  # type: ignore[no-untyped-def]
        return [InserterSpec("available-arc", GridConfig, GridInserter, "fake grid")]

    @hookimpl
    def regopack_density_controllers(self):  # type: ignore[no-untyped-def]
        return [DensityControllerSpec("eta", EtaConfig, Identity, "fake eta")]


def fake_registry(*more: object):  # type: ignore[no-untyped-def]
    return make_registry(FakePlugin(), *more, builtins=())


class PythonDensity:
    """A density controller written in Python (``half``), for the refusals before drawing."""

    @hookimpl
    def regopack_density_controllers(self):  # type: ignore[no-untyped-def]
        from pydantic import BaseModel

        from regopack.registry.interfaces import DensityController
        from regopack.registry.plugin_types import DensityControllerSpec

        class Config(BaseModel):
            pass

        class Half(DensityController):
            def __init__(self, cfg: Config) -> None:
                pass

            def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
                return arcs

        return [DensityControllerSpec("half", Config, Half, "a Python controller")]
