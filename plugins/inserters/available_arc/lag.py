"""The lag of each particle size in the sweep order, learned from a pilot sweep.

In the sweep's steady state the small particles do not land where the stream
is: they fill the last pores of the oldest candidates, near the bottom of the
zone, a size-dependent depth below its top (the smallest about 0.85 of the
zone height for the Table-1 materials, the coarse ones at the top). At the
start there are no such old candidates yet, so every small particle of the
first zone height fills the young pores next to the floor, which ends up
with too many of them. Offering each particle only after the front has risen
by its size's depth gives the first zone what the steady state gives every
other, and the particles held back fill the last zone's old pores under the
top.

The depths are a property of the materials and the zone, not known before a
packing, so a *pilot* measures them: the first particles of the stream are
swept into a small walled box at the bottom of the domain (three zone heights
high; in 2D a rectangle two zone heights wide, in 3D a square floor one zone
height a side), and the depth of every particle placed once the pilot's zone
top is two zone heights up is averaged per √2 size class. The same pilot
serves both dimensions (:func:`pilot_lags`): only the sweep that runs it
differs. In 3D the floor is narrower than in 2D because a square of two zone
heights would make the pilot four times as costly (twelve zone volumes),
while one zone height a side already gives the fine classes of the Chang'e-5
sizes thousands of placements to average. A size distribution with few fine
particles gives the pilot few of them: the classes finer than every class it
measured well take that class's lag (:func:`class_lags`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.population import Population, ShapeBatch
from regopack.geometry.solids import sphere_volume

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

PILOT_WIDTH = {2: 2.0, 3: 1.0}
"""Sides of the pilot's floor, in zone heights, by dimension (at most the domain's)."""
PILOT_HEIGHT = 3.0
"""Height of the pilot's box, in zone heights."""
MEASURE_FROM = 2.0
"""Placements count once the pilot's zone top is this many zone heights up: its
zone has then left the pilot's own first zone height, which has no lags."""
MIN_HEIGHT = 2.5
"""Domains lower than this many zone heights get no lags (no steady state to learn from)."""
PILOT_FILL = 1.0
"""Particle area (volume in 3D) given to the pilot, over its box's (2D: it fills about 0.87)."""
MIN_LAG = 0.1
"""Mean depths under this many zone heights are no lag (about the depth at which the
coarse particles that make the front land)."""
MIN_SAMPLES = 20
"""Placements a size class needs in the pilot to get a lag of its own (fewer: no lag, or
the lag of the finest class with enough when it is finer than all of them)."""


def head(population: Population, m: int) -> Population:
    """Return the first ``m`` particles of ``population``."""
    sh = population.shapes
    off = sh.offsets[: m + 1]
    shapes = ShapeBatch(
        vertices=sh.vertices[: int(off[-1])],
        offsets=off,
        orientation=sh.orientation[:m],
        rounding=None if sh.rounding is None else sh.rounding[:m],
    )
    return Population(
        radius=population.radius[:m],
        mineral=population.mineral[:m],
        mineral_names=population.mineral_names,
        shapes=shapes,
    )


def size_class(radius: FloatArray, r_min: float) -> IntArray:
    """√2 size class of each equivalent radius, 0 for ``[r_min, √2 r_min)``."""
    return np.floor(2.0 * np.log2(np.maximum(radius / r_min, 1.0))).astype(np.int64)


def class_lags(
    radius: FloatArray,
    depth: FloatArray,
    r_min: float,
    min_lag: float,
    min_samples: int = MIN_SAMPLES,
) -> tuple[FloatArray, IntArray]:
    """Lag (length) of each size class: its mean depth below the zone top when placed.

    Parameters
    ----------
    radius
        Equivalent radius of each measured placement.
    depth
        Its depth below its zone's top when it was placed (negative above it).
    r_min
        Radius of the lower end of class 0.
    min_lag
        Shallower means are no lag: the particles that make the front land
        about their own size below the top.
    min_samples
        Classes with fewer placements get no lag, but for those finer than
        every class with enough placements, which take the finest such class's
        lag (a size distribution with few fine particles gives the pilot few of
        them to measure).

    Returns
    -------
    lag, samples
        Per class: the lag (0 where undersampled or shallow) and the number of placements.
    """
    cls = size_class(radius, r_min)
    ncls = int(cls.max()) + 1 if cls.size else 0
    samples = np.bincount(cls, minlength=ncls).astype(np.int64)
    total = np.bincount(cls, weights=depth, minlength=ncls)
    lag = np.zeros(ncls, dtype=np.float64)
    ok = samples >= min_samples
    lag[ok] = total[ok] / samples[ok]
    lag[lag < min_lag] = 0.0
    if ok.any():
        # the classes finer than every measured one land at least as deep as the
        # finest measured class: they take its lag rather than none
        first = int(np.argmax(ok))
        lag[:first] = lag[first]
    return lag, samples


