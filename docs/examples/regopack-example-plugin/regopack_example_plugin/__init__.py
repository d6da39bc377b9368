"""Example regopack plugin: elliptical particles and an aspect-ratio analyzer.

Two plugins in one module, registered through the entry-point group
``regopack`` (see ``pyproject.toml``):

``ellipse-polygon`` (shape)
    Convex polygons with ``m`` vertices on an ellipse of aspect ratio
    ``aspect``, turned by a random angle, of area pi r^2, with the reference
    point at the centre.
``aspect`` (analyzer)
    Aspect ratio of every placed particle, from the principal second moments
    of area of its outline (the equivalent ellipse), with its mean and a
    histogram.

Examples
--------
>>> import numpy as np
>>> gen = EllipsePolygon(EllipseConfig(aspect=3.0, m=12))
>>> batch = gen.generate(np.array([1.0, 2.0]), np.random.default_rng(0))
>>> batch.offsets.tolist()
[0, 12, 24]
>>> area, aspect, _ = second_moment_aspect(batch.vertices, batch.offsets)
>>> np.round(area / np.pi, 9).tolist(), np.round(aspect, 9).tolist()
([1.0, 4.0], [3.0, 3.0])
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.geometry.population import ShapeBatch
from regopack.packing.core import Packing
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Analyzer, ShapeGenerator
from regopack.registry.plugin_types import AnalyzerSpec, ShapeSpec

__all__ = [
    "AspectConfig",
    "AspectRatio",
    "EllipseConfig",
    "EllipsePolygon",
    "regopack_analyzers",
    "regopack_shapes",
    "second_moment_aspect",
]

__version__ = "0.1.0"

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ---------------------------------------------------------------------------
# shape: ellipse-polygon


class EllipseConfig(BaseModel):
    """Parameters of the ellipse-polygon shape generator."""

    model_config = ConfigDict(extra="forbid")

    aspect: float = Field(
        2.0,
        ge=1,
        le=20,
        allow_inf_nan=False,
        description="Aspect ratio of the ellipse, long axis over short axis (1 to 20).",
    )
    aspect_max: float | None = Field(
        None,
        ge=1,
        le=20,
        allow_inf_nan=False,
        description=(
            "When set, each particle's aspect ratio is drawn uniformly between aspect "
            "and aspect_max."
        ),
    )
    m: int = Field(16, ge=4, le=256, description="Number of vertices (4 to 256).")

    @model_validator(mode="after")
    def _check_range(self) -> Self:
        if self.aspect_max is not None and self.aspect_max < self.aspect:
            raise ValueError(
                f"aspect_max ({self.aspect_max}) must not be less than aspect ({self.aspect})"
            )
        return self


class EllipsePolygon(ShapeGenerator):
    """Convex m-gons inscribed in an ellipse, of area pi r^2, randomly turned.

    The vertices are ``(a cos t_k, b sin t_k)`` with ``t_k = 2 pi k / m``, an
    affine image of the regular m-gon, scaled so that the polygon's area
    ``(m / 2) a b sin(2 pi / m)`` is ``pi r^2`` and ``a / b`` is the aspect
    ratio. Draws ``n`` orientations, then (only when ``aspect_max`` is set)
    ``n`` aspect ratios.

    Parameters
    ----------
    config
        Validated parameters.
    """

    def __init__(self, config: EllipseConfig) -> None:
        self.config = config

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Return one outline per radius, counter-clockwise, centred on the reference point."""
        r = np.asarray(radius, dtype=np.float64)
        n, m = r.shape[0], self.config.m
        theta = rng.uniform(0.0, 2.0 * np.pi, n)
        if self.config.aspect_max is None:
            aspect = np.full(n, self.config.aspect)
        else:
            aspect = rng.uniform(self.config.aspect, self.config.aspect_max, n)
        ab = 2.0 * np.pi * r**2 / (m * np.sin(2.0 * np.pi / m))
        a, b = np.sqrt(ab * aspect), np.sqrt(ab / aspect)
        t = 2.0 * np.pi * np.arange(m) / m
        x = a[:, None] * np.cos(t)
        y = b[:, None] * np.sin(t)
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        vertices = np.stack([(x * c - y * s).ravel(), (x * s + y * c).ravel()], axis=1)
        offsets = np.arange(0, m * n + 1, m, dtype=np.int64)
        return ShapeBatch(vertices=vertices, offsets=offsets, orientation=theta)


# ---------------------------------------------------------------------------
# analyzer: aspect


