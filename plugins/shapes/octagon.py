"""Random convex polygons with a shape coefficient psi (the paper's octagons).

Each particle has ``m`` edge normals at ``theta0 + 2 pi k / m`` with raw
support distances ``s_k = 1 + a sigma_k |2 xi_k - 1|^psi`` (SPEC §2). The
outline is the intersection of the half-planes ``n_k . x <= s_k``; every
``s_k`` is then replaced by the outline's true support value so that the
particle keeps exactly ``m`` edge directions (some of zero length), and the
outline is scaled to the area ``pi r^2``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numba
import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.geometry.population import ShapeBatch
from regopack.plugins.common.halfplane_clip import clip_halfplane
from regopack.plugins.shapes.coefficients import Amplitude, ShapeCoefficient
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import ShapeGenerator
from regopack.registry.plugin_types import ShapeSpec

FloatArray = NDArray[np.float64]
SNAP = 1e-10
"""Vertices closer than this fraction of the largest support value are merged."""


class OctagonConfig(BaseModel):
    """Parameters of the random convex polygon with shape coefficient psi."""

    model_config = ConfigDict(extra="forbid", strict=True)

    psi: ShapeCoefficient = Field(
        1.0,
        description=(
            "Shape coefficient psi (> 0): larger is rounder, psi -> inf gives the regular m-gon."
        ),
    )
    a: Amplitude = Field(
        1.0 / 3.0,
        description=(
            "Perturbation amplitude a in (0, 1]: support distances lie within ±a of their mean."
        ),
    )
    m: int = Field(
        8, ge=3, le=256, description="Number of edge directions m (3 to 256; the paper uses 8)."
    )


@numba.njit(cache=True)
def _true_support(s: FloatArray, nx: FloatArray, ny: FloatArray) -> FloatArray:
    """Support values of the polygon ``{x : n_k . x <= s_k}`` along every ``n_k``.

    Clips a bounding polygon by each half-plane (Sutherland-Hodgman) and takes
    the maximum of ``n_k . v`` over the resulting vertices.
    """
    n, m = s.shape
    h = np.empty((n, m))
    cap = 2 * m + 8
    px = np.empty(cap)
    py = np.empty(cap)
    qx = np.empty(cap)
    qy = np.empty(cap)
    for p in range(n):
        smax = 0.0
        for k in range(m):
            if s[p, k] > smax:
                smax = s[p, k]
        big = 4.0 * smax / math.cos(math.pi / m) + 1.0
        cnt = 4
        px[0] = -big
        py[0] = -big
        px[1] = big
        py[1] = -big
        px[2] = big
        py[2] = big
        px[3] = -big
        py[3] = big
        for k in range(m):
            cnt = clip_halfplane(px, py, cnt, nx[k], ny[k], s[p, k], qx, qy)
            for j in range(cnt):
                px[j] = qx[j]
                py[j] = qy[j]
        for k in range(m):
            best = -np.inf
            for j in range(cnt):
                v = nx[k] * px[j] + ny[k] * py[j]
                if v > best:
                    best = v
            h[p, k] = min(best, s[p, k])
    return h


def polygon_from_support(h: FloatArray, m: int) -> tuple[FloatArray, FloatArray]:
    """Vertices of the polygon with unit normals at ``2 pi k / m`` and support values ``h``.

    Vertex ``k`` is the start of edge ``k`` (the edge with normal ``k``), i.e. the
    intersection of the supporting lines ``k - 1`` and ``k``.

    Returns
    -------
    x, y
        ``(n, m)`` vertex coordinates, counter-clockwise.
    """
    phi = 2.0 * np.pi * np.arange(m) / m
    c, s = np.cos(phi), np.sin(phi)
    cp, sp = np.roll(c, 1), np.roll(s, 1)
    hp = np.roll(h, 1, axis=1)
    det = math.sin(2.0 * math.pi / m)
    x = (hp * s - h * sp) / det
    y = (cp * h - c * hp) / det
    # the two ends of a zero-length edge come from different line pairs and differ
    # by rounding; make them identical so that outlines stay simple polygons
    tol = SNAP * np.max(h, axis=1) if h.shape[0] else np.zeros(0)
    for k in range(1, 2 * m):
        cur, prev = k % m, (k - 1) % m
        close = np.hypot(x[:, cur] - x[:, prev], y[:, cur] - y[:, prev]) <= tol
        x[close, cur] = x[close, prev]
        y[close, cur] = y[close, prev]
    return x, y


class RandomPolygon(ShapeGenerator):
    """Random convex m-gon with shape coefficient psi (default: the paper's octagon).

    Examples
    --------
    >>> import numpy as np
    >>> gen = RandomPolygon(OctagonConfig(psi=0.5))
    >>> batch = gen.generate(np.array([1.0, 2.0]), np.random.default_rng(0))
    >>> batch.vertices.shape
    (16, 2)
    """

    def __init__(self, config: OctagonConfig) -> None:
        self.config = config

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Draw one outline per radius (random draws: orientation, signs, xi)."""
        cfg = self.config
        m = cfg.m
        n = int(radius.shape[0])
        theta0 = rng.random(n) * (2.0 * np.pi / m)
        sign = 2.0 * rng.integers(0, 2, size=(n, m)) - 1.0
        xi = rng.random((n, m))
        s = 1.0 + cfg.a * sign * np.abs(2.0 * xi - 1.0) ** cfg.psi
        # guard the a = 1 limit: a zero support would put the centre on the outline
        np.maximum(s, 1e-9, out=s)
        phi = 2.0 * np.pi * np.arange(m) / m
        h = _true_support(s, np.cos(phi), np.sin(phi)) if n else np.empty((0, m))
        x, y = polygon_from_support(h, m)
        area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
        scale = np.sqrt(np.pi * radius**2 / area)
        ct, st = np.cos(theta0), np.sin(theta0)
        xs = x * scale[:, None]
        ys = y * scale[:, None]
        vx = xs * ct[:, None] - ys * st[:, None]
        vy = xs * st[:, None] + ys * ct[:, None]
        vertices = np.stack([vx.ravel(), vy.ravel()], axis=1)
        offsets = np.arange(0, n * m + 1, m, dtype=np.int64)
        return ShapeBatch(vertices=vertices, offsets=offsets, orientation=theta0)


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``octagon`` shape."""
    return [
        ShapeSpec(
            name="octagon",
            config_model=OctagonConfig,
            factory=RandomPolygon,
            description="Random convex m-gon (m = 8 by default) with shape coefficient psi.",
        )
    ]