def pilot_lags(
    radius: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    zone: float,
    delta: float,
    run_pilot: Callable[[int, FloatArray, FloatArray], tuple[FloatArray, IntArray, float]],
) -> tuple[IntArray, dict[str, Any]]:
    """Lag of every particle, in bins of height ``delta``, learned from a pilot sweep.

    Parameters
    ----------
    radius
        Equivalent radius of the particles of the run, in stream order.
    lo, hi
        Lower and upper corners of the run's domain box (2 or 3 coordinates,
        the last one the height); the pilot is a walled box on its floor, at
        its lower corner.
    zone
        The run's zone height.
    delta
        The run's bin height.
    run_pilot
        ``run_pilot(m, lo, hi)`` sweeps the stream's first ``m`` particles into
        the walled box ``lo``, ``hi`` with the run's settings and zone; returns
        the placed centres' heights above the box's floor (NaN where not
        placed), each particle's zone top (bin, -1 where not measured, see
        ``Lags.top_at``) and the pilot's bin height.

    Returns
    -------
    lag, info
        ``(n,)`` lags in bins, and what the pilot measured (for the summary).
    """
    n = radius.shape[0]
    dim = lo.shape[0]
    lag = np.zeros(n, dtype=np.int64)
    height = float(hi[-1] - lo[-1])
    info: dict[str, Any] = {
        "lag_pilot_particles": 0,
        "lag_samples": 0,
        "lagged": 0,
        "lag_max": 0.0,
    }
    if n == 0 or not zone > 0 or height < MIN_HEIGHT * zone:
        return lag, info
    side = PILOT_WIDTH[dim] * zone
    extent = [min(float(hi[a] - lo[a]), side) for a in range(dim - 1)]
    extent.append(min(height, PILOT_HEIGHT * zone))
    # enough of the stream's first particles to fill the pilot, whatever the run's count
    cell = math.prod(extent)
    if dim == 2:
        mean = math.pi * float(np.mean(radius**2))
    else:
        mean = float(np.mean(sphere_volume(radius)))
    m = min(n, math.ceil(PILOT_FILL * cell / mean))
    plo = np.array(lo, dtype=np.float64)
    phi = plo + np.array(extent)
    y, top_at, pdelta = run_pilot(m, plo, phi)
    measured = (top_at >= 0) & ((top_at + 1.0) * pdelta >= MEASURE_FROM * zone)
    depth = (top_at[measured] + 1.0) * pdelta - y[measured]
    r_min = float(radius.min())
    lags, _ = class_lags(radius[:m][measured], depth, r_min, MIN_LAG * zone)
    cls = size_class(radius, r_min)
    known = cls < lags.shape[0]
    lag[known] = np.rint(lags[cls[known]] / delta).astype(np.int64)
    info["lag_pilot_particles"] = m
    info["lag_samples"] = int(measured.sum())
    info["lagged"] = int(np.count_nonzero(lag))
    info["lag_max"] = float(lags.max()) if lags.size else 0.0
    return lag, info


def pilot_generator(rng: np.random.Generator) -> np.random.Generator:
    """Return an independent generator spawned from ``rng``, which keeps its own stream.

    The pilot draws from it, so that the run's own stream is the same with
    and without lags.
    """
    try:
        return rng.spawn(1)[0]
    except (TypeError, ValueError):  # a generator without a seed sequence
        # seeded from a copy of ``rng``, whose own stream stays untouched
        twin = type(rng.bit_generator)()
        twin.state = rng.bit_generator.state
        return np.random.default_rng(np.random.Generator(twin).integers(2**63))