def second_moment_aspect(
    vertices: FloatArray, offsets: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Area, aspect ratio and major-axis angle of polygons from their second moments.

    The aspect ratio is ``sqrt(l1 / l2)`` for the principal second moments of
    area ``l1 >= l2`` about the centroid: that of the ellipse with the same
    second moments. It is exactly ``a / b`` for the polygons of
    :class:`EllipsePolygon` and 1 for any regular polygon.

    Parameters
    ----------
    vertices
        ``(M, 2)`` counter-clockwise vertices of all polygons, one after another.
    offsets
        ``(n + 1,)`` polygon ``j`` is ``vertices[offsets[j]:offsets[j + 1]]``
        (at least three vertices each).

    Returns
    -------
    area, aspect, angle
        ``(n,)`` arrays; ``angle`` is the direction of the major axis in
        ``(-pi/2, pi/2]`` radians.
    """
    v = np.asarray(vertices, dtype=np.float64)
    starts = np.asarray(offsets[:-1], dtype=np.int64)
    nxt = np.arange(1, v.shape[0] + 1)
    nxt[np.asarray(offsets[1:], dtype=np.int64) - 1] = starts
    x0, y0 = v[:, 0], v[:, 1]
    x1, y1 = v[nxt, 0], v[nxt, 1]
    cross = x0 * y1 - x1 * y0

    def total(values: FloatArray) -> FloatArray:
        out: FloatArray = np.add.reduceat(values, starts)
        return out

    area = 0.5 * total(cross)
    cx = total((x0 + x1) * cross) / (6.0 * area)
    cy = total((y0 + y1) * cross) / (6.0 * area)
    ixx = total((x0 * x0 + x0 * x1 + x1 * x1) * cross) / 12.0 - area * cx * cx
    iyy = total((y0 * y0 + y0 * y1 + y1 * y1) * cross) / 12.0 - area * cy * cy
    ixy = total((x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cross) / 24.0 - area * cx * cy
    half_sum = 0.5 * (ixx + iyy)
    root = np.hypot(0.5 * (ixx - iyy), ixy)
    major, minor = half_sum + root, np.maximum(half_sum - root, 0.0)
    with np.errstate(divide="ignore"):
        aspect = np.sqrt(major / minor)
    angle = 0.5 * np.arctan2(2.0 * ixy, ixx - iyy)
    return area, aspect, angle


class AspectConfig(BaseModel):
    """Parameters of the aspect analyzer."""

    model_config = ConfigDict(extra="forbid")

    bins: int = Field(
        20, ge=1, le=1000, description="Number of bins of the aspect-ratio histogram."
    )
    upper: float | None = Field(
        None,
        gt=1,
        allow_inf_nan=False,
        description=(
            "Upper end of the histogram (its lower end is 1); default: the largest aspect "
            "ratio found."
        ),
    )


class AspectRatio(Analyzer):
    """Aspect ratio of the placed particles: mean, spread, per mineral and histogram.

    Parameters
    ----------
    config
        Validated parameters (default: :class:`AspectConfig` defaults).
    """

    name = "aspect"

    def __init__(self, config: AspectConfig | None = None) -> None:
        self.config = config or AspectConfig()
        self._aspect: FloatArray | None = None
        self._angle: FloatArray | None = None
        self._index: IntArray | None = None
        self._mineral: IntArray | None = None
        self._mineral_names: tuple[str, ...] = ()

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Measure every placed particle's outline."""
        _, aspect, angle = second_moment_aspect(packing.vertices, packing.offsets)
        placed = np.flatnonzero(packing.placed).astype(np.int64)
        self._index = placed
        self._aspect = aspect[placed]
        self._angle = angle[placed]
        self._mineral = packing.mineral[placed].astype(np.int64)
        self._mineral_names = tuple(packing.mineral_names)
        return self

    @property
    def aspect(self) -> FloatArray:
        """``(n_placed,)`` aspect ratio of every placed particle, in particle order."""
        if self._aspect is None:
            raise RuntimeError("call compute() first")
        return self._aspect

    @property
    def mean(self) -> float:
        """Mean aspect ratio of the placed particles (NaN when none is placed)."""
        return float(np.mean(self.aspect)) if self.aspect.size else float("nan")

    def histogram(self) -> tuple[FloatArray, IntArray]:
        """Bin edges ``(bins + 1,)`` and counts ``(bins,)`` of the aspect ratios."""
        values = self.aspect
        top = self.config.upper
        if top is None:
            top = float(values.max()) if values.size else 2.0
            top = max(top, 1.0 + 1e-9)
        counts, edges = np.histogram(values, bins=self.config.bins, range=(1.0, top))
        return edges, counts.astype(np.int64)

    def results(self) -> dict[str, Any]:
        """Scalars: count, mean, median, std, min, max and the mean of each mineral."""
        values = self.aspect
        assert self._mineral is not None
        out: dict[str, Any] = {"n": int(values.size)}
        if values.size == 0:
            return out
        out |= {
            "mean": float(values.mean()),
            "median": float(np.median(values)),
            "std": float(values.std()),
            "min": float(values.min()),
            "max": float(values.max()),
        }
        for k, mineral in enumerate(self._mineral_names):
            mine = values[self._mineral == k]
            if mine.size:
                out[f"mean_{mineral}"] = float(mine.mean())
        return out

    def tables(self) -> dict[str, dict[str, Any]]:
        """``aspect`` (one row per placed particle) and ``aspect_histogram``."""
        values = self.aspect
        assert self._index is not None and self._angle is not None
        edges, counts = self.histogram()
        return {
            "aspect": {
                "particle": self._index,
                "mineral": self._mineral,
                "aspect": values,
                "major_axis_angle": self._angle,
            },
            "aspect_histogram": {"lower": edges[:-1], "upper": edges[1:], "count": counts},
        }


# ---------------------------------------------------------------------------
# hooks


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``ellipse-polygon`` shape generator."""
    return [
        ShapeSpec(
            name="ellipse-polygon",
            config_model=EllipseConfig,
            factory=EllipsePolygon,
            description="Convex m-gon inscribed in an ellipse of a given aspect ratio.",
        )
    ]


@hookimpl
def regopack_analyzers() -> Iterable[AnalyzerSpec]:
    """Register the ``aspect`` analyzer."""
    return [
        AnalyzerSpec(
            name="aspect",
            config_model=AspectConfig,
            factory=AspectRatio,
            description="Aspect ratio of the placed particles from their second moments of area.",
        )
    ]
